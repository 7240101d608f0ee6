"""Algorithm #5's "could see" readings on constructed views whose answer is known.

A robot at the origin faces +x; the incoming view is a wall 5 m ahead (surfaces in scan
order, so the robot is on their left). Which old surfaces the robot could see is worked
out by hand for each case.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from albot2d.errors import InputError
from albot2d.evaluation.checks import invariants as inv
from albot2d.geometry import Pose, transform_segments
from albot2d.mapping import Albot1
from albot2d.mapping.albot1.deletion import seen_side_mask, visible_share
from albot2d.mapping.albot1.global_map import GlobalMap, GlobalMapParams

WALL = np.array([[5.0, -2.0, 5.0, 2.0]])  # scan order: lower bearing first
# Two pieces of that wall with a doorway between y = -0.5 and 0.5.
DOORWAY = np.array([[5.0, -2.0, 5.0, -0.5], [5.0, 0.5, 5.0, 2.0]])
VISIBLE = GlobalMapParams.preset("visible")


def seg(x0: float, y0: float, x1: float, y1: float) -> np.ndarray:
    return np.array([[x0, y0, x1, y1]], dtype=float)


def test_visible_share_of_known_cases() -> None:
    cases = {
        "old copy 0.3 m behind the wall": (seg(5.3, -1, 5.3, 1), 1.0),
        "a wall 1 m behind the incoming one": (seg(6.0, -1, 6.0, 1), 0.0),
        "in the free space in front": (seg(3.0, -1, 3.0, 1), 1.0),
        # At x = 3 the fan of the wall spans |y| <= 1.2; the 8 samples of y in [-1, 5] are
        # at -0.625, 0.125, 0.875, 1.625, … so 3 of 8 are in it.
        "partly in the fan": (seg(3.0, -1, 3.0, 5), 3 / 8),
        "behind the robot": (seg(-3.0, -1, -3.0, 1), 0.0),
    }
    segs = np.vstack([s for s, _ in cases.values()])
    share = visible_share(segs, WALL, Pose(), 0.5, 8)
    for (name, (_, want)), got in zip(cases.items(), share, strict=True):
        assert got == pytest.approx(want), name


def test_a_doorway_is_not_seen_through_but_the_joined_polygon_covers_it() -> None:
    """An old surface in the doorway, just short of the wall line: P (endpoints joined)
    contains it, so ``in_view`` deletes it; no sight line meets a view surface there, so
    ``visible`` keeps it."""
    in_doorway = seg(4.8, -0.2, 4.8, 0.2)
    assert visible_share(in_doorway, DOORWAY, Pose(), 0.5, 8)[0] == 0.0
    for rule, kept in (("paper", 0), ("visible", 1)):
        g = GlobalMap(GlobalMapParams.preset(rule))
        g.insert(in_doorway, 0)
        g.add_view(DOORWAY, 1, Pose())
        assert int(np.count_nonzero(g.snapshot().map_ids == 0)) == kept, rule


def test_visibility_turns_with_the_robot() -> None:
    turned = Pose(1.0, 1.0, np.pi / 2)  # at (1, 1) facing +y: the wall is y = 6
    wall = np.array([[3.0, 6.0, -1.0, 6.0]])  # scan order from the robot's right
    share = visible_share(
        np.vstack([seg(0, 6.3, 2, 6.3), seg(0, 7.0, 2, 7.0)]), wall, turned, 0.5, 4
    )
    np.testing.assert_allclose(share, [1.0, 0.0])


def test_seen_side_is_the_left_of_a_surface_in_scan_order() -> None:
    facing = WALL[0]
    back = facing[[2, 3, 0, 1]]  # the same line seen from beyond x = 5
    np.testing.assert_array_equal(seen_side_mask(np.vstack([facing, back]), Pose()), [True, False])
    assert not seen_side_mask(WALL, Pose(6.0, 0.0, np.pi))[0]


def test_the_far_face_of_a_wall_stays_and_the_displaced_copy_goes() -> None:
    """Old map 0 saw this wall's near face 0.3 m off (drift) and, from the far room, its
    other face 0.15 m behind it: the near copy is deleted; the far face, which the robot
    cannot see from where it is, stays with ``seen_side="front"`` and goes with ``"any"``."""
    near_copy = seg(5.3, -1.0, 5.3, 1.0)
    far_face = seg(5.15, 1.0, 5.15, -1.0)  # seen from x > 5: reversed direction
    for side, survivors in (("front", 1), ("any", 0)):
        g = GlobalMap(GlobalMapParams.preset("visible", seen_side=side))
        g.insert(np.vstack([near_copy, far_face]), 0)
        report = g.add_view(WALL, 1, Pose())
        assert report.deleted_current == 2 - survivors, side
        left = g.snapshot()
        assert int(np.count_nonzero(left.map_ids == 0)) == survivors, side
        if survivors:
            np.testing.assert_array_equal(left.segments[left.map_ids == 0], far_face)


@pytest.mark.parametrize(("min_share", "deleted"), [(0.0, 2), (0.5, 1), (1.0, 1)])
def test_min_visible_share_decides_partly_visible_surfaces(min_share: float, deleted: int) -> None:
    partly = seg(3.0, -1.0, 3.0, 5.0)  # 3/8 visible (see above)
    wholly = seg(3.0, -1.0, 3.0, 1.0)
    g = GlobalMap(GlobalMapParams.preset("visible", min_visible_share=min_share))
    g.insert(np.vstack([partly, wholly]), 0)  # the robot is on their left: seen side
    assert g.add_view(WALL, 1, Pose()).deleted_current == deleted


def test_a_revisit_still_deletes_what_it_sees_under_the_visible_rule() -> None:
    """Transience (Fig. 10): back at the start after 39 maps elsewhere, the robot deletes
    map 0's wall it sees again and keeps the out-of-view rest of the loop."""
    g = GlobalMap(VISIBLE)
    g.add_view(WALL, 0, Pose())
    for m in range(1, 40):  # 3 m apart, each behind the next robot: none deletes another
        g.add_view(np.array([[3.0 * m + 0.5, 30.0, 3.0 * m, 30.0]]), m, Pose(3.0 * m, 28.0, 0.0))
    report = g.add_view(WALL + np.array([0.2, 0.0, 0.2, 0.0]), 40, Pose(0.05, 0.0, 0.0))
    assert report.affected_maps == (0,) and report.deleted_older == 1
    assert 0 not in g.snapshot().map_ids.tolist() and len(g) == 40


def test_bad_visibility_parameters_are_refused() -> None:
    with pytest.raises(InputError, match="min_visible_share must be in"):
        GlobalMapParams(min_visible_share=1.5)
    with pytest.raises(InputError, match="seen_side must be one of"):
        GlobalMapParams(seen_side="back")  # type: ignore[arg-type]
    with pytest.raises(InputError, match="visible_samples"):
        GlobalMapParams(visible_samples=0)


@settings(max_examples=60, deadline=None)
@given(
    st.integers(0, 2**32 - 1), st.sampled_from([0.0, 0.5, 1.0]), st.sampled_from(["front", "any"])
)
def test_the_invariant_recomputed_from_the_definitions_agrees_with_the_map(
    seed: int, min_share: float, side: str
) -> None:
    """Random old surfaces around a robot, a random view in scan order: after the update,
    the invariant (its own P, facing, seen side and sight lines, via shapely) finds nothing
    the map should have deleted; and a map that skipped the deletion is caught."""
    rng = np.random.default_rng(seed)
    robot = Pose(*rng.uniform(-1, 1, 2), rng.uniform(-np.pi, np.pi))
    bearings = np.sort(rng.uniform(-1.5, 1.5, 2 * int(rng.integers(1, 6))))
    ranges = rng.uniform(1.0, 6.0, len(bearings))
    local = np.column_stack([ranges * np.cos(bearings), ranges * np.sin(bearings)])
    view = transform_segments(robot.as_array(), local.reshape(-1, 4))
    params = GlobalMapParams.preset("visible", min_visible_share=min_share, seen_side=side)
    mapper = Albot1()
    mapper.map = GlobalMap(params)
    for m in range(3):
        a = rng.uniform(-7, 7, (8, 2))
        old = np.hstack([a, a + rng.uniform(-2, 2, (8, 2))])
        mapper.map.insert(old, m)
    report = mapper.map.add_view(view, 3, robot)
    inv.check_update_deleted_facing_overlap(mapper, report, robot, view)
    if report.deleted_current + report.deleted_older:
        skipped = Albot1()
        skipped.map = GlobalMap(params)
        for m, segs in enumerate(np.split(mapper.map._segments[:24], 3)):
            skipped.map.insert(segs, m)
        skipped.map.insert(view, 3)  # added without deleting anything
        with pytest.raises(inv.InvariantError, match="update_deletes_facing_overlap"):
            inv.check_update_deleted_facing_overlap(skipped, report, robot, view)
