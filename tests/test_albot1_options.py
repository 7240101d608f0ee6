"""The authors' code's behaviours as named options, each on a hand-built case whose answer
is known: key-endpoint matching, the fitness order and floor, heuristic 2 by fitness,
per-view localisation with the odometry fallback, the presets and ``albot1[...]`` names."""

from __future__ import annotations

import math

import numpy as np
import pytest

from albot2d.errors import InputError
from albot2d.geometry import Pose
from albot2d.mapping.albot1.mapper import Albot1, Albot1Params
from albot2d.mapping.albot1.triangulation import TriangulationParams, triangulate
from albot2d.mapping.registry import mapper_factory, resolve_mappers
from albot2d.perception import Surfaces, TrackingParams, rtsv, start_tracking
from albot2d.perception.tracking import key_endpoints, match_fitness

WALL = np.array([[3.0, -1.0, 3.0, 1.0]])


def test_key_endpoint_is_the_real_one_or_the_nearer() -> None:
    segs = np.array([[3.0, -1.0, 3.0, 2.0], [3.0, -1.0, 3.0, 2.0], [1.0, 0.0, 5.0, 0.0]])
    occ = np.array([[True, False], [False, False], [False, False]])
    assert key_endpoints(Surfaces.from_segments(segs, occ)).tolist() == [1, 0, 0]


def test_key_endpoint_matching_ignores_the_other_end() -> None:
    """Endpoint 1 (key: endpoint 0 is occluded) stays put; endpoint 0 moves 0.6 m: the
    corresponding-endpoints rule finds the pair by endpoint 1 as well, but the key rule
    checks only the key end, and fails when that one moves while the other stays."""
    tracked = start_tracking(Surfaces.from_segments(WALL, [[True, False]]))
    grown = Surfaces.from_segments(np.array([[3.0, -1.6, 3.0, 1.0]]), [[False, False]])
    key = TrackingParams(match_endpoint="key")
    assert len(rtsv(tracked, grown, Pose(), key)[0]) == 1
    shrunk_key_end = Surfaces.from_segments(np.array([[3.0, -1.0, 3.0, 0.45]]), [[False, False]])
    assert len(rtsv(tracked, shrunk_key_end, Pose(), key)[0]) == 0
    # Whether the candidate's key end is real is not checked by the key rule …
    occluded_there = Surfaces.from_segments(WALL, [[False, True]])
    assert len(rtsv(tracked, occluded_there, Pose(), key)[0]) == 1
    # … but is by the corresponding-endpoints rule (no real corner seen in both).
    assert len(rtsv(tracked, occluded_there, Pose())[0]) == 0


def test_fitness_follows_the_authors_formula() -> None:
    view = Surfaces.from_segments(np.array([[4.0, -0.5, 4.0, 0.5]]))
    # length 1000 mm, d 100 mm, 1 degree, range 4000 mm: 1000 * 300 * 4 / 4000 = 300
    f = match_fitness(view, view, np.array([[0.1]]), np.array([[math.radians(1.0)]]))
    assert f[0, 0] == pytest.approx(300.0)


def test_fitness_floor_forces_an_update() -> None:
    """A short, far surface matched 0.35 m off has fitness 450·50·5/6000 ≈ 19 < 80."""
    far = Surfaces.from_segments(np.array([[6.0, -0.225, 6.0, 0.225]]))
    tracked = start_tracking(far, TrackingParams(min_length_m=0.4))
    off = Surfaces.from_segments(np.array([[6.0, 0.125, 6.0, 0.575]]))
    loose = TrackingParams(match_endpoint="key")
    assert len(rtsv(tracked, off, Pose(), loose)[0]) == 1
    floored = TrackingParams(match_endpoint="key", fitness_floor=80.0)
    assert len(rtsv(tracked, off, Pose(), floored)[0]) == 0


def test_fitness_order_prefers_the_longer_candidate_over_the_nearer() -> None:
    tracked = start_tracking(Surfaces.from_segments(WALL))
    near_short = np.array([[3.0, -1.0 + 0.05, 3.0, 0.0]])  # endpoint 0 5 cm off, 0.95 m long
    far_long = np.array([[3.0, -1.2, 3.0, 1.0]])  # endpoint 0 20 cm off, 2.2 m long
    view = Surfaces.from_segments(np.vstack([near_short, far_long]))
    params = TrackingParams(match_endpoint="key")
    by_distance = rtsv(tracked, view, Pose(), params)[1]
    by_fitness = rtsv(
        tracked, view, Pose(), TrackingParams(match_endpoint="key", match_order="fitness")
    )[1]
    assert by_distance.view_index.tolist() == [0]
    assert by_fitness.view_index.tolist() == [1]


def _two_walls() -> tuple[Surfaces, Surfaces]:
    """Two corners that afford different poses: a long near wall (fit) and a short far one."""
    local = Surfaces.from_segments(
        np.array([[2.0, -2.0, 2.0, 2.0], [8.0, 3.0, 8.0, 3.45]]), [[False, True], [False, True]]
    )
    # The view is the local map seen from (0.05, 0, 0), but the far corner is 0.3 m off.
    current = local.transformed(Pose(0.05, 0.0, 0.0).inverse().as_array())
    shifted = current.segments.copy()
    shifted[1] += np.array([0.0, -0.3, 0.0, -0.3])
    return local, Surfaces.from_segments(shifted, current.occluded)


def test_heuristic_two_by_fitness_or_nearest_to_path_integration() -> None:
    local, current = _two_walls()
    pi = Pose(0.05, 0.3, 0.0)  # path integration happens to agree with the far corner
    base = TriangulationParams(heading="selected", use_outlier_heuristic=False)
    nearest = triangulate(local, current, pi, base)
    fittest = triangulate(
        local,
        current,
        pi,
        TriangulationParams(heading="selected", use_outlier_heuristic=False, choose="fitness"),
    )
    assert nearest is not None and fittest is not None
    assert nearest.y == pytest.approx(0.3, abs=1e-9)  # the far corner, nearest to PI
    assert fittest.y == pytest.approx(0.0, abs=1e-9)  # the long near wall


def test_presets_select_consistent_sets_and_refuse_unknown_names() -> None:
    paper, original = Albot1Params.preset("paper"), Albot1Params.preset("original")
    assert paper == Albot1Params()
    assert original.min_tracked == 3 and original.localise_every_view
    assert original.tracking.match_endpoint == "key" and original.tracking.fitness_floor == 80
    assert original.tracking.min_view_angle_deg == 0.0
    assert original.triangulation.choose == "fitness"
    assert original.global_map.enlarge == "radial"
    assert Albot1Params.preset("original", min_tracked=4).min_tracked == 4
    # start-stop: the paper plus the heading of views whose surfaces give no position
    assert Albot1Params.preset("start_stop") == Albot1Params(heading_fallback_surfaces=1)
    made = mapper_factory("albot1[preset=start_stop]")()
    assert made.params.heading_fallback_surfaces == 1  # type: ignore[attr-defined]
    with pytest.raises(InputError, match="valid: default, paper_literal, original, start_stop"):
        Albot1Params.preset("orignal")


def test_per_view_localisation_keeps_odometry_beyond_the_fallback() -> None:
    """A view whose triangulation is 1 m from the odometric pose keeps the odometric pose;
    within the fallback it takes the triangulated one."""
    walls = np.array(
        [
            [3.0, -2.0, 3.0, -0.5],
            [3.0, 0.5, 3.0, 2.0],
            [1.0, 2.0, 2.5, 2.0],
            [1.0, -2.0, 2.5, -2.0],
            [5.0, -3.0, 5.0, 3.0],
        ]
    )
    occ = np.zeros((len(walls), 2), bool)
    view = Surfaces.from_segments(walls, occ)
    m = Albot1(Albot1Params(localise_every_view=True))
    tracked = start_tracking(view)
    odometric = Pose(0.1, 0.0, 0.0)
    truth_view = view.transformed(Pose(0.12, 0.0, 0.0).inverse().as_array())
    tracked_now = tracked.__class__(
        tracked.ids, tracked.local, truth_view.select(np.arange(len(truth_view))[: len(tracked)])
    )
    near = m._localise_between_updates(tracked_now, odometric, 1)
    assert near.x == pytest.approx(0.12, abs=1e-6)
    far_view = view.transformed(Pose(1.1, 0.0, 0.0).inverse().as_array())
    tracked_far = tracked.__class__(
        tracked.ids, tracked.local, far_view.select(np.arange(len(far_view))[: len(tracked)])
    )
    kept = m._localise_between_updates(tracked_far, odometric, 3)
    assert kept == odometric


def test_albot1_variants_by_name() -> None:
    factories = resolve_mappers(["albot1", "albot1[deletion=v1]", "albot1[preset=original]"])
    assert list(factories) == ["albot1", "albot1[deletion=v1]", "albot1[preset=original]"]
    v1 = factories["albot1[deletion=v1]"]()
    assert isinstance(v1, Albot1) and v1.params.global_map.current_map == "touch"
    assert v1.name == "albot1[deletion=v1]"
    assert factories["albot1[preset=original]"]().params.min_tracked == 3
    assert mapper_factory("albot1[min_tracked=3]")().params.min_tracked == 3  # type: ignore[attr-defined]
    for bad in ("albot1[colour=red]", "albot1[deletion=none]", "albot1[min_tracked=x]"):
        with pytest.raises(InputError):
            mapper_factory(bad)()


def test_surface_heading_fallback_corrects_only_the_heading() -> None:
    """Tracked walls whose real ends were seen at grazing angles (``uncertain``: no precise
    position): by default the view is placed by path integration; with
    ``heading_fallback_surfaces=1`` its heading comes from the walls' directions and its
    position stays path integration's."""
    walls = np.array([[3.0, -2.0, 3.0, 2.0], [1.0, 2.0, 2.5, 2.0], [1.0, -2.0, 2.5, -2.0]])
    occ = np.zeros((len(walls), 2), bool)
    uncertain = np.ones((len(walls), 2), bool)
    view = Surfaces(walls, occ, np.full((len(walls), 2), -1), uncertain)
    truth = Pose(0.3, 0.1, math.radians(4.0))
    moved = view.transformed(truth.inverse().as_array())
    moved = Surfaces(moved.segments, occ, moved.beams, uncertain)
    odometric = Pose(0.32, 0.05, math.radians(1.0))
    for on in (False, True):
        m = Albot1(Albot1Params(heading_fallback_surfaces=int(on)))
        tracked = start_tracking(view, TrackingParams(min_view_angle_deg=0.0))
        tracked = tracked.__class__(tracked.ids, tracked.local, moved)
        pose, method = m.localise(tracked, odometric, 1)
        assert method == "path_integration"
        assert (pose.x, pose.y) == (odometric.x, odometric.y)
        expected = truth.theta if on else odometric.theta
        assert pose.theta == pytest.approx(expected, abs=1e-9)
    with pytest.raises(InputError, match="heading_fallback_surfaces"):
        Albot1Params(heading_fallback_surfaces=-1)
