"""Trackable-surface criteria and RTSV (algorithm #1) on views of exactly known geometry."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from albot2d.errors import InputError
from albot2d.geometry import Pose, point_segment_distance
from albot2d.perception import (
    Surfaces,
    TrackedSurfaces,
    TrackingParams,
    extract_surfaces,
    match_surfaces,
    rtsv,
    start_tracking,
    trackable_mask,
)
from tests.perception_helpers import box, scan_of

small_increments = st.builds(
    Pose,
    st.floats(-0.6, 0.6),
    st.floats(-0.6, 0.6),
    st.floats(-0.5, 0.5),
)


def polar(r: float, bearing_deg: float) -> tuple[float, float]:
    b = math.radians(bearing_deg)
    return r * math.cos(b), r * math.sin(b)


def star_view() -> Surfaces:
    """Six trackable surfaces around the robot, at directions at least 25° apart."""
    segs, occ = [], []
    for k, (r, bearing, direction, length) in enumerate(
        [
            (3.0, -80, 10, 1.2),
            (2.5, -40, 120, 0.9),
            (4.0, -5, 85, 2.0),
            (3.5, 30, 150, 1.0),
            (2.0, 60, 40, 0.7),
            (5.0, 100, 180 + 65, 1.5),
        ]
    ):
        cx, cy = polar(r, bearing)
        dx, dy = polar(0.5 * length, direction)
        segs.append([cx - dx, cy - dy, cx + dx, cy + dy])
        occ.append([k % 3 == 0, k % 3 == 1])  # mixed flags, never both occluded
    return Surfaces.from_segments(np.array(segs), np.array(occ))


def moved(view: Surfaces, increment: Pose) -> Surfaces:
    """The same surfaces seen after the robot moved by ``increment``."""
    return view.transformed(increment.inverse().as_array())


# --- parameters and criteria --------------------------------------------------------------


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("min_length_m", -0.1),
        ("min_view_angle_deg", 200.0),
        ("match_angle_deg", 0.0),
        ("match_distance_m", float("inf")),
        ("line_distance_fallback", "yes"),
    ],
)
def test_bad_params_name_field_and_value(field: str, value: object) -> None:
    with pytest.raises(InputError, match=rf"{field}.*{value!r}"):
        TrackingParams(**{field: value})


def test_length_must_be_strictly_over_the_minimum() -> None:
    exactly = [3.0, -0.2, 3.0, 0.2]  # 0.4 m exactly (0.2 + 0.2 is exact in floats)
    longer = [3.0, -0.2, 3.0, 0.2 + 1e-9]
    mask = trackable_mask(Surfaces.from_segments([exactly, longer]))
    assert mask.tolist() == [False, True]
    assert not trackable_mask(Surfaces.from_segments([longer]), TrackingParams(min_length_m=0.5))[0]


def test_view_angle_boundary() -> None:
    def seen_under(angle_deg: float) -> list[float]:
        return [*polar(5.0, 20.0), *polar(20.0, 20.0 + angle_deg)]

    surfaces = Surfaces.from_segments([seen_under(3.0 + 1e-7), seen_under(3.0 - 1e-7)])
    assert surfaces.lengths_m.min() > 10.0
    assert trackable_mask(surfaces).tolist() == [True, False]
    looser = TrackingParams(min_view_angle_deg=2.0)
    assert trackable_mask(surfaces, looser).tolist() == [True, True]


def test_at_least_one_endpoint_must_be_unoccluded() -> None:
    seg = [3.0, -1.0, 3.0, 1.0]
    flags = [[True, True], [True, False], [False, True], [False, False]]
    surfaces = Surfaces.from_segments([seg] * 4, flags)
    assert trackable_mask(surfaces).tolist() == [False, True, True, True]


def test_start_tracking_takes_the_trackable_surfaces_with_fresh_ids() -> None:
    view = star_view()
    short = Surfaces.from_segments([[1.0, 0.0, 1.0, 0.3]])
    both = Surfaces(
        np.vstack([view.segments, short.segments]),
        np.vstack([view.occluded, short.occluded]),
        np.vstack([view.beams, short.beams]),
    )
    tracked = start_tracking(both, first_id=7)
    assert tracked.ids.tolist() == list(range(7, 13))
    np.testing.assert_array_equal(tracked.local.segments, view.segments)
    np.testing.assert_array_equal(tracked.current.segments, view.segments)
    assert tracked.next_id == 13
    assert TrackedSurfaces.empty().next_id == 0


def test_tracked_surfaces_validate_their_arrays() -> None:
    view = star_view()
    with pytest.raises(ValueError, match="one id per surface"):
        TrackedSurfaces(np.arange(5), view, view)
    with pytest.raises(ValueError, match="unique"):
        TrackedSurfaces(np.zeros(6, np.int64), view, view)


# --- RTSV -----------------------------------------------------------------------------------


@given(small_increments)
def test_known_increment_tracks_every_surface_trackable_in_both_views(increment: Pose) -> None:
    view = star_view()
    tracked = start_tracking(view, first_id=100)
    new_view = moved(view, increment)
    # Shuffle the new view so identities must come from matching, not from order.
    perm = np.random.default_rng(0).permutation(len(new_view))
    new_view = new_view.select(perm)
    survivors, info = rtsv(tracked, new_view, increment)
    still = trackable_mask(new_view)
    expected = np.sort(perm[still])  # tracked indices whose surface is still trackable
    assert info.tracked_index.tolist() == expected.tolist()
    assert survivors.ids.tolist() == (100 + expected).tolist()
    np.testing.assert_array_equal(survivors.local.segments, view.segments[expected])
    np.testing.assert_allclose(
        survivors.current.segments,
        view.select(expected).transformed(increment.inverse().as_array()).segments,
        atol=1e-9,
    )
    np.testing.assert_allclose(info.distance_m, 0.0, atol=1e-9)


def test_trackable_mask_is_kept_with_the_view_per_parameters() -> None:
    view = star_view()
    params, looser = TrackingParams(), TrackingParams(min_length_m=0.0, min_view_angle_deg=0.0)
    first = trackable_mask(view, params)
    assert trackable_mask(view, params) is first and not first.flags.writeable
    other = trackable_mask(view, looser)  # other parameters: computed, not the kept one
    assert other is not first and other.sum() >= first.sum()
    fresh = Surfaces(view.segments, view.occluded, view.beams, view.uncertain)
    np.testing.assert_array_equal(trackable_mask(fresh, params), first)


def test_survivors_share_the_tracker_state_only_when_none_is_lost() -> None:
    """RTSV skips copying ids and local geometry when every tracked surface survives; either
    way the survivors are what the checked constructor builds from the match, read-only."""
    view = star_view()
    tracked = start_tracking(view, first_id=7)
    assert tracked.ids.tolist() == list(range(7, 7 + len(tracked)))
    assert not tracked.ids.flags.writeable
    TrackedSurfaces(tracked.ids, tracked.local, tracked.current)  # passes its checks
    increment = Pose(0.1, 0.0, 0.01)
    all_kept, info = rtsv(tracked, moved(view, increment), increment)
    assert len(all_kept) == len(tracked) and all_kept.local is tracked.local
    lost_one = moved(view, increment).select(np.arange(1, len(view)))  # first surface gone
    some_kept, info_some = rtsv(tracked, lost_one, increment)
    assert 0 < len(some_kept) < len(tracked)
    for got, inf, new_view in ((all_kept, info, moved(view, increment)),
                               (some_kept, info_some, lost_one)):  # fmt: skip
        want = TrackedSurfaces(tracked.ids[inf.tracked_index],
                               tracked.local.select(inf.tracked_index),
                               new_view.select(inf.view_index))  # fmt: skip
        np.testing.assert_array_equal(got.ids, want.ids)
        for a, b in ((got.local, want.local), (got.current, want.current)):
            np.testing.assert_array_equal(a.segments, b.segments)
            np.testing.assert_array_equal(a.occluded, b.occluded)
            np.testing.assert_array_equal(a.beams, b.beams)
        assert not got.ids.flags.writeable and not got.local.segments.flags.writeable


def test_ten_degree_heading_error_loses_every_surface() -> None:
    view, increment = star_view(), Pose(0.3, 0.1, 0.2)
    tracked, new_view = start_tracking(view), moved(view, increment)
    wrong = increment.compose(Pose(0.0, 0.0, math.radians(10.0)))
    assert len(rtsv(tracked, new_view, wrong)[0]) == 0
    # The angle gate is what rejects them: widened, they are found again.
    wide = TrackingParams(match_angle_deg=12.0, match_distance_m=2.0)
    assert len(rtsv(tracked, new_view, wrong, wide)[0]) == len(view)
    slight = increment.compose(Pose(0.0, 0.0, math.radians(1.0)))
    assert len(rtsv(tracked, new_view, slight)[0]) == len(view)


@pytest.mark.parametrize("direction_deg", [0.0, 90.0, 200.0])
def test_half_metre_position_error_loses_every_surface(direction_deg: float) -> None:
    view, increment = star_view(), Pose(0.3, 0.1, 0.2)
    tracked, new_view = start_tracking(view), moved(view, increment)
    wrong = increment.compose(Pose(*polar(0.5, direction_deg), 0.0))
    assert len(rtsv(tracked, new_view, wrong)[0]) == 0
    wide = TrackingParams(match_distance_m=0.55)
    assert len(rtsv(tracked, new_view, wrong, wide)[0]) == len(view)
    near = increment.compose(Pose(*polar(0.3, direction_deg), 0.0))
    assert len(rtsv(tracked, new_view, near)[0]) == len(view)


def test_matching_is_one_to_one_and_prefers_the_nearest() -> None:
    wall = np.array([[3.0, -1.0, 3.0, 1.0]])
    shifted = wall + np.array([0.0, 0.1, 0.0, 0.1])
    farther = wall + np.array([0.0, 0.25, 0.0, 0.25])
    tracked = start_tracking(Surfaces.from_segments(wall))
    view = Surfaces.from_segments(np.vstack([farther, shifted]))
    survivors, info = rtsv(tracked, view, Pose())
    assert info.view_index.tolist() == [1]
    np.testing.assert_allclose(info.distance_m, [0.1])
    # Two tracked surfaces near one candidate: only the nearer keeps it.
    two = start_tracking(Surfaces.from_segments(np.vstack([farther, wall])))
    survivors, info = rtsv(two, Surfaces.from_segments(shifted), Pose())
    assert info.tracked_index.tolist() == [1] and survivors.ids.tolist() == [1]


def test_only_unoccluded_corresponding_endpoints_count() -> None:
    wall = np.array([[3.0, -1.0, 3.0, 1.0]])
    tracked = start_tracking(Surfaces.from_segments(wall, [[False, True]]))
    # Endpoint 0 moved 0.5 m along the wall (it is a real corner in neither view
    # after the move), endpoint 1 is the same but occluded in the old view.
    grown = np.array([[3.0, -1.5, 3.0, 1.0]])
    view = Surfaces.from_segments(grown, [[False, False]])
    assert len(rtsv(tracked, view, Pose())[0]) == 0
    # Endpoint 0 occluded in the new view: no corner seen in both, no match …
    view = Surfaces.from_segments(grown, [[True, False]])
    assert len(rtsv(tracked, view, Pose())[0]) == 0
    # … unless such pairs fall back to the distance from the corners to the other line.
    fallback = TrackingParams(line_distance_fallback=True)
    assert len(rtsv(tracked, view, Pose(), fallback)[0]) == 1


def test_only_trackable_view_surfaces_are_candidates() -> None:
    wall = np.array([[3.0, -1.0, 3.0, 1.0]])
    tracked = start_tracking(Surfaces.from_segments(wall))
    all_occluded = Surfaces.from_segments(wall, [[True, True]])
    assert len(rtsv(tracked, all_occluded, Pose())[0]) == 0
    short = Surfaces.from_segments([[3.0, -1.0, 3.0, -0.65]])
    assert len(rtsv(tracked, short, Pose())[0]) == 0
    assert len(rtsv(tracked, short, Pose(), candidates=[True])[0]) == 1
    assert len(rtsv(TrackedSurfaces.empty(), short, Pose())[0]) == 0


@given(
    small_increments,
    st.builds(Pose, st.floats(-20, 20), st.floats(-20, 20), st.floats(-math.pi, math.pi)),
)
def test_tracking_does_not_depend_on_the_frame(increment: Pose, frame: Pose) -> None:
    # Express both views in frames offset by the same rigid transform from their robot
    # frames: the increment between them changes accordingly, the matches must not.
    view = star_view()
    noisy = moved(view, increment.compose(Pose(0.05, -0.03, 0.02)))  # imperfect odometry
    tracked = start_tracking(view)
    base, base_info = rtsv(tracked, noisy, increment)
    to_frame = frame.inverse().as_array()
    tracked_f = TrackedSurfaces(tracked.ids, tracked.local, tracked.current.transformed(to_frame))
    noisy_f = noisy.transformed(to_frame)
    increment_f = frame.inverse().compose(increment).compose(frame)
    same, info = rtsv(tracked_f, noisy_f, increment_f, candidates=base_info.candidates)
    assert same.ids.tolist() == base.ids.tolist()
    assert info.view_index.tolist() == base_info.view_index.tolist()
    np.testing.assert_allclose(info.distance_m, base_info.distance_m, atol=1e-9)


def test_match_surfaces_checks_the_candidate_mask() -> None:
    view = star_view()
    with pytest.raises(ValueError, match="candidates"):
        match_surfaces(view, view, candidates=[True])


# --- end to end on exact scans --------------------------------------------------------------


OFFICE = np.vstack(
    [
        box(0.0, 0.0, 6.0, 3.0),
        box(2.0, 1.5, 0.6, 0.4),
        box(-1.5, -1.8, 0.5, 0.5),
        box(3.5, -1.0, 0.3, 0.8),
        [[-4.0, 3.0, -4.0, 1.2]],  # a partition wall
    ]
)


@given(small_increments, st.integers(0, 2**32 - 1))
def test_scans_from_two_poses_track_the_same_walls(increment: Pose, seed: int) -> None:
    start = Pose(-2.5, 0.3, 0.1)
    rng = np.random.default_rng(seed)
    first = extract_surfaces(scan_of(OFFICE, start, noise_sigma=0.005, rng=rng))
    second = extract_surfaces(scan_of(OFFICE, start.compose(increment), noise_sigma=0.005, rng=rng))
    tracked = start_tracking(first)
    survivors, _ = rtsv(tracked, second, increment)
    assert len(tracked) >= 4
    assert len(survivors) >= 2
    # Every match is the same physical wall: both observations lie on one world segment.
    world_local = survivors.local.transformed(start.as_array()).segments
    world_now = survivors.current.transformed(start.compose(increment).as_array()).segments
    d_local = point_segment_distance(world_local.reshape(-1, 2), OFFICE).reshape(-1, 2, len(OFFICE))
    d_now = point_segment_distance(world_now.reshape(-1, 2), OFFICE).reshape(-1, 2, len(OFFICE))
    same_wall = (d_local.max(axis=1) < 0.03) & (d_now.max(axis=1) < 0.03)
    assert same_wall.any(axis=1).all()
