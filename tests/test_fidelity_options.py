"""Named options from the error budget: which endpoints give a triangulated position
(``TriangulationParams.position_endpoint``, the authors' code's readings) and which view
surfaces RTSV may recognise (``TrackingParams.match_candidates``, an ablation)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from albot2d.errors import InputError
from albot2d.geometry import Pose
from albot2d.mapping.albot1.mapper import Albot1Params
from albot2d.mapping.albot1.triangulation import TriangulationParams, pose_affordances, triangulate
from albot2d.perception.surfaces import Surfaces

WALLS = np.array([[3.0, -2.0, 3.0, 2.0], [1.0, 2.0, 2.5, 2.0], [1.0, -2.0, 2.5, -2.0]])
TRUTH = Pose(0.3, 0.1, math.radians(4.0))
ODOMETRIC = Pose(0.32, 0.05, math.radians(1.0))


def _pair(uncertain_local: bool, occluded_local: bool) -> tuple[Surfaces, Surfaces]:
    """The same three walls in the local map and, exactly, from ``TRUTH``; the view sees
    every end unoccluded but uncertain (ends seen at grazing angles)."""
    n = len(WALLS)
    beams = np.full((n, 2), -1)
    local = Surfaces(
        WALLS, np.full((n, 2), occluded_local), beams, np.full((n, 2), uncertain_local)
    )
    moved = Surfaces.from_segments(WALLS).transformed(TRUTH.inverse().as_array())
    current = Surfaces(moved.segments, np.zeros((n, 2), bool), beams, np.ones((n, 2), bool))
    return local, current


def test_the_strict_reading_needs_a_precise_end_in_both_views() -> None:
    local, current = _pair(uncertain_local=False, occluded_local=False)
    strict = TriangulationParams()
    assert strict.position_endpoint == "both"
    assert len(pose_affordances(local, current, ODOMETRIC.theta, strict).poses) == 0
    assert triangulate(local, current, ODOMETRIC, strict) is None


@pytest.mark.parametrize("occluded_local", [False, True])
def test_the_codes_reading_takes_an_end_real_in_the_current_view(occluded_local: bool) -> None:
    # whatever the local map's end was (here even occluded), an end real in the view counts
    local, current = _pair(uncertain_local=True, occluded_local=occluded_local)
    code = TriangulationParams(position_endpoint="current_real")
    aff = pose_affordances(local, current, ODOMETRIC.theta, code)
    assert len(aff.poses) == 3
    np.testing.assert_allclose(aff.poses, np.tile(TRUTH.as_array(), (3, 1)), atol=1e-9)
    pose = triangulate(local, current, ODOMETRIC, code)
    assert pose is not None
    np.testing.assert_allclose(pose.as_array(), TRUTH.as_array(), atol=1e-9)


def test_an_occluded_end_in_the_view_never_gives_a_position() -> None:
    local, current = _pair(uncertain_local=False, occluded_local=False)
    current = Surfaces(current.segments, np.ones((3, 2), bool), current.beams, current.uncertain)
    code = TriangulationParams(position_endpoint="current_real")
    assert len(pose_affordances(local, current, ODOMETRIC.theta, code).poses) == 0


@pytest.mark.parametrize("reverse_current", [False, True])
def test_the_programs_reading_takes_the_tracked_surfaces_key_end(reverse_current: bool) -> None:
    """Key end real in the local map (end 0; end 1 occluded); in the view every end is
    occluded, so only ``local_key`` affords a position, and the right one even when the
    view lists the wall's ends the other way round (a flipped direction)."""
    n = len(WALLS)
    beams = np.full((n, 2), -1)
    occ = np.tile([False, True], (n, 1))
    local = Surfaces(WALLS, occ, beams, np.zeros((n, 2), bool))
    moved = Surfaces.from_segments(WALLS).transformed(TRUTH.inverse().as_array()).segments
    if reverse_current:
        moved = moved[:, [2, 3, 0, 1]]
    current = Surfaces(moved, np.ones((n, 2), bool), beams, np.zeros((n, 2), bool))
    for mode, expected in (("both", 0), ("current_real", 0), ("local_key", 3)):
        params = TriangulationParams(position_endpoint=mode)  # type: ignore[arg-type]
        aff = pose_affordances(local, current, ODOMETRIC.theta, params)
        assert len(aff.poses) == expected
    aff = pose_affordances(
        local, current, ODOMETRIC.theta, TriangulationParams(position_endpoint="local_key")
    )
    np.testing.assert_allclose(aff.poses, np.tile(TRUTH.as_array(), (n, 1)), atol=1e-9)
    np.testing.assert_allclose(aff.local_points, WALLS[:, :2])  # end 0: the real one


def test_the_original_preset_uses_the_codes_reading_and_bad_values_are_refused() -> None:
    assert Albot1Params.preset("original").triangulation.position_endpoint == "local_key"
    assert Albot1Params.preset("paper").triangulation.position_endpoint == "both"
    with pytest.raises(InputError, match="position_endpoint"):
        TriangulationParams(position_endpoint="key")  # type: ignore[arg-type]


def test_the_option_by_mapper_name() -> None:
    from albot2d.mapping.registry import mapper_factory

    made = mapper_factory("albot1[position_endpoint=current_real]")()
    assert made.params.triangulation.position_endpoint == "current_real"  # type: ignore[attr-defined]
    assert made.params.triangulation.choose == "nearest_to_pi"  # type: ignore[attr-defined]
    with pytest.raises(InputError, match="position_endpoint"):
        mapper_factory("albot1[position_endpoint=nearest]")()


def test_rtsv_candidates_all_recognises_a_wall_now_seen_edge_on() -> None:
    """A wall tracked from the local map, now seen under 2° (not trackable in the new
    view): lost with the paper's trackable candidates, recognised by the ``all``
    ablation."""
    from albot2d.mapping.registry import mapper_factory
    from albot2d.perception import rtsv, start_tracking
    from albot2d.perception.tracking import TrackingParams, trackable_mask, view_angles_rad

    # a wall 1 m long whose near end (a real corner) is at (2, 1): seen broadside first
    local = Surfaces.from_segments(np.array([[2.0, 1.0, 2.0, 2.0]]), np.array([[False, True]]))
    # the robot moves to (1.98, 0) turned so the wall lies almost along its line of sight
    move = Pose(1.98, 0.0, math.radians(90.0))
    seen = local.transformed(move.inverse().as_array())
    assert np.degrees(view_angles_rad(seen))[0] < 1.0 and not trackable_mask(seen)[0]
    for mode, survives in (("trackable", 0), ("all", 1)):
        params = TrackingParams(match_candidates=mode)  # type: ignore[arg-type]
        tracked = start_tracking(local, params)
        assert len(tracked) == 1
        after, _ = rtsv(tracked, seen, move, params)
        assert len(after) == survives
    made = mapper_factory("albot1[match_candidates=all]")()
    assert made.params.tracking.match_candidates == "all"  # type: ignore[attr-defined]
    with pytest.raises(InputError, match="match_candidates"):
        TrackingParams(match_candidates="some")  # type: ignore[arg-type]
