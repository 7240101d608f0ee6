"""The deletion rule's geometric tests against hand-worked answers, on the numpy reference
and on the compiled path alike (no environment variable: the reference functions are
called directly, the dispatching ones with ``backend=``).

- facing side: which surfaces lie in front of the robot's lateral axis, by each
  ``facing_test``, worked out in the robot's frame (endpoints exactly on the axis are not
  in front);
- seen side: the robot strictly left of a directed surface;
- in range: both endpoints within the reach, the reach itself included;
- visibility: the share of a surface's sample points seen through a view, by similar
  triangles;
- the view polygon enlarged "forward": the buffer of the view's polygon clipped by a
  half-plane built independently (a large shapely box in the robot's frame).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from shapely import affinity

from albot2d.geometry import Pose
from albot2d.mapping.albot1.deletion import (
    facing_mask,
    facing_seen_mask,
    in_range_mask,
    seen_side_mask,
    view_polygon,
    visible_share,
)
from albot2d.perception.extraction import numba_available

SHARE_BACKENDS = ["numpy", pytest.param("numba", marks=pytest.mark.skipif(
    not numba_available(), reason="numba not installed"))]  # fmt: skip

# The robot at (1, -2) facing +y (90°): "forward" is +y, its lateral axis the line y = −2.
ROBOT = Pose(1.0, -2.0, math.pi / 2)


def _world(local: list[tuple[float, float, float, float]]) -> np.ndarray:
    """Segments given in ROBOT's frame (x forward, y left) mapped to the world by hand:
    world = (1 − y_local, −2 + x_local)."""
    return np.array([[1.0 - y0, -2.0 + x0, 1.0 - y1, -2.0 + x1] for x0, y0, x1, y1 in local])


# (local segment, both_endpoints, midpoint, any_endpoint)
FACING_CASES = [
    ((1.0, -1.0, 2.0, 1.0), True, True, True),  # wholly in front
    ((2.0, 0.5, -1.0, 0.5), False, True, True),  # straddles, midpoint (0.5) in front
    ((1.0, 0.5, -3.0, 0.5), False, False, True),  # straddles, midpoint (−1) behind
    ((-1.0, 2.0, -2.0, -2.0), False, False, False),  # wholly behind
    ((0.0, 1.0, 3.0, 1.0), False, True, True),  # one end exactly on the axis
    ((0.0, 1.0, 0.0, -1.0), False, False, False),  # along the axis: not in front
]


@pytest.mark.parametrize("test", ["both_endpoints", "midpoint", "any_endpoint"])
@pytest.mark.parametrize("facing_y", [True, False])
def test_facing_side_by_each_test_worked_in_the_robots_frame(test: str, facing_y: bool) -> None:
    """Facing +y (``ROBOT``) the cases off the axis; facing +x from the same place (where
    the axis is exact in floating point: cos 0 = 1, sin 0 = 0) all of them."""
    col = {"both_endpoints": 1, "midpoint": 2, "any_endpoint": 3}[test]
    if facing_y:
        robot, cases = ROBOT, FACING_CASES[:4]
        segs = _world([c[0] for c in cases])
    else:
        robot, cases = Pose(1.0, -2.0, 0.0), FACING_CASES
        segs = np.array([c[0] for c in cases]) + np.array([1.0, -2.0, 1.0, -2.0])
    want = [c[col] for c in cases]
    assert facing_mask(segs, robot, test).tolist() == want  # type: ignore[arg-type]
    assert facing_seen_mask(segs, robot, test, "any").tolist() == want  # type: ignore[arg-type]


def test_seen_side_is_the_robots_strict_left_of_each_directed_surface() -> None:
    """Robot at (1, −2). Walking from (3, 0) to (3, −4) (direction −y) one's left is +x:
    the robot (x = 1) is on the right. Reversed, (3, −4) → (3, 0), it is on the left. A
    surface through the robot: neither. From (−1, 0) to (−1, −4): left is +x, the robot."""
    segs = np.array(
        [
            [3.0, 0.0, 3.0, -4.0],  # robot on its right
            [3.0, -4.0, 3.0, 0.0],  # robot on its left
            [0.0, -2.0, 2.0, -2.0],  # robot on the line itself
            [-1.0, 0.0, -1.0, -4.0],  # going −y at x = −1: left is +x, the robot
        ]
    )
    want = [False, True, False, True]
    assert seen_side_mask(segs, ROBOT).tolist() == want
    # With seen_side="front" the facing test is and-ed with it (all four "any_endpoint"
    # in front? the third lies on the axis: not in front).
    front = facing_mask(segs, ROBOT, "any_endpoint") & np.array(want)
    assert facing_seen_mask(segs, ROBOT, "any_endpoint", "front").tolist() == front.tolist()
    assert front.tolist() == [False, True, False, True]


def test_in_range_counts_both_endpoints_and_the_reach_itself() -> None:
    """Reach 5 m from (1, −2): (4, 2) is exactly 5 m away (3-4-5), (5, 1) is 5 m too,
    (1, 3.01) is 5.01 m."""
    segs = np.array(
        [
            [4.0, 2.0, 5.0, 1.0],  # both exactly at the reach
            [1.0, -2.0, 1.0, 3.01],  # second end just beyond
            [1.0, 3.01, 1.0, -2.0],  # first end just beyond
            [-2.0, -6.0, 1.0, -2.0],  # (−2, −6): 5 m exactly, the other at the robot
            [-2.0, -7.0, 1.0, -2.0],  # (−2, −7): √34 > 5
        ]
    )
    assert in_range_mask(segs, ROBOT, 5.0).tolist() == [True, False, False, True, False]
    assert in_range_mask(segs, ROBOT, 6.0).tolist() == [True, True, True, True, True]


@pytest.mark.parametrize("backend", SHARE_BACKENDS)
def test_visible_share_by_similar_triangles(backend: str) -> None:
    """The view is one wall 2 m ahead, 2 m wide (local x = 2, y ∈ [−1, 1]). A map
    surface 2.3 m ahead and 4 m wide has 8 sample points at y = ±0.25, ±0.75, ±1.25,
    ±1.75; a sight line to (2.3, y) crosses x = 2 at y·2/2.3, inside the wall for
    |y| ≤ 1.15: 4 of 8 seen, each 0.3/2.3 of its ray's length beyond the wall
    (0.30–0.32 m), so with 0.5 m allowed the share is 0.5 and with 0.1 m it is 0. A surface in
    front of the wall (x = 1.5, |y| ≤ 0.5) is wholly seen; one behind the robot or beside
    the view not at all."""
    view = _world([(2.0, -1.0, 2.0, 1.0)])
    segs = _world(
        [
            (2.3, -2.0, 2.3, 2.0),
            (1.5, -0.5, 1.5, 0.5),
            (-2.0, -1.0, -2.0, 1.0),
            (1.0, 3.0, 2.0, 4.0),
        ]
    )
    got = visible_share(segs, view, ROBOT, 0.5, backend=backend)
    np.testing.assert_array_equal(got, [0.5, 1.0, 0.0, 0.0])
    got = visible_share(segs, view, ROBOT, 0.1, backend=backend)
    np.testing.assert_array_equal(got, [0.0, 1.0, 0.0, 0.0])
    # 4 samples on the wide surface: y = ±0.5, ±1.5 → 2 of 4 seen.
    got = visible_share(segs[:1], view, ROBOT, 0.5, samples=4, backend=backend)
    np.testing.assert_array_equal(got, [0.5])
    assert visible_share(segs[:0], view, ROBOT, 0.5, backend=backend).shape == (0,)
    np.testing.assert_array_equal(
        visible_share(segs, view[:0], ROBOT, 0.5, backend=backend), np.zeros(4)
    )


@pytest.mark.parametrize("backend", SHARE_BACKENDS)
def test_visible_share_of_a_surface_seen_through_two_view_surfaces(backend: str) -> None:
    """Two view walls with a doorway between (local y ∈ [−2, −0.4] and [0.4, 2] at x = 2):
    a surface at x = 3, y ∈ [−2, 2] (8 samples at ±0.25 … ±1.75) is seen where the
    sight line crosses a wall: |y|·2/3 ∈ [0.4, 2] → |y| ≥ 0.6: 6 of 8 (1 m beyond at
    most 1.2 m along the ray, allowed 2 m)."""
    view = _world([(2.0, -2.0, 2.0, -0.4), (2.0, 0.4, 2.0, 2.0)])
    segs = _world([(3.0, -2.0, 3.0, 2.0)])
    got = visible_share(segs, view, ROBOT, 2.0, backend=backend)
    np.testing.assert_array_equal(got, [0.75])


@pytest.mark.parametrize("heading_deg", [0.0, 90.0, -135.0])
def test_forward_view_polygon_is_the_buffer_clipped_at_the_lateral_axis(
    heading_deg: float,
) -> None:
    """P (``enlarge="forward"``) equals the 0.5 m buffer of the triangle (viewpoint, the
    wall's ends) cut by a 100 m box in front of the robot, turned and moved by shapely's
    affinity functions: the same area, and their symmetric difference has no area."""
    robot = Pose(1.0, -2.0, math.radians(heading_deg))
    local = [(2.0, -1.0, 2.0, 1.5), (2.0, 1.5, 0.5, 3.0)]
    c, s = math.cos(robot.theta), math.sin(robot.theta)
    segs = np.array(
        [
            [1.0 + c * x0 - s * y0, -2.0 + s * x0 + c * y0, 1.0 + c * x1 - s * y1,
             -2.0 + s * x1 + c * y1]
            for x0, y0, x1, y1 in local
        ]
    )  # fmt: skip
    got = view_polygon(segs, robot, 0.5, "forward")
    ring = [(robot.x, robot.y), *segs.reshape(-1, 2).tolist()]
    front = affinity.translate(
        affinity.rotate(shapely.box(0.0, -100.0, 100.0, 100.0), heading_deg, origin=(0, 0)),
        robot.x,
        robot.y,
    )
    want = shapely.Polygon(ring).buffer(0.5, quad_segs=16).intersection(front)
    assert got.area == pytest.approx(want.area, rel=1e-9)
    assert shapely.symmetric_difference(got, want).area == pytest.approx(0.0, abs=1e-9)
    # Nothing behind the robot: a point 0.3 m behind is outside, 0.3 m ahead inside.
    assert not got.contains(shapely.Point(robot.x - 0.3 * c, robot.y - 0.3 * s))
    assert got.contains(shapely.Point(robot.x + 0.3 * c, robot.y + 0.3 * s))


@pytest.mark.parametrize("backend", SHARE_BACKENDS)
def test_a_view_surface_through_the_viewpoint_hides_nothing(backend: str) -> None:
    """A view surface passing through the robot itself (local y ∈ [−1, 1] at x = 0) is
    met by every sight line at the robot, not in front of it: a surface 0.3 m ahead is
    not seen through it, though it lies within the 0.5 m allowed beyond."""
    view = _world([(0.0, -1.0, 0.0, 1.0)])
    segs = _world([(0.3, -0.1, 0.3, 0.1)])
    np.testing.assert_array_equal(visible_share(segs, view, ROBOT, 0.5, backend=backend), [0.0])


def test_quick_touch_box_grows_the_ring_box_each_way() -> None:
    """Ring (0, 0), (2, 1), (1, 3) and enlarge 0.5 m: the box grows by 1.011·0.5 m
    (+1 µm) on all four sides."""
    from albot2d.mapping.albot1.deletion import quick_touch_box

    grow = 1.011 * 0.5 + 1e-6
    got = quick_touch_box(np.array([[0.0, 0.0], [2.0, 1.0], [1.0, 3.0]]), 0.5)
    assert got == pytest.approx([-grow, -grow, 2.0 + grow, 3.0 + grow], abs=1e-12)


def test_an_empty_views_polygon_is_a_disc_of_sixty_four_sides() -> None:
    """No surfaces: P is the viewpoint buffered by 0.5 m with 16 segments a quadrant, a
    regular 64-gon of area ½·64·r²·sin(2π/64)."""
    got = view_polygon(np.zeros((0, 4)), ROBOT, 0.5, "all_round")
    assert got.area == pytest.approx(0.5 * 64 * 0.25 * math.sin(2 * math.pi / 64), rel=1e-9)
    assert got.contains(shapely.Point(ROBOT.x + 0.49, ROBOT.y))


def test_forward_clip_reaches_the_farthest_point_from_a_robot_below_the_origin() -> None:
    """The robot at (0, −1) facing +y, one wall 4 m ahead (y = 3): P is the triangle
    buffered by 0.5 m, cut at the lateral axis y = −1 only (its far side at y = 3.5 is
    kept whole: the clipping box must reach past the wall, measured from the robot)."""
    robot = Pose(0.0, -1.0, math.pi / 2)
    segs = np.array([[0.5, 3.0, -0.5, 3.0]])
    got = view_polygon(segs, robot, 0.5, "forward")
    want = shapely.Polygon([(0.0, -1.0), (0.5, 3.0), (-0.5, 3.0)]).buffer(0.5, quad_segs=16)
    want = want.intersection(shapely.box(-100.0, -1.0, 100.0, 100.0))
    assert got.area == pytest.approx(want.area, rel=1e-9)
    assert got.bounds[3] == pytest.approx(3.5, abs=1e-9)


def test_touching_mask_tests_the_forward_ray_even_when_p_is_empty() -> None:
    import shapely

    from albot2d.geometry import Pose
    from albot2d.mapping.albot1.deletion import touching_mask

    segs = np.array([[1.0, -0.5, 1.0, 0.5], [1.0, 2.0, 1.0, 3.0]])  # across / off the ray
    empty = shapely.Polygon()
    assert touching_mask(empty, segs, Pose(), forward_ray_m=2.0).tolist() == [True, False]
    assert touching_mask(empty, segs, Pose(), forward_ray_m=0.0).tolist() == [False, False]
    assert touching_mask(empty, segs, Pose(0.0, 0.0, math.pi), 2.0).tolist() == [False, False]
