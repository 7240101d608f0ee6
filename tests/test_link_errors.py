"""Albot1's per-link error budget (albot2d.studies.link_errors)."""

from __future__ import annotations

import math
from itertools import islice

import numpy as np
import pytest

from albot2d.evaluation.run.setup import RunSpec, build_run
from albot2d.geometry import Pose
from albot2d.mapping.albot1.mapper import Albot1
from albot2d.perception.surfaces import Surfaces
from albot2d.studies.link_errors import (
    LinkError,
    LinkRecorder,
    kind_summary,
    link_errors,
    main,
    record_run,
    recording_albot1,
    window_budget,
)

NAN = float("nan")


def _link(map_id: int, travelled: float, kind: str) -> LinkError:
    return LinkError(map_id, map_id, travelled, kind, *([0] * 5), *([NAN] * 10))


def test_window_budget_splits_a_known_chain_by_kind() -> None:
    # Truth: five viewpoints 1 m apart along x. Link 2 carries +1° of heading error
    # (a triangulation), link 3 +0.1 m along x (path integration); the others are exact.
    truth = np.array([[float(i), 0.0, 0.0] for i in range(5)])
    mapper = Albot1()
    rel = [Pose(), Pose(1, 0, 0), Pose(1, 0, math.radians(1.0)), Pose(1.1, 0, 0), Pose(1, 0, 0)]
    kinds = ["start", "triangulation", "triangulation", "pi_no_tracked", "triangulation"]
    for i, r in enumerate(rel):
        mapper.route.append(i, Surfaces.empty(), r, "start" if i == 0 else "triangulation")
    links = [_link(i, float(i), k) for i, k in enumerate(kinds)]
    budget = window_budget(mapper, links, truth, end_m=4.0, window_m=30.0)
    assert budget["all"]["links"] == 4
    assert budget["all"]["heading_deg"] == pytest.approx(1.0)
    assert budget["triangulation"]["heading_deg"] == pytest.approx(1.0)
    # a 1° turn at map 2 moves map 4, 2 m further on, by the chord 4 sin 0.5°
    assert budget["triangulation"]["position_m"] == pytest.approx(4 * math.sin(math.radians(0.5)))
    assert budget["pi_no_tracked"]["heading_deg"] == pytest.approx(0.0, abs=1e-12)
    assert budget["pi_no_tracked"]["position_m"] == pytest.approx(0.1)
    # headings alone: the 1° turn; positions alone: the 0.1 m step
    assert budget["all: headings only"]["position_m"] == pytest.approx(
        4 * math.sin(math.radians(0.5))
    )
    assert budget["all: positions only"]["position_m"] == pytest.approx(0.1)
    assert budget["all: positions only"]["heading_deg"] == pytest.approx(0.0, abs=1e-12)
    # a window holding only maps 3-4 sees just the link between them, which is exact
    late = window_budget(mapper, links, truth, end_m=4.0, window_m=1.5)
    assert late["all"]["position_m"] == pytest.approx(0.0, abs=1e-12)


def test_recording_changes_nothing_and_path_integration_is_exact_without_noise() -> None:
    spec = RunSpec(noise="none", mappers=("albot1",))
    mapper, recorder, truth, travelled = record_run(spec, max_frames=500)
    setup = build_run(spec)
    plain = Albot1()
    for frame in islice(setup.simulator.drive(setup.tour, setup.profile), 500):
        plain.observe(frame)
    assert mapper.on_localise is recorder
    np.testing.assert_array_equal(mapper.route.relative_poses(), plain.route.relative_poses())
    links = link_errors(mapper, recorder, truth, travelled)
    assert len(links) == len(mapper.route) > 10
    assert links[0].kind == "start"
    # without odometry noise path integration is the truth, on every link
    assert max(abs(link.pi_heading_err_deg) for link in links) < 1e-6
    assert max(link.pi_position_err_m for link in links) < 1e-6
    kinds = {link.kind for link in links[1:]}
    assert "triangulation" in kinds
    for link in links:
        if link.kind == "triangulation":
            assert link.consistent >= link.kept >= 1
            assert link.affordances >= link.consistent
            assert abs(link.heading_err_deg) < 2.0  # line fits only: laser noise
        else:  # path integration: the link is the odometry, exact here
            assert abs(link.heading_err_deg) < 1e-6
    summary = kind_summary(links)
    assert sum(row["links"] for k, row in summary.items() if " " not in k) == len(links) - 1


def test_cli_rejects_an_unknown_preset(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--preset", "bogus", "--max-frames", "5"]) == 2
    assert "bogus" in capsys.readouterr().out


def test_cli_overrides_nested_fields(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(
        ["--max-frames", "40", "--param", "triangulation.position_endpoint=current_real",
         "--param", "min_tracked=3", "--windows", "1"]
    )  # fmt: skip
    assert code == 0
    assert "local maps" in capsys.readouterr().out
    assert main(["--param", "triangulation.position_endpoint=nearest"]) == 2
    assert main(["--param", "min_tracked"]) == 2


def test_each_kind_of_path_integration_is_told_apart() -> None:
    """Hand-built tracked walls: none left, ends imprecise in both views, every
    affordance beyond the gate, and the heading taken from the walls' directions."""
    from albot2d.mapping.albot1.mapper import Albot1Params
    from albot2d.perception import TrackedSurfaces, start_tracking
    from albot2d.perception.tracking import TrackingParams

    walls = np.array([[3.0, -2.0, 3.0, 2.0], [1.0, 2.0, 2.5, 2.0], [1.0, -2.0, 2.5, -2.0]])
    n = len(walls)
    occ = np.zeros((n, 2), bool)
    beams = np.full((n, 2), -1)
    truth = Pose(0.3, 0.1, math.radians(4.0))
    odometric = Pose(0.32, 0.05, math.radians(1.0))

    def tracked_pair(uncertain: bool, seen_from: Pose) -> TrackedSurfaces:
        flags = np.full((n, 2), uncertain)
        view = Surfaces(walls, occ, beams, flags)
        moved = view.transformed(seen_from.inverse().as_array())
        tracked = start_tracking(view, TrackingParams(min_view_angle_deg=0.0))
        return TrackedSurfaces(
            tracked.ids, tracked.local, Surfaces(moved.segments, occ, beams, flags)
        )

    def kind(recording: tuple[Albot1, LinkRecorder], tracked: TrackedSurfaces) -> str:
        mapper, recorder = recording
        mapper.localise(tracked, odometric, 1)
        return recorder.localisations[-1].kind

    paper = recording_albot1()
    assert kind(paper, TrackedSurfaces.empty()) == "pi_no_tracked"
    assert kind(paper, tracked_pair(True, truth)) == "pi_no_endpoint"
    assert kind(paper, tracked_pair(False, truth)) == "triangulation"
    # the walls say the view is 2 m from where odometry puts it: beyond 0.4 m per step
    assert kind(paper, tracked_pair(False, Pose(2.3, 0.1, truth.theta))) == "pi_gated"
    fallback = recording_albot1(Albot1Params(heading_fallback_surfaces=1))
    assert kind(fallback, tracked_pair(True, truth)) == "pi_surface_heading"
    record = paper[1].localisations[2]
    assert record is not None and record.tracked == 3 and record.consistent == 3
