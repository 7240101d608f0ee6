"""Map quality against distances worked out by hand (parallel walls at known offsets,
points at known distances from a segment's ends or interior), and completeness as a
count of covered points, in layouts that reach every search radius and the grid edges.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from albot2d.evaluation.metrics.map_quality import (
    MapQualityParams,
    map_quality,
    nearest_segment_distance_bounded,
    point_to_segment_geos,
)
from albot2d.geometry import Pose

WALL = np.array([[0.0, 0.0, 10.0, 0.0]])
ORIGIN = Pose(0.0, 0.0, 0.0)


def test_point_to_segment_distances_by_hand() -> None:
    """Segment (1, 1)–(4, 5) (length 5): a point beyond end b, one before end a, one
    beside the interior (distance by the cross product over the length), a degenerate
    segment (a point)."""
    px = np.array([7.0, -2.0, 1.0 + 1.5 + 0.8 * 2.0, 3.0])
    py = np.array([9.0, -3.0, 1.0 + 2.0 - 0.6 * 2.0, 3.0])
    seg = np.array([[1.0, 1.0, 4.0, 5.0]] * 3 + [[0.0, -1.0, 0.0, -1.0]])
    got = point_to_segment_geos(px, py, seg)
    np.testing.assert_allclose(got, [5.0, 5.0, 2.0, 5.0], atol=1e-12)


def test_accuracy_of_walls_at_known_offsets_reaching_every_search_radius() -> None:
    """Map surfaces parallel to a 10 m wall at 0.3, 1.5, 5 and 20 m (within the first,
    second and third search radius, and beyond them all): every sample is exactly its
    offset away. Equal lengths and spacing: mean 6.7, max 20; p95 lies in the 20 m
    surface's samples."""
    offsets = [0.3, 1.5, 5.0, 20.0]
    segs = np.array([[2.0, y, 8.0, y] for y in offsets])
    q = map_quality(segs, WALL, start_pose=ORIGIN)
    assert q.surfaces == 4
    assert q.accuracy_m_mean == pytest.approx(np.mean(offsets), abs=1e-12)
    assert q.accuracy_m_max == pytest.approx(20.0, abs=1e-12)
    assert q.accuracy_m_p95 == pytest.approx(20.0, abs=1e-12)
    # Beyond the wall's end: a surface from (12, 0) to (13, 0) lies 2..3 m from (10, 0).
    q = map_quality([[12.0, 0.0, 13.0, 0.0]], WALL, start_pose=ORIGIN)
    assert q.accuracy_m_mean == pytest.approx(2.5, abs=1e-12)
    assert q.accuracy_m_max == pytest.approx(3.0, abs=1e-12)


def test_the_map_is_placed_by_the_start_pose() -> None:
    """Started at (5, −1) facing +y: a surface 1 m to the robot's right and 2 m long
    straight ahead, (0, −1)–(2, −1) in its frame, is (6, −1)–(6, 1) in the world: 1 m
    from the true wall x = 5."""
    truth = np.array([[5.0, -5.0, 5.0, 5.0]])
    start = Pose(5.0, -1.0, math.pi / 2)
    q = map_quality([[0.0, -1.0, 2.0, -1.0]], truth, start_pose=start)
    assert q.accuracy_m_mean == pytest.approx(1.0, abs=1e-12)
    assert q.accuracy_m_max == pytest.approx(1.0, abs=1e-12)


def test_completeness_counts_points_within_the_tolerance() -> None:
    """Seen points every 0.5 m along the wall (21 points, x = 0 … 10) and 9 more far off
    (30 m and 60 m away, so the grid of seen points is wide). The map covers x ∈ [0, 4]
    at 0.1 m off the wall (exactly the tolerance: covered) and has a surface 100 m away
    (outside the grid): 9 of 30 points covered. With a 0.09 m tolerance, none."""
    seen = np.vstack(
        [
            np.column_stack([np.linspace(0.0, 10.0, 21), np.zeros(21)]),
            np.column_stack([np.full(5, 30.0), np.linspace(-2.0, 2.0, 5)]),
            np.column_stack([np.linspace(0.0, 3.0, 4), np.full(4, 60.0)]),
        ]
    )
    segs = np.array([[0.0, 0.1, 4.0, 0.1], [100.0, 100.0, 101.0, 100.0]])
    q = map_quality(segs, WALL, start_pose=ORIGIN, seen_points=seen)
    assert q.completeness == pytest.approx(9 / 30, abs=1e-12)
    tight = MapQualityParams(coverage_tolerance_m=0.09)
    q = map_quality(segs, WALL, start_pose=ORIGIN, seen_points=seen, params=tight)
    assert q.completeness == 0.0
    # A second surface covering the far column: 9 + 5 of 30.
    more = np.vstack([segs, [[30.05, -3.0, 30.05, 3.0]]])
    q = map_quality(more, WALL, start_pose=ORIGIN, seen_points=seen)
    assert q.completeness == pytest.approx(14 / 30, abs=1e-12)


def test_an_empty_map_has_no_accuracy_and_covers_nothing() -> None:
    seen = np.array([[1.0, 0.0], [2.0, 0.0]])
    q = map_quality(np.zeros((0, 4)), WALL, start_pose=ORIGIN, seen_points=seen)
    assert (q.accuracy_m_mean, q.accuracy_m_p95, q.accuracy_m_max) == (None, None, None)
    assert q.completeness == 0.0
    assert q.surfaces == 0
    q = map_quality(np.zeros((0, 4)), WALL, start_pose=ORIGIN)
    assert q.completeness is None


@pytest.mark.parametrize("beyond", ["nearest", "inf"])
def test_bounded_nearest_distance_by_radius(beyond: str) -> None:
    """Points 0.2, 1, 3 and 12 m above the wall's middle, radii (0.5, 2): the first two
    are found within a radius, the others by the tree (``"nearest"``) or not (``"inf"``)."""
    pts = np.array([[5.0, 0.2], [5.0, 1.0], [5.0, 3.0], [5.0, 12.0]])
    got = nearest_segment_distance_bounded(pts, WALL, (0.5, 2.0), beyond=beyond)
    far = [3.0, 12.0] if beyond == "nearest" else [math.inf, math.inf]
    np.testing.assert_allclose(got, [0.2, 1.0, *far], atol=1e-12)


def test_a_point_equidistant_from_two_walls_has_one_distance() -> None:
    """(5, 1) is 1 m from y = 0 and from y = 2: one distance per point, 1 m, whether the
    nearest wall is searched within radii or by the tree."""
    from albot2d.evaluation.metrics.map_quality import nearest_segment_distance

    walls = np.array([[0.0, 0.0, 10.0, 0.0], [0.0, 2.0, 10.0, 2.0]])
    pts = np.array([[5.0, 1.0], [5.0, 0.5]])
    np.testing.assert_allclose(nearest_segment_distance(pts, walls), [1.0, 0.5], atol=1e-12)
    np.testing.assert_allclose(nearest_segment_distance_bounded(pts, walls), [1.0, 0.5], atol=1e-12)
    far = np.array([[5.0, 30.0]])
    np.testing.assert_allclose(nearest_segment_distance_bounded(far, walls), [28.0], atol=1e-12)


def test_no_true_walls_leaves_accuracy_undefined_without_warnings() -> None:
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # numpy's mean-of-inf / percentile warnings fail
        q = map_quality(np.array([[0.0, 0.0, 1.0, 0.0]]), np.zeros((0, 4)), start_pose=Pose())
    assert (q.accuracy_m_mean, q.accuracy_m_p95, q.accuracy_m_max) == (None, None, None)
    assert q.surfaces == 1
