"""Triangulation: known poses are recovered; the two heuristics behave as the paper says."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from albot2d.geometry import Pose, wrap_angle
from albot2d.mapping.albot1.triangulation import (
    TriangulationParams,
    heading_from_directions,
    pose_affordances,
    triangulate,
)
from albot2d.perception.surfaces import Surfaces

# Walls of a room seen from its middle, in the local map's frame (scan order irrelevant here).
ROOM = np.array(
    [
        [3.0, -2.0, 3.0, 2.0],
        [2.0, 3.0, -2.0, 3.0],
        [-3.0, 2.0, -3.0, -2.0],
        [-2.0, -3.0, 2.0, -3.0],
    ]
)


def observe(local: Surfaces, pose: Pose) -> Surfaces:
    """The same surfaces as seen from ``pose`` (expressed in the local map)."""
    return local.transformed(pose.inverse().as_array())


def assert_pose_close(a: Pose, b: Pose, tol: float = 1e-9) -> None:
    assert abs(a.x - b.x) < tol and abs(a.y - b.y) < tol
    assert abs(wrap_angle(a.theta - b.theta)) < tol


@given(
    st.floats(-1.0, 1.0),
    st.floats(-1.0, 1.0),
    st.floats(-math.pi, math.pi),
    st.integers(1, 4),
)
def test_exact_observations_triangulate_to_the_true_pose(
    x: float, y: float, th: float, n: int
) -> None:
    local = Surfaces.from_segments(ROOM[:n])
    truth = Pose(x, y, th)
    current = observe(local, truth)
    est = triangulate(local, current, Pose(x + 0.3, y - 0.2, th + 0.05))
    assert est is not None
    assert_pose_close(est, truth, 1e-9)


def test_two_surfaces_at_known_poses() -> None:
    local = Surfaces.from_segments(ROOM[:2])
    truth = Pose(0.5, -0.25, math.radians(20))
    est = triangulate(local, observe(local, truth), Pose(0.4, -0.2, math.radians(18)))
    assert est is not None
    assert_pose_close(est, truth)


def test_occluded_endpoints_give_no_affordance() -> None:
    local = Surfaces.from_segments(ROOM[:1], occluded=[[True, True]])
    current = observe(local, Pose(0.2, 0.0, 0.0))
    assert triangulate(local, current, Pose()) is None
    # An endpoint occluded only in the current view is unusable too; the other one works.
    local = Surfaces.from_segments(ROOM[:1], occluded=[[False, False]])
    current = Surfaces.from_segments(observe(local, Pose(0.2, 0, 0)).segments, [[True, False]])
    aff = pose_affordances(local, current, 0.0)
    assert len(aff.poses) == 1
    np.testing.assert_allclose(aff.poses[0], [0.2, 0.0, 0.0], atol=1e-12)


def test_reversed_endpoint_order_is_resolved_by_the_heading_hint() -> None:
    local = Surfaces.from_segments(ROOM[:1])
    truth = Pose(0.3, 0.1, 0.2)
    current = observe(local, truth)
    flipped = Surfaces.from_segments(current.segments[:, [2, 3, 0, 1]])
    est = triangulate(local, flipped, Pose(0.25, 0.1, 0.15))
    assert est is not None
    assert_pose_close(est, truth)


def test_heuristic_one_drops_the_outlier_and_heuristic_two_picks_nearest_to_pi() -> None:
    local = Surfaces.from_segments(ROOM)
    truth = Pose(0.2, 0.1, 0.0)
    current = observe(local, truth).segments.copy()
    current[0, [0, 2]] += 0.02  # a small error: affordance 2 cm off
    current[2, [1, 3]] += 1.5  # a gross error: this surface was mis-tracked
    cur = Surfaces.from_segments(current)
    aff = pose_affordances(local, cur, 0.0)
    assert len(aff.poses) == 4
    # The path-integration estimate lies towards the outlier; heuristic 1 must remove it.
    pi = Pose.from_array(aff.poses[2])
    bare = {"max_pi_deviation_m": math.inf, "max_pi_deviation_deg": math.inf}
    with_h1 = triangulate(local, cur, pi, TriangulationParams(**bare))
    without_h1 = triangulate(
        local, cur, pi, TriangulationParams(use_outlier_heuristic=False, **bare)
    )
    assert without_h1 is not None and with_h1 is not None
    assert_pose_close(without_h1, pi)
    assert with_h1.distance_to(truth) < 0.03


def test_mismatched_lengths_raise() -> None:
    with pytest.raises(ValueError, match="surfaces"):
        triangulate(Surfaces.from_segments(ROOM[:2]), Surfaces.from_segments(ROOM[:1]), Pose())


def test_affordances_inconsistent_with_path_integration_are_discarded() -> None:
    local = Surfaces.from_segments(ROOM[:2])
    truth = Pose(0.2, 0.1, 0.0)
    current = observe(local, truth).segments.copy()
    # Surface 0 seen rotated by 8 degrees about the robot: its affordance is far off.
    c, s = math.cos(math.radians(8)), math.sin(math.radians(8))
    p = current[0].reshape(2, 2)
    current[0] = (p @ np.array([[c, s], [-s, c]])).ravel()
    cur = Surfaces.from_segments(current)
    pi = Pose(0.21, 0.1, 0.01)
    est = triangulate(local, cur, pi)
    assert est is not None
    assert_pose_close(est, truth)  # only surface 1 is consistent with path integration
    # Only the bad surface left: no affordance survives, the caller falls back to PI.
    assert triangulate(local.select([0]), cur.select([0]), pi) is None
    bare = TriangulationParams(max_pi_deviation_m=math.inf, max_pi_deviation_deg=math.inf)
    assert triangulate(local.select([0]), cur.select([0]), pi, bare) is not None


@pytest.mark.parametrize("field", ["max_pi_deviation_m", "max_pi_deviation_deg"])
def test_gate_parameters_are_validated(field: str) -> None:
    from albot2d.errors import InputError

    with pytest.raises(InputError, match=field):
        TriangulationParams(**{field: -1.0})


def test_heading_from_directions_needs_no_corner() -> None:
    """Walls whose ends are all occluded afford no position, but their directions give the
    heading; path integration's position is not touched."""
    occ = [[True, True]] * 3
    local = Surfaces.from_segments(ROOM[:3], occluded=occ)
    truth = Pose(0.4, -0.3, math.radians(12.0))
    current = observe(local, truth)
    current = Surfaces(current.segments, np.ones((3, 2), bool), current.beams)
    pi = Pose(0.45, -0.25, math.radians(10.0))
    assert triangulate(local, current, pi) is None
    heading = heading_from_directions(local, current, pi)
    assert heading is not None and heading == pytest.approx(truth.theta, abs=1e-9)


def test_heading_from_directions_drops_what_contradicts_path_integration() -> None:
    local = Surfaces.from_segments(ROOM[:2], occluded=[[True, True]] * 2)
    truth = Pose(0.0, 0.0, math.radians(30.0))
    current = observe(local, truth)
    # 30° from path integration: beyond the 5°-per-step gate after one step, inside after 7
    pi = Pose(0.0, 0.0, 0.0)
    assert heading_from_directions(local, current, pi, steps=1) is None
    assert heading_from_directions(local, current, pi, steps=7) == pytest.approx(truth.theta)
    empty = Surfaces.from_segments(np.zeros((0, 4)))
    assert heading_from_directions(empty, empty, pi) is None


def test_heading_from_directions_counts_agreeing_surfaces() -> None:
    """A wall mis-measured by 2° is left out of the consensus; asking for more agreeing
    walls than the three good ones gives no heading."""
    local = Surfaces.from_segments(ROOM, occluded=[[True, True]] * 4)
    truth = Pose(0.2, 0.1, math.radians(-8.0))
    segs = observe(local, truth).segments.copy()
    rot = Pose(0.0, 0.0, math.radians(2.0)).as_array()
    segs[3] = Surfaces.from_segments(segs[3:4]).transformed(rot).segments[0]
    current = Surfaces.from_segments(segs, occluded=[[True, True]] * 4)
    pi = Pose(0.2, 0.1, math.radians(-7.0))
    three = heading_from_directions(local, current, pi, min_agreeing=3)
    assert three == pytest.approx(truth.theta, abs=1e-9)
    assert heading_from_directions(local, current, pi, min_agreeing=4) is None
