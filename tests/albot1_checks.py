"""Invariant checks of an Albot1 run, shared by the unit, property and fuzzing tests."""

from __future__ import annotations

import itertools

import numpy as np
import shapely

from albot2d.geometry import Pose
from albot2d.mapping import Albot1, LocalMap, UpdateReport

__all__ = ["UpdateRecorder", "check_local_map_rule", "check_update_deleted_facing_overlap"]


def check_local_map_rule(m: Albot1, min_tracked: int = 4) -> None:
    """A view is remembered exactly when fewer than ``min_tracked`` tracked surfaces remain;
    V(c-1) is remembered unless it already is the current local map (Use-Vc); the route
    map is connected (its chain composes to every local map's pose)."""
    steps = m.steps
    assert steps[0].remembered == (steps[0].frame_index,)
    for prev, step in itertools.pairwise(steps):
        if step.tracked >= min_tracked:
            assert step.remembered == ()
            continue
        assert step.remembered, f"frame {step.frame_index}: {step.tracked} tracked, nothing kept"
        if step.use_vc:
            assert step.remembered == (step.frame_index,)
        else:
            assert step.remembered[0] == prev.frame_index
            assert step.remembered[-1] in (prev.frame_index, step.frame_index)
    # The Use-Vc switch holds exactly when the previous view became the local map.
    for prev, step in itertools.pairwise(steps):
        assert step.use_vc == (bool(prev.remembered) and prev.remembered[-1] == prev.frame_index)
    chain = m.route.compose_chain()
    stored = np.array([lm.pose.as_array() for lm in m.route])
    np.testing.assert_allclose(chain, stored, atol=1e-9)
    assert [lm.map_id for lm in m.route] == list(range(len(m.route)))
    assert all(lm.method != "start" for lm in m.route.maps[1:])


class UpdateRecorder:
    """An ``on_update`` hook that checks algorithm #5's postcondition after every update."""

    def __init__(self, mapper: Albot1 | None = None) -> None:
        self.mapper = mapper
        self.updates = 0

    def __call__(self, report: UpdateReport, lm: LocalMap) -> None:
        assert self.mapper is not None
        check_update_deleted_facing_overlap(self.mapper, report, lm.pose)
        self.updates += 1


def check_update_deleted_facing_overlap(m: Albot1, report: UpdateReport, robot: Pose) -> None:
    """After an update, no surface of an older map (in the affected group) that lies inside
    or across the enlarged view polygon is left on the robot's facing side."""
    snap = m.map.snapshot()
    older = snap.map_ids < report.map_id
    if not older.any() or report.polygon.is_empty:
        return
    segs = snap.segments[older]
    ids = snap.map_ids[older]
    hits = shapely.intersects(report.polygon, shapely.linestrings(segs.reshape(-1, 2, 2)))
    c, s = np.cos(robot.theta), np.sin(robot.theta)
    mid = 0.5 * (segs[:, :2] + segs[:, 2:])
    facing = c * (mid[:, 0] - robot.x) + s * (mid[:, 1] - robot.y) > 0.0
    current = report.map_id - 1
    # Surfaces of the map being left were deleted outright when inside the polygon.
    assert not np.any(hits & (ids == current)), "current-map surface left inside the view"
    # Older overlapping maps lose everything on the facing side.
    assert not np.any(hits & facing & (ids < current)), "older facing surface left in view"
