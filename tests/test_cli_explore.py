"""``albot2d run --tour explore``: the frontier explorer drives, the mappers map its views,
report.json carries coverage against time, and the run reproduces."""

from __future__ import annotations

import json
from pathlib import Path

from albot2d.cli import main

SMALL = ["--kind", "rooms", "--width", "14", "--height", "10", "--profile", "dataset3"]


def test_run_tour_explore_writes_coverage_and_reproduces(tmp_path: Path, capsys) -> None:
    out = tmp_path / "explore"
    assert main(["run", *SMALL, "--tour", "explore", "--max-frames", "60", "--out", str(out)]) == 0
    report = json.loads((out / "report.json").read_text())
    assert report["params"]["spec"]["tour_kind"] == "explore"
    exploration = report["exploration"]
    assert 0.0 < exploration["final_coverage"] <= 1.0
    assert exploration["collisions"] == 0
    assert exploration["ended"] == "stopped"  # --max-frames cut it short
    assert exploration["reachable_floor_m2"] > 50.0
    assert report["run"]["frames"] == 60
    assert set(report["mappers"]) == {"albot1", "naive", "truth"}
    assert (out / "paths.png").exists() or any(out.glob("*.png"))
    capsys.readouterr()
    again = tmp_path / "again"
    assert main(["run", "--reproduce", str(out / "report.json"), "--out", str(again)]) == 0
    assert "identical" in capsys.readouterr().out


def test_unknown_tour_names_explore(tmp_path: Path, capsys) -> None:
    assert main(["run", *SMALL, "--tour", "spiral", "--out", str(tmp_path / "o")]) == 2
    assert "explore" in capsys.readouterr().err
