"""``albot2d replay``: the mappers on a recorded log or bag, scored against its relations.

Reads ``LOG.clf`` or ``LOG.clf.gz`` (FLASER or ROBOTLASER1 lines; see the shared data's
SOURCES.md) or a ROS 1 bag (``.bag``) or ROS 2 bag (a directory, ``.mcap`` or ``.db3``):
its LaserScan topic (--scan-topic, default /scan) with odometry from --odom-topic (default
/odom) or else /tf (odom -> base_link); see docs/ros.md. It runs every mapper (default
albot1 and naive; ``truth`` needs ground truth and is refused) and writes
``DIR/report.json`` with each mapper's and raw odometry's relative pose error (overall,
short < 2 s, long ≥ 2 s), process counts, timings and homing estimates (true values
null), plus the map figures. The relations file is ``--relations``
or, if not given, ``LOG.relations`` beside the log or ``../relations/LOG.relations``.
A malformed log line stops the replay with its file and line; nothing is written then.

Real data: a LOG that is not found as given is looked up in the data folder, --data DIR
or else the environment variable ALBOT2D_DATA, as DIR/LOG or DIR/raw/LOG (with its
relations in DIR/relations/), e.g. ALBOT2D_DATA=~/slam-data albot2d replay
mit-csail.clf.gz --out out-mit/. The MIT CSAIL log and its relations come from the
Freiburg SLAM benchmark (Kümmerle et al. 2009, ais.informatik.uni-freiburg.de/slamevaluation);
any CARMEN log with FLASER or ROBOTLASER1 lines works.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from albot2d.cli.common import (
    add_export_option,
    add_json_option,
    add_mapper_option,
    add_out_option,
    add_scoring_options,
    finish,
    prepare_out_dir,
    print_tables,
    progress_bar,
    scoring_params,
)
from albot2d.cli.options import positive_int
from albot2d.cli.viewer import add_viewer_options, check_viewer_options, open_viewer
from albot2d.errors import InputError

if TYPE_CHECKING:
    from albot2d.cli.options import Subcommands
    from albot2d.evaluation.run.experiment import ExperimentResult
    from albot2d.frames import Frame

__all__ = ["DATA_ENV", "find_log", "register", "run"]

DATA_ENV = "ALBOT2D_DATA"


def find_log(text: str, data: str | None) -> Path:
    """``LOG`` as given, else in the data folder (``data`` or ``$ALBOT2D_DATA``)."""
    log = Path(text).expanduser()
    if log.is_file() or log.is_dir():  # a directory: a ROS 2 bag
        return log
    folder = data if data is not None else os.environ.get(DATA_ENV)
    tried = [str(log)]
    if folder and not log.is_absolute():
        root = Path(folder).expanduser()
        for candidate in (root / log, root / "raw" / log):
            if candidate.is_file() or candidate.is_dir():
                return candidate
            tried.append(str(candidate))
    hint = "" if folder else f" (set {DATA_ENV} or --data to look it up in a data folder)"
    raise InputError(f"{text}: no such log file; tried {', '.join(tried)}{hint}")


def register(subparsers: Subcommands) -> None:
    p = subparsers.add_parser(
        "replay", help="run the mappers on a CARMEN log or ROS bag and score them against its "
        "relations",
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter,
    )  # fmt: skip
    p.add_argument(
        "log",
        metavar="LOG",
        help="a CARMEN log (.clf, plain or gzip) or a ROS bag (.bag, .mcap, .db3 or a ROS 2 "
        "bag directory), as a path or in the data folder",
    )
    p.add_argument(
        "--scan-topic",
        metavar="TOPIC",
        help="a bag's sensor_msgs/LaserScan topic (default /scan)",
    )
    p.add_argument(
        "--odom-topic",
        metavar="TOPIC",
        help="a bag's nav_msgs/Odometry topic (default /odom; without it, /tf odom->base_link)",
    )
    p.add_argument(
        "--data", metavar="DIR", help=f"data folder where LOG is looked up (default: ${DATA_ENV})"
    )
    p.add_argument(
        "--relations",
        metavar="FILE",
        help="Kümmerle relations file (default: found beside the log)",
    )
    add_mapper_option(
        p,
        "albot1, naive, slam and scan_odometry ([slam] extra)",
        "default: albot1 naive; truth needs a simulated run",
    )
    p.add_argument("--max-frames", metavar="N", help="use only the first N laser scans")
    add_scoring_options(p)
    add_out_option(p, no_figures="write report.json only")
    p.add_argument(
        "--strict",
        action="store_true",
        help="refuse a log with anomalies (bad ranges, timestamps out of order)",
    )
    add_export_option(p, ("occupancy", "g2o"))
    add_viewer_options(p)
    add_json_option(p)
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    from albot2d.evaluation import DEFAULT_REPLAY_MAPPERS, find_relations, replay_log
    from albot2d.evaluation.run.replay import check_replay_mappers
    from albot2d.logs.relations import read_relations
    from albot2d.mapping.registry import resolve_mappers

    log = find_log(args.log, args.data)
    mappers = tuple(args.mapper or DEFAULT_REPLAY_MAPPERS)
    check_replay_mappers(mappers)
    resolve_mappers(list(mappers))
    max_frames = positive_int(args.max_frames, "--max-frames")
    params = scoring_params(args)
    relations = Path(args.relations) if args.relations is not None else find_relations(log)
    if relations is not None:
        read_relations(relations)  # a bad relations file fails before anything is created
    from albot2d.cli.exporters import ExportSource, export_options, write_exports

    options = export_options(args)
    names = list(args.export or [])
    check_viewer_options(args)
    out, created = prepare_out_dir(args.out)
    viewer = open_viewer(args, f"albot2d replay {log.name}")
    bar = progress_bar(max_frames, " views", "replay")

    def exports(result: ExperimentResult) -> list[str]:  # --export: a log has no world
        return write_exports(out, names, ExportSource([], None, result, options))

    def frame(f: Frame, travelled: float) -> None:
        if viewer is not None:
            viewer.on_frame(f, travelled)
        bar.set_postfix_str(f"{travelled:.0f} m", refresh=False)
        bar.update(1)

    ok = False
    try:
        result = finish(
            out, created, "replay",
            lambda: replay_log(log, relations_path=relations, mappers=mappers, params=params,
                               max_frames=max_frames, on_frame=frame, on_stage=bar.set_description,
                               strict=args.strict, scan_topic=args.scan_topic,
                               odom_topic=args.odom_topic,
                               on_mappers=None if viewer is None else viewer.on_mappers),
            args.no_figures, bar.set_description,
            extra_exports=exports if names else None,
        )  # fmt: skip
        ok = True
    finally:
        bar.close()
        if viewer is not None:
            viewer.finish(ok)
    anomalies = result.report["log"]["anomalies"]
    if any(anomalies[k] for k in anomalies if not k.startswith("frames_")):
        from albot2d.logs.anomalies import LogAnomalies

        print(
            f"albot2d replay: warning: {log}: {LogAnomalies(**anomalies).summary()} "
            "(--strict refuses such a log)",
            file=sys.stderr,
        )
    print_tables(result, out, args.json)
    used = result.report["run"].get("relations_used")
    if relations is None:
        print(
            f"albot2d replay: note: no relations file for {log} (give --relations), so no RPE",
            file=sys.stderr,
        )
    elif not used:
        print(
            f"albot2d replay: warning: no relation of {relations} matches the log's "
            "timestamps (is it the relations file of this log?)",
            file=sys.stderr,
        )
    return 0
