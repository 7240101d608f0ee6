"""Robot log I/O: CARMEN logs (read and write), Kümmerle relations files, simulated run dirs.

- ``carmen``: record types and the streaming reader (plain/gzip); ``carmen_writer``: the writer;
- ``frames``: CARMEN records ↔ albot2d ``Frame`` streams (``read_frames``, ``write_carmen``);
- ``relations``: relations files and relations from a truth trajectory;
- ``run_files``: a simulated run directory (log, truth, relations, manifest);
- ``rosbag``: ROS 1 / ROS 2 bags → frames (``read_bag``); ``rosbag_writer``: frames → bags.
"""

from albot2d.logs.carmen import (
    CarmenReader,
    CarmenStats,
    CommentRecord,
    LaserRecord,
    NeffRecord,
    OdomRecord,
    ParamRecord,
    Record,
    read_carmen,
)
from albot2d.logs.carmen_writer import (
    EXACT,
    LOG_PRECISION,
    FloatFormat,
    format_record,
    write_records,
)
from albot2d.logs.log_frames import (
    DEFAULT_EVEN_BEAM_CONVENTION,
    DEFAULT_FOV_DEG,
    DEFAULT_NO_RETURN_THRESHOLD_M,
    EvenBeamConvention,
    frames_to_records,
    read_frames,
    records_to_frames,
    write_carmen,
)
from albot2d.logs.relations import (
    Relations,
    RelationsOptions,
    match_timestamps,
    read_relations,
    relations_from_truth,
    write_relations,
)
from albot2d.logs.rosbag import BagFrames, is_bag, read_bag
from albot2d.logs.rosbag_writer import write_bag
from albot2d.logs.run_files import Run, read_run, read_truth, write_run, write_truth

__all__ = [
    "DEFAULT_EVEN_BEAM_CONVENTION",
    "DEFAULT_FOV_DEG",
    "DEFAULT_NO_RETURN_THRESHOLD_M",
    "EXACT",
    "LOG_PRECISION",
    "BagFrames",
    "CarmenReader",
    "CarmenStats",
    "CommentRecord",
    "EvenBeamConvention",
    "FloatFormat",
    "LaserRecord",
    "NeffRecord",
    "OdomRecord",
    "ParamRecord",
    "Record",
    "Relations",
    "RelationsOptions",
    "Run",
    "format_record",
    "frames_to_records",
    "is_bag",
    "match_timestamps",
    "read_bag",
    "read_carmen",
    "read_frames",
    "read_relations",
    "read_run",
    "read_truth",
    "records_to_frames",
    "relations_from_truth",
    "write_bag",
    "write_carmen",
    "write_records",
    "write_relations",
    "write_run",
    "write_truth",
]
