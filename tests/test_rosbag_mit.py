"""The shared MIT CSAIL log as ROS bags: ``scripts/carmen_to_rosbag.py`` (rosbags' own
writer, not albot2d's) converts it to a ROS 1 bag and a ROS 2 MCAP bag, and replaying each
gives the CARMEN replay's relative pose error within 1 %."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from albot2d.cli import main

ROOT = Path(__file__).resolve().parents[1]


def _rpe(report_path: Path) -> dict[str, tuple[int, float, float]]:
    report = json.loads(report_path.read_text())
    out = {"odometry": report["odometry"]["rpe"]}
    out |= {name: m["rpe"] for name, m in report["mappers"].items()}
    return {k: (v["relations"], v["trans_m_mean"], v["rot_deg_mean"]) for k, v in out.items()}


@pytest.mark.slow
def test_the_mit_log_as_bags_replays_with_the_carmen_rpe(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = shared_data / "raw" / "mit-csail.clf.gz"
    relations = shared_data / "relations" / "mit-csail.relations"
    ros1, ros2 = tmp_path / "mit.bag", tmp_path / "mit_ros2"
    script = ROOT / "scripts" / "carmen_to_rosbag.py"
    done = subprocess.run(
        [sys.executable, str(script), str(log), "--ros1", str(ros1), "--ros2", str(ros2)],
        capture_output=True, text=True, check=False,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "1988 scans" in done.stdout and list(ros2.glob("*.mcap"))
    rpe = {}
    for name, source in (("carmen", log), ("ros1", ros1), ("ros2", ros2)):
        out = tmp_path / name
        argv = ["replay", str(source), "--relations", str(relations), "--out", str(out)]
        assert main([*argv, "--no-figures"]) == 0
        rpe[name] = _rpe(out / "report.json")
    capsys.readouterr()
    carmen = rpe["carmen"]
    assert carmen["odometry"][0] == 1172  # every relation of the log is used
    for name in ("ros1", "ros2"):
        for key, (n, trans, rot) in rpe[name].items():
            assert n == carmen[key][0], (name, key)
            assert trans == pytest.approx(carmen[key][1], rel=0.01), (name, key)
            assert rot == pytest.approx(carmen[key][2], rel=0.01), (name, key)
