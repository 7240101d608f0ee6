"""Egocentric map quality on hand-built maps whose answer is known."""

from __future__ import annotations

import math

import numpy as np
import pytest

from albot2d.evaluation.metrics.egocentric import (
    EgocentricParams,
    egocentric_quality,
    in_robot_frame,
    seen_window_local,
    unique_on_grid,
)
from albot2d.evaluation.metrics.map_quality import sample_segments
from albot2d.geometry import Pose, transform_segments

# A corridor 2 m wide along +x in the world, the robot at (10, 0) facing +x.
WALLS = np.array([[0.0, -1.0, 20.0, -1.0], [0.0, 1.0, 20.0, 1.0]])
ROBOT = np.array([10.0, 0.0, 0.0])


def seen_behind() -> np.ndarray:
    """What the robot saw over the last 10 m: both walls from x = 0 to 10, world frame."""
    pts = sample_segments(np.array([[0.0, -1.0, 10.0, -1.0], [0.0, 1.0, 10.0, 1.0]]), 0.05)
    return seen_window_local(pts, ROBOT, 0.05)


def test_a_perfect_map_is_complete_and_exact() -> None:
    seen = seen_behind()
    local = in_robot_frame(ROBOT, WALLS, 30.0)
    q = egocentric_quality(seen, local, WALLS, ROBOT)
    assert q.completeness == 1.0
    assert q.accuracy_m_p95 == pytest.approx(0.0, abs=1e-9)
    assert q.surfaces == 2 and q.window_m == 30.0


def test_a_map_with_one_wall_is_half_complete() -> None:
    q = egocentric_quality(seen_behind(), in_robot_frame(ROBOT, WALLS[:1], 30.0), WALLS, ROBOT)
    assert q.completeness == pytest.approx(0.5, abs=0.01)


def test_the_map_is_judged_from_the_mappers_own_pose() -> None:
    """A map placed 3 m off in its own frame, with the mapper's pose off by the same 3 m,
    is as good as the truth: only relative placement counts. A 2° heading error shows up."""
    offset = Pose(3.0, -2.0, 0.0)
    map_frame = transform_segments(offset.inverse().as_array(), WALLS)
    est_pose = (offset.inverse() @ Pose.from_array(ROBOT)).as_array()
    q = egocentric_quality(seen_behind(), in_robot_frame(est_pose, map_frame, 30.0), WALLS, ROBOT)
    assert q.completeness == 1.0 and q.accuracy_m_p95 == pytest.approx(0.0, abs=1e-9)
    turned = est_pose + np.array([0.0, 0.0, math.radians(2.0)])
    q2 = egocentric_quality(seen_behind(), in_robot_frame(turned, map_frame, 30.0), WALLS, ROBOT)
    # 10 m behind the robot a 2° error is 0.35 m: beyond the 0.25 m tolerance.
    assert q2.completeness is not None and 0.5 < q2.completeness < 0.9
    assert q2.accuracy_m_p95 is not None and 0.2 < q2.accuracy_m_p95 < 0.5


def test_empty_inputs() -> None:
    q = egocentric_quality(np.zeros((0, 2)), np.zeros((0, 4)), WALLS, ROBOT)
    assert q.completeness is None and q.accuracy_m_p95 is None and q.surfaces == 0
    q = egocentric_quality(seen_behind(), np.zeros((0, 4)), WALLS, ROBOT)
    assert q.completeness == 0.0 and q.accuracy_m_p95 is None


def test_grid_keeps_one_point_per_cell_and_params_are_checked() -> None:
    pts = np.array([[0.01, 0.01], [0.02, 0.03], [0.5, 0.5]])
    assert len(unique_on_grid(pts, 0.05)) == 2
    with pytest.raises(Exception, match="window_m"):
        EgocentricParams(window_m=0.0)


def test_a_run_reports_egocentric_quality_revisits_and_updates_by_region() -> None:
    """report.json carries the new sections for a view-based mapper (and None otherwise)."""
    from albot2d.evaluation.run.experiment import RunSpec, run_experiment

    spec = RunSpec(kind="office", seed=1, profile="start_stop", tour_kind="circuit",
                   noise="pioneer3dx", mappers=("albot1", "naive"), max_frames=40)  # fmt: skip
    mappers = run_experiment(spec).report["mappers"]
    albot1, naive = mappers["albot1"], mappers["naive"]
    ego = albot1["map"]["egocentric"]
    assert ego["window_m"] == 30.0 and 0.0 <= ego["completeness"] <= 1.0
    assert ego["surfaces"] == albot1["counts"]["global_map_surfaces"]
    assert all(0.0 <= e["egocentric_completeness"] <= 1.0 for e in albot1["homing"])
    assert albot1["revisits"]["min_gap_maps"] == 20 and naive["revisits"] is None
    by_region = albot1["updates_by_region"]
    # An update is a frame that remembered a view (one frame may remember V(c-1) and V(c)).
    assert 0 < by_region["all"]["updates"] <= albot1["counts"]["local_maps"] - 1
    assert naive["updates_by_region"] is None


def test_stops_scored_while_driving_equal_the_kept_inputs_scored_later() -> None:
    """With the true walls, drive_mappers scores each stop there and then and keeps no map
    copies (memory follows the map, not stops × map); the scores equal those computed
    afterwards from the kept window and maps, stop by stop, mapper by mapper."""
    from albot2d.evaluation.run.scoring import egocentric_at
    from albot2d.evaluation.run.setup import RunSpec, build_run
    from albot2d.evaluation.run.trace import HomingParams, Trace, drive_mappers

    spec = RunSpec(kind="office", seed=2, world_params={"width_m": 30.0, "height_m": 24.0},
                   profile="dataset3", tour_length_m=30.0, max_frames=600)  # fmt: skip
    setup = build_run(spec)
    frames = list(setup.simulator.drive(setup.tour, setup.profile))
    walls = setup.world.obstacle_segments
    homing = HomingParams(stop_every_m=5.0)

    def drive(with_walls: bool) -> Trace:
        mappers = {n: f() for n, f in setup.mapper_factories.items()}
        return drive_mappers(iter(frames), mappers, homing=homing, max_frames=spec.max_frames,
                             walls=walls if with_walls else None)  # fmt: skip

    kept, scored = drive(False), drive(True)
    assert len(scored.stops) == len(kept.stops) >= 3
    for a, b in zip(kept.stops, scored.stops, strict=True):
        assert a.seen is not None and set(a.maps) == {"albot1", "naive", "truth"}
        assert b.seen is None and not b.maps and set(b.egocentric) == set(a.maps)
        for name in a.maps:
            later = egocentric_at(kept, a, name, walls)
            assert later is not None and later.completeness is not None
            assert egocentric_at(scored, b, name, walls) == later
    # Without the world (a real log's scoring) there is no egocentric quality either way.
    assert egocentric_at(scored, scored.stops[0], "albot1", None) is None
