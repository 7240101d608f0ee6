"""``albot2d experiments --quick`` says it is a smoke run wherever it shows (its first
output line, every verdict line, the page's banner and verdicts), and a figure of a run
cut short says where it stopped instead of naming a place it never reached."""

from __future__ import annotations

import numpy as np

from albot2d.cli import main
from albot2d.evaluation.paper.figdata import map_panel
from albot2d.evaluation.paper.jobs import FigureRun, MapAt, Snapshot


def _fig(reached: bool) -> FigureRun:
    albot1 = MapAt(np.zeros((1, 4)), np.zeros(1, dtype=np.int64), np.zeros(3), 149, 20, 0)
    snap = Snapshot(np.zeros(3), 7.2, 149, {"albot1": albot1}, reached)
    return FigureRun(world_walls=np.zeros((1, 4)), true_poses=np.zeros((200, 3)),
                     odom_poses=np.zeros((200, 3)), snaps={"E5": snap}, waypoints={},
                     updates=None, views=None)  # fmt: skip


def test_a_panel_names_the_place_only_when_the_run_got_there():
    title = "(b) Albot₁ {at}, before passing S"
    reached = map_panel(_fig(True), "E5", "albot1", title, place="at E5")
    assert reached is not None and reached["title"] == "(b) Albot₁ at E5, before passing S"
    cut = map_panel(_fig(False), "E5", "albot1", title, place="at E5")
    assert cut is not None
    assert cut["title"].splitlines() == [
        "(b) Albot₁", "run cut short at view 149, 7 m (not at E5)", "before passing S",
    ]  # fmt: skip


def test_quick_says_smoke_run_first_and_beside_every_verdict(tmp_path, capsys):
    out = tmp_path / "exp"
    assert main(["experiments", "--quick", "--only", "table1", "--seeds", "0", "--workers",
                 "1", "--no-figures", "--out", str(out)]) == 0  # fmt: skip
    lines = capsys.readouterr().out.splitlines()
    assert "smoke run" in lines[0]
    verdicts = [line for line in lines if line.startswith("table1")]
    assert verdicts and all(line.endswith("(smoke run)") for line in verdicts)
    page = (out / "index.html").read_text()
    assert "id='smoke-banner'" in page
    assert page.count("(smoke run)") >= 2  # the summary table and the section's verdict


def test_a_full_run_says_nothing_of_smoke(tmp_path):
    from albot2d.viz.paper_page import render_page

    data = {"seeds": [0, 1], "quick": False, "odometry_noise": "pioneer3dx", "albot_x": "slam",
            "verdicts": {"x": "partly"},
            "experiments": {"x": {"claim": "c", "rule": "r", "verdict": "partly",
                                  "paper": {}, "ours": {}, "figure_seed": 0}}}  # fmt: skip
    page = render_page(data, {})
    assert "smoke run" not in page and "smoke-banner" not in page
