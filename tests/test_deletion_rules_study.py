"""The deletion-rule study (``albot2d.studies.deletion_rules``): a real short run's local
maps re-added under every rule; re-adding under Albot₁'s own rule at its own poses gives
its own global map and its own scores, and no rule keeps more than no deletion."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from albot2d.evaluation.run.scoring import egocentric_at
from albot2d.evaluation.run.setup import RunSpec
from albot2d.geometry import Pose
from albot2d.mapping.albot1.global_map import GlobalMapParams
from albot2d.studies.deletion_rules import (
    RULES,
    RecordedRun,
    check_faithful,
    main,
    readd,
    record_run,
    rule_scores,
    transience,
)

# ~42 m of the default run: stops at 20 and 40 m and the end
FRAMES = 1600


@pytest.fixture(scope="module")
def run() -> RecordedRun:
    return record_run(RunSpec(max_frames=FRAMES))


def test_the_run_is_the_default_run_cut_short(run: RecordedRun) -> None:
    assert run.spec == RunSpec(max_frames=FRAMES, mappers=("albot1",))
    assert run.trace.n_frames == FRAMES and len(run.stops()) >= 3
    assert [m.map_id for m in run.maps] == list(range(len(run.maps)))
    # the remembered count never falls, and reaches every local map by the end
    assert np.all(np.diff(run.remembered_after_row) >= 0)
    assert run.remembered_after_row[-1] == len(run.maps) == len(run.mapper.route)


def test_visible_at_albot1s_poses_is_albot1s_own_map(run: RecordedRun) -> None:
    assert run.mapper.params.global_map == GlobalMapParams.preset("visible")
    visible = next(r for r in RULES if r.name == "visible")
    mine = readd(run.maps, visible.params, "albot1")
    ours, its = mine.snapshot(), run.mapper.global_map()
    assert len(its.segments) > 100
    np.testing.assert_array_equal(ours.segments, its.segments)
    np.testing.assert_array_equal(ours.map_ids, its.map_ids)
    assert check_faithful(run) > len(its.segments)
    # and the study's scores of that row are the run's own at every stop
    scores = rule_scores(run, visible.params, "albot1")
    own = [egocentric_at(run.trace, stop, "albot1", run.walls) for stop in run.stops()]
    assert [(s.completeness, s.accuracy_m_p95, s.surfaces) for s in scores] == [
        (q.completeness, q.accuracy_m_p95, q.surfaces) for q in own if q is not None
    ]


def test_the_faithfulness_check_can_fail(run: RecordedRun) -> None:
    maps = list(run.maps)
    k = len(maps) // 2
    maps[k] = dataclasses.replace(maps[k], pose=maps[k].pose @ Pose(0.05, 0.0, 0.0))
    with pytest.raises(RuntimeError, match="differs from Albot₁'s"):
        check_faithful(dataclasses.replace(run, maps=tuple(maps)))


def test_albot1s_poses_do_not_depend_on_its_deletion_rule(run: RecordedRun) -> None:
    # the former table took its poses from albot1[deletion=paper]: the same local maps at
    # the same poses (localisation never reads the global map), and its own map is the
    # paper rule's re-added map
    paper = record_run(RunSpec(max_frames=FRAMES), "albot1[deletion=paper]")
    assert paper.name == "albot1[deletion=paper]"
    assert [(m.frame_index, m.pose) for m in paper.maps] == [
        (m.frame_index, m.pose) for m in run.maps
    ]
    assert check_faithful(paper) > 0
    assert len(paper.mapper.global_map().segments) < len(run.mapper.global_map().segments)


def test_no_deletion_keeps_at_least_what_every_rule_keeps(run: RecordedRun) -> None:
    for poses in ("albot1", "true"):
        ceiling = rule_scores(run, None, poses)
        total = sum(len(m.segments) for m in run.maps)
        assert ceiling[-1].surfaces == total  # nothing deleted
        for rule in RULES[1:]:
            scores = rule_scores(run, rule.params, poses)
            assert len(scores) == len(ceiling)
            for s, c in zip(scores, ceiling, strict=True):
                assert s.surfaces <= c.surfaces, (rule.name, poses, s.travelled_m)
        _, kept = transience(run, None, poses)
        assert (kept.added, kept.kept, kept.revisit_updates) == (total, total, 0)
        # v1 deletes most of what is added (albot2d 0.1's reading)
        v1 = rule_scores(run, RULES[-1].params, poses)
        assert v1[-1].surfaces < 0.5 * ceiling[-1].surfaces


def test_the_command_prints_the_table_and_writes_json(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / "study.json"
    assert main(["--max-frames", "800", "--json", str(out), "--quiet"]) == 0
    text = capsys.readouterr().out
    assert "| **`visible`** (default) |" in text and "| `v1` |" in text
    study = json.loads(out.read_text())
    assert study["frames"] == 800 and study["faithful_surfaces"] > 0
    assert [row["rule"] for row in study["rows"]] == [r.name for r in RULES]
    assert len(study["rows"][0]["albot1"]) == len(study["stops_m"]) >= 2
    assert study["spec"]["max_frames"] == 800 and study["spec"]["tour_kind"] == "loop"


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--seed", "x"], "--seed: invalid int value"),
        (["--tour-length", "50", "--min-tour-length", "50"], "not both"),
        (["--at", "20,abc"], "argument --at: expected metres"),
        (["--noise", "nosuch"], "nosuch"),
        (["--tour-length", "-3"], "tour_length_m must be a positive number"),
        (["--json", "/nonexistent-dir/x.json"], "--json: no directory"),
        (["--albot1", "naive"], "--albot1: give albot1"),
        (["--albot1", "albot1[deletion=nosuch]"], "nosuch"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(argv: list[str], message: str, capsys) -> None:  # type: ignore[no-untyped-def]
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("deletion_rules: ") and message in lines[0]
