#!/usr/bin/env python3
"""The MIT CSAIL log as a CARMEN log, a ROS 1 bag and a ROS 2 MCAP bag: replay RPE table.

Converts the log with ``scripts/carmen_to_rosbag.py`` (rosbags' own writer), replays the
three with ``albot2d replay`` (default mappers) against the log's relations and prints the
Markdown table of docs/ros.md; ``--write docs/ros.md`` replaces the table there (between its
``<!-- mit-bag-rpe -->`` markers)::

    python scripts/mit_bag_rpe.py ../shared/data --write docs/ros.md
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import subprocess
import sys
import tempfile
from pathlib import Path

from albot2d.cli import main as albot2d

HERE = Path(__file__).resolve().parent
MARK = "<!-- mit-bag-rpe -->"


def table(data: Path, work: Path) -> str:
    log = data / "raw" / "mit-csail.clf.gz"
    relations = data / "relations" / "mit-csail.relations"
    ros1, ros2 = work / "mit.bag", work / "mit_ros2"
    subprocess.run(
        [sys.executable, str(HERE / "carmen_to_rosbag.py"), str(log),
         "--ros1", str(ros1), "--ros2", str(ros2)],
        check=True, stdout=subprocess.DEVNULL,
    )  # fmt: skip
    rows = [
        "| source | relations | Albot₁ RPE trans / rot | naive RPE trans / rot |",
        "|---|---|---|---|",
    ]
    for label, source in (("`mit-csail.clf.gz`", log), ("`mit.bag` (ROS 1)", ros1),
                          ("`mit_ros2` (ROS 2 MCAP)", ros2)):  # fmt: skip
        out = work / source.name.replace(".", "_")
        argv = ["replay", str(source), "--relations", str(relations), "--out", str(out)]
        if albot2d([*argv, "--no-figures", "--json"]) != 0:
            raise SystemExit(f"replay of {source} failed")
        report = json.loads((out / "report.json").read_text())
        cells = []
        for name in ("albot1", "naive"):
            rpe = report["mappers"][name]["rpe"]
            cells.append(f"{rpe['trans_m_mean']:.6f} m / {rpe['rot_deg_mean']:.6f}°")
        used = report["odometry"]["rpe"]["relations"]
        rows.append(f"| {label} | {used} | {cells[0]} | {cells[1]} |")
    return "\n".join(rows) + "\n"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("data", type=Path, help="the shared data folder (raw/, relations/)")
    p.add_argument("--write", type=Path, metavar="FILE", help="replace the table in FILE")
    args = p.parse_args(argv)
    with tempfile.TemporaryDirectory() as work, contextlib.redirect_stdout(io.StringIO()):
        text = table(args.data, Path(work))
    if args.write is None:
        print(text, end="")
        return 0
    doc = args.write.read_text()
    head, _, rest = doc.partition(MARK + "\n")
    _, _, tail = rest.partition(MARK + "\n")
    if not rest:
        raise SystemExit(f"{args.write}: no {MARK} markers")
    args.write.write_text(f"{head}{MARK}\n{text}{MARK}\n{tail}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
