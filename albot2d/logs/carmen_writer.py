"""CARMEN log writer: one line per record, at a chosen float precision, atomically.

:func:`format_record` is the inverse of :class:`~albot2d.logs.carmen.CarmenReader`'s parsing:
the reader gives back the same record (exactly with :data:`EXACT`; to the written decimals with
:data:`LOG_PRECISION`, the precision of real logs).
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from albot2d.geometry import Pose
from albot2d.logs.carmen import (
    CommentRecord,
    LaserRecord,
    NeffRecord,
    OdomRecord,
    ParamRecord,
    Record,
)
from albot2d.logs.textio import atomic_text_output

__all__ = [
    "EXACT",
    "LOG_PRECISION",
    "FloatFormat",
    "format_float",
    "format_record",
    "write_records",
]


@dataclass(frozen=True)
class FloatFormat:
    """Decimals written per kind of number; ``None`` writes ``repr`` (exact round trip).

    The default (:data:`LOG_PRECISION`) is what real logs use: ranges to 1 mm, poses to 1e-6 m
    or rad, timestamps to 1 µs. :data:`EXACT` reproduces every float bit for bit.
    """

    range_decimals: int | None = 3
    pose_decimals: int | None = 6
    timestamp_decimals: int | None = 6


LOG_PRECISION = FloatFormat()
EXACT = FloatFormat(None, None, None)


def format_float(value: float, decimals: int | None) -> str:
    """``value`` to ``decimals`` places; its shortest exact ``repr`` when ``decimals`` is None."""
    value = float(value)
    if decimals is None:
        return repr(value)
    return f"{value:.{decimals}f}"


def _join(values: Iterable[float], decimals: int | None) -> str:
    if decimals is None:
        return " ".join(map(repr, values))
    spec = f".{decimals}f"
    return " ".join(format(v, spec) for v in values)


def _pose_text(pose: Pose, fmt: FloatFormat) -> str:
    return _join((pose.x, pose.y, pose.theta), fmt.pose_decimals)


def _stamps(ipc: float, host: str, logger: float, fmt: FloatFormat) -> str:
    d = fmt.timestamp_decimals
    return f"{format_float(ipc, d)} {host} {format_float(logger, d)}"


def format_record(record: Record, fmt: FloatFormat = LOG_PRECISION) -> str:
    """One CARMEN line (no newline) for ``record``; :class:`CarmenReader` parses it back."""
    if isinstance(record, LaserRecord):
        return _format_laser(record, fmt)
    if isinstance(record, OdomRecord):
        motion = _join((record.tv_mps, record.rv_radps, record.accel_mps2), fmt.pose_decimals)
        stamps = _stamps(record.ipc_timestamp, record.hostname, record.logger_timestamp, fmt)
        return f"ODOM {_pose_text(record.pose, fmt)} {motion} {stamps}"
    if isinstance(record, ParamRecord):
        if record.ipc_timestamp is None or record.logger_timestamp is None:
            return f"PARAM {record.name} {record.value}"
        host = record.hostname or "nohost"
        return f"PARAM {record.name} {record.value} " + _stamps(
            record.ipc_timestamp, host, record.logger_timestamp, fmt
        )
    if isinstance(record, NeffRecord):
        return f"NEFF {record.value!r}"
    if isinstance(record, CommentRecord):
        return f"# {record.text}"
    raise TypeError(f"not a CARMEN record: {record!r}")


def _format_laser(record: LaserRecord, fmt: FloatFormat) -> str:
    ranges = _join(record.ranges.tolist(), fmt.range_decimals)
    stamps = _stamps(record.ipc_timestamp, record.hostname, record.logger_timestamp, fmt)
    poses = f"{_pose_text(record.pose, fmt)} {_pose_text(record.odom_pose, fmt)}"
    if record.message != "ROBOTLASER1":
        return f"{record.message} {record.n_beams} {ranges} {poses} {stamps}"
    remissions = record.remissions if record.remissions is not None else np.empty(0)

    def num(value: float | None) -> str:
        return repr(float(value or 0.0))

    head = " ".join(
        [str(record.laser_type or 0), num(record.start_angle_rad), num(record.fov_rad),
         num(record.angular_resolution_rad), num(record.max_range_m), num(record.accuracy_m),
         str(record.remission_mode or 0)]
    )  # fmt: skip
    rems = _join(remissions.tolist(), None)
    motion = " ".join(
        num(v) for v in (record.tv_mps, record.rv_radps, record.forward_safety_dist_m,
                         record.side_safety_dist_m, record.turn_axis)
    )  # fmt: skip
    parts = [
        "ROBOTLASER1", head, str(record.n_beams), ranges, str(len(remissions)), rems,
        poses, motion, stamps,
    ]  # fmt: skip
    return " ".join(part for part in parts if part)


def write_records(
    path: str | os.PathLike[str], records: Iterable[Record], fmt: FloatFormat = LOG_PRECISION
) -> int:
    """Write ``records`` as a CARMEN log, atomically (gzip if ``path`` ends in .gz).

    Streams: records are formatted one at a time. Returns the number of records written.
    """
    count = 0
    with atomic_text_output(path) as out:
        for record in records:
            out.write(format_record(record, fmt))
            out.write("\n")
            count += 1
    return count
