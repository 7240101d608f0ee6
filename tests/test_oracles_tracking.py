"""RTSV's matching against distances and matches worked out by hand, on the numpy
reference (``backend="numpy"``, no environment variable) and the compiled matcher alike
where it covers the settings; the options only the reference implements (key endpoints,
the endpoint-to-segment fallback, fitness order) by hand too.

The scene: three predicted surfaces and four view surfaces, all in one frame, with the
distances between corresponding endpoints and the direction gaps written out below.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from albot2d.geometry import Pose
from albot2d.perception.extraction import numba_available
from albot2d.perception.surfaces import Surfaces
from albot2d.perception.tracking import (
    TrackedSurfaces,
    TrackingParams,
    key_endpoints,
    match_fitness,
    match_surfaces,
    rtsv,
    start_tracking,
)

BACKENDS = ["numpy", pytest.param("numba", marks=pytest.mark.skipif(
    not numba_available(), reason="numba not installed"))]  # fmt: skip

# Predicted: A along y = 2 from x = 0 to 2; B along x = 3 from y = −1 to 1; C along
# y = −3 from x = 0 to 2 with its first end occluded.
PRED = Surfaces.from_segments(
    [[0.0, 2.0, 2.0, 2.0], [3.0, -1.0, 3.0, 1.0], [0.0, -3.0, 2.0, -3.0]],
    [[False, False], [False, False], [True, False]],
)
# View: a = A shifted by (0.1, 0.2) (ends 0.2236 m away); b = B shifted 0.3 in y
# (0.3 m); b2 = B shifted 0.1 in x with its second end occluded (first end 0.1 m);
# c = C with its second end occluded (no end unoccluded in both; first end 0.05 m off).
VIEW = Surfaces.from_segments(
    [
        [0.1, 2.2, 2.1, 2.2],
        [3.0, -0.7, 3.0, 1.3],
        [3.1, -1.0, 3.1, 1.0],
        [0.05, -3.0, 2.05, -3.0],
    ],
    [[False, False], [False, False], [False, True], [False, True]],
)


@pytest.mark.parametrize("backend", BACKENDS)
def test_nearest_shared_endpoint_decides_and_matching_is_one_to_one(backend: str) -> None:
    """A–a at √(0.1² + 0.2²); B's candidates b (0.3 m) and b2 (0.1 m, its shared first
    end): b2 wins; C shares no unoccluded end with c: unmatched."""
    pi, vj, dist, angle = match_surfaces(PRED, VIEW, backend=backend)
    assert pi.tolist() == [0, 1]
    assert vj.tolist() == [0, 2]
    np.testing.assert_allclose(dist, [math.hypot(0.1, 0.2), 0.1], atol=1e-12)
    np.testing.assert_allclose(angle, [0.0, 0.0], atol=1e-12)


@pytest.mark.parametrize("backend", BACKENDS)
def test_candidates_and_gates_at_their_limits(backend: str) -> None:
    """Without b2 as a candidate B takes b (0.3 m); with a 0.25 m gate B finds none and
    A (0.2236 m) still matches; a direction gap of 6° > 5° is no match."""
    pi, vj, dist, _ = match_surfaces(PRED, VIEW, None, [True, True, False, True], backend=backend)
    assert (pi.tolist(), vj.tolist()) == ([0, 1], [0, 1])
    np.testing.assert_allclose(dist, [math.hypot(0.1, 0.2), 0.3], atol=1e-12)
    gate = TrackingParams(match_distance_m=0.25)
    pi, vj, _, _ = match_surfaces(PRED, VIEW, gate, [True, True, False, True], backend=backend)
    assert (pi.tolist(), vj.tolist()) == ([0], [0])
    turned = Surfaces.from_segments(
        [[0.0, 2.0, 2.0 * math.cos(math.radians(6)), 2.0 + 2.0 * math.sin(math.radians(6))]]
    )
    assert len(match_surfaces(PRED, turned, backend=backend)[0]) == 0
    nearly = Surfaces.from_segments(
        [[0.0, 2.0, 2.0 * math.cos(math.radians(4)), 2.0 + 2.0 * math.sin(math.radians(4))]]
    )
    pi, _, dist, angle = match_surfaces(PRED, nearly, backend=backend)
    assert pi.tolist() == [0]
    assert dist[0] == pytest.approx(0.0, abs=1e-12)
    assert angle[0] == pytest.approx(math.radians(4.0), abs=1e-12)


def test_line_distance_fallback_measures_ends_against_the_other_segment() -> None:
    """C and c share no unoccluded end. C's real end (2, −3) lies on c (0 m); c's real
    end (0.05, −3) lies on C (0 m): matched at 0 with the fallback. A pair with ends
    0.3 m off the other's line is matched at 0.3."""
    fallback = TrackingParams(line_distance_fallback=True)
    pi, vj, dist, _ = match_surfaces(PRED, VIEW, fallback, backend="numpy")
    assert pi.tolist() == [0, 1, 2]
    assert vj.tolist() == [0, 2, 3]
    np.testing.assert_allclose(dist, [math.hypot(0.1, 0.2), 0.1, 0.0], atol=1e-12)
    pred = Surfaces.from_segments([[0.0, 0.0, 4.0, 0.0]], [[True, False]])
    view = Surfaces.from_segments([[1.0, 0.3, 3.0, 0.3]], [[True, False]])
    # Corresponding ends: pred's end 1 (4, 0) vs view's end 1 (3, 0.3) is shared:
    # √(1 + 0.09) > 0.4, no match without fallback (and with it: shared, so the same).
    assert len(match_surfaces(pred, view, fallback, backend="numpy")[0]) == 0
    view = Surfaces.from_segments([[1.0, 0.3, 3.0, 0.3]], [[False, True]])
    # No end shared; pred's (4, 0) is 1.04 m from the view segment, view's (1, 0.3) is
    # 0.3 m from pred's: 0.3.
    pi, _, dist, _ = match_surfaces(pred, view, fallback, backend="numpy")
    assert pi.tolist() == [0]
    assert dist[0] == pytest.approx(0.3, abs=1e-12)
    assert len(match_surfaces(pred, view, backend="numpy")[0]) == 0


def test_key_endpoints_are_the_real_end_or_the_nearer() -> None:
    """Real second end → 1; both real, first nearer → 0; both real, second nearer → 1;
    first real → 0; both occluded, second nearer → 1."""
    s = Surfaces.from_segments(
        [
            [1.0, 0.0, 5.0, 0.0],
            [1.0, 1.0, 5.0, 1.0],
            [0.0, 5.0, 0.0, -1.0],
            [6.0, 0.0, 1.0, 0.0],
            [6.0, 0.0, 1.0, 0.0],
        ],
        [[True, False], [False, False], [False, False], [False, True], [True, True]],
    )
    assert key_endpoints(s).tolist() == [1, 0, 1, 0, 1]


def test_key_endpoint_matching_compares_that_end_only() -> None:
    """``match_endpoint="key"``: A's key end is its nearer (0, 2), 0.2236 m from a's
    first; B's is its nearer (3, −1) vs b's first (3, −0.7): 0.3 m, and vs b2's
    (3.1, −1): 0.1 m (b2's occlusion is not looked at); C's key is its real end
    (2, −3) vs c's (2.05, −3), 0.05 m, though that end of c is occluded."""
    key = TrackingParams(match_endpoint="key")
    pi, vj, dist, _ = match_surfaces(PRED, VIEW, key, backend="numpy")
    assert pi.tolist() == [0, 1, 2]
    assert vj.tolist() == [0, 2, 3]
    np.testing.assert_allclose(dist, [math.hypot(0.1, 0.2), 0.1, 0.05], atol=1e-12)


def test_fitness_order_prefers_the_longer_nearer_surface() -> None:
    """One predicted wall (x = 3, y ∈ [−1, 1]), two view candidates sharing its ends: a
    2 m one 0.2 m off and a 6 m one 0.3 m off. By distance the first wins; by the
    authors' fitness length·(400 − d)·(5 − Δθ)/max(range, 2000) (mm, deg, range of the
    view surface's midpoint): 2000·200·5/3006.7 = 665 against 6000·100·5/3448.2 = 870,
    the second."""
    pred = Surfaces.from_segments([[3.0, -1.0, 3.0, 1.0]])
    view = Surfaces.from_segments([[3.0, -0.8, 3.0, 1.2], [3.0, -1.3, 3.0, 4.7]])
    d = np.array([[0.2, 0.3]])
    fit = match_fitness(pred, view, d, np.zeros((1, 2)))
    range1 = 1000.0 * math.hypot(3.0, 0.2)
    range2 = 1000.0 * math.hypot(3.0, 1.7)
    np.testing.assert_allclose(
        fit, [[2000 * 200 * 5 / range1, 6000 * 100 * 5 / range2]], rtol=1e-12
    )
    by_distance = match_surfaces(pred, view, backend="numpy")
    assert by_distance[1].tolist() == [0]
    by_fitness = match_surfaces(pred, view, TrackingParams(match_order="fitness"))
    assert by_fitness[1].tolist() == [1]
    assert by_fitness[2][0] == pytest.approx(0.3, abs=1e-12)
    # A floor above the best fitness drops every match (the authors' forced update).
    floor = TrackingParams(fitness_floor=1000.0)
    assert len(match_surfaces(pred, view, floor)[0]) == 0
    floor = TrackingParams(fitness_floor=800.0)
    assert match_surfaces(pred, view, floor)[1].tolist() == [0]


def test_tracked_surfaces_store_read_only_int_ids_and_select_in_order() -> None:
    s = Surfaces.from_segments(np.arange(12.0).reshape(3, 4))
    tracked = TrackedSurfaces([7, 3, 5], s, s)  # type: ignore[arg-type]
    assert tracked.ids.dtype == np.int64
    assert not tracked.ids.flags.writeable
    assert tracked.next_id == 8
    picked = tracked.select([2, 0])
    assert picked.ids.tolist() == [5, 7]
    np.testing.assert_array_equal(picked.local.segments, s.segments[[2, 0]])
    np.testing.assert_array_equal(picked.current.segments, s.segments[[2, 0]])
    masked = tracked.select(np.array([False, True, True]))
    assert masked.ids.tolist() == [3, 5]
    with pytest.raises(ValueError, match="unique"):
        TrackedSurfaces([1, 1, 2], s, s)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="one id per surface"):
        TrackedSurfaces([1, 2], s, s)  # type: ignore[arg-type]


def test_rtsv_after_a_known_motion_keeps_ids_and_local_geometry() -> None:
    """The robot drives 1 m forward and turns 90° left: a wall 3 m ahead (x = 3) is then
    2 m to its right (y = −2, running the other way round in x). RTSV recognises it and
    keeps its id and its local-map geometry; a second wall that left the view is lost."""
    view0 = Surfaces.from_segments([[3.0, -1.0, 3.0, 1.0], [0.0, 4.0, -2.0, 4.0]])
    tracked = start_tracking(view0, first_id=10)
    assert tracked.ids.tolist() == [10, 11]
    # In the new frame (origin (1, 0), x along old +y): old (x, y) → (y, 1 − x).
    view1 = Surfaces.from_segments([[-1.0, -2.0, 1.0, -2.0]])
    survivors, info = rtsv(tracked, view1, Pose(1.0, 0.0, math.pi / 2))
    assert survivors.ids.tolist() == [10]
    np.testing.assert_array_equal(survivors.local.segments, view0.segments[:1])
    np.testing.assert_array_equal(survivors.current.segments, view1.segments)
    np.testing.assert_allclose(info.predicted.segments[0], [-1.0, -2.0, 1.0, -2.0], atol=1e-12)
    assert info.distance_m[0] == pytest.approx(0.0, abs=1e-12)
    # Nothing lost: the state's ids and local geometry are the same objects' values.
    same, _ = rtsv(survivors, view1, Pose())
    assert same.ids.tolist() == [10]
    np.testing.assert_array_equal(same.local.segments, view0.segments[:1])


def test_fallback_leaves_out_occluded_ends_and_measures_each_pair() -> None:
    """Fallback distances per pair, occluded ends left out. P0 (−2, 0.3)–(2, 0.3) has
    only its second end real, and it lies on V0 (1, 0.3)–(3, 0.3) (whose second end is
    occluded): 0 m. P1 (10, 0)–(14, 0) is 6 m from V1 (20, 0.3)–(22, 0.3): no match.
    P2 (0, 5)–(4, 5) has its occluded first end on V2 (−1, 5.05)–(1, 5.05), but that end
    does not count: V2's real end (−1, 5.05) is 1.001 m from P2, P2's real end 3 m from
    V2: no match."""
    real_second = [True, False]
    pred = Surfaces.from_segments(
        [[-2.0, 0.3, 2.0, 0.3], [10.0, 0.0, 14.0, 0.0], [0.0, 5.0, 4.0, 5.0]],
        [real_second, real_second, real_second],
    )
    view = Surfaces.from_segments(
        [[1.0, 0.3, 3.0, 0.3], [20.0, 0.3, 22.0, 0.3], [-1.0, 5.05, 1.0, 5.05]],
        [[False, True], [False, True], [False, True]],
    )
    fallback = TrackingParams(line_distance_fallback=True)
    pi, vj, dist, _ = match_surfaces(pred, view, fallback, backend="numpy")
    assert (pi.tolist(), vj.tolist()) == ([0], [0])
    assert dist[0] == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("backend", BACKENDS)
def test_nothing_to_match_gives_four_empty_arrays(backend: str) -> None:
    for got in (
        match_surfaces(PRED, VIEW, None, [False] * 4, backend=backend),
        match_surfaces(Surfaces.empty(), VIEW, backend=backend),
    ):
        assert [len(x) for x in got] == [0, 0, 0, 0]
        assert got[0].dtype == got[1].dtype == np.int64


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [
        ("match_endpoint", "nearest", "TrackingParams.match_endpoint must be corresponding or key"),
        ("match_order", "random", "TrackingParams.match_order must be distance or fitness"),
        ("match_candidates", "some", "TrackingParams.match_candidates must be trackable or all"),
    ],
)
def test_tracking_params_name_the_field_and_its_choices(
    field: str, value: str, message: str
) -> None:
    from albot2d.errors import InputError

    with pytest.raises(InputError, match=rf"^{message}, got {value!r}$"):
        TrackingParams(**{field: value})  # type: ignore[arg-type]


def test_candidates_may_be_any_truthy_mask() -> None:
    """A 0/1 float mask selects as a bool one does."""
    pi, vj, _, _ = match_surfaces(PRED, VIEW, None, [1.0, 1.0, 0.0, 1.0], backend="numpy")
    assert (pi.tolist(), vj.tolist()) == ([0, 1], [0, 1])


def test_all_candidates_recognise_a_surface_that_is_no_longer_trackable() -> None:
    """A wall tracked at 2 m long is seen next as 0.3 m (shortened by an occluder): not
    trackable (≤ 0.4 m), so RTSV by the paper loses it; with ``match_candidates="all"``
    (every surface of the view) it is recognised, its real end unmoved."""
    from albot2d.perception.tracking import recognise

    current = Surfaces.from_segments([[3.0, -1.0, 3.0, 1.0]])
    view = Surfaces.from_segments([[3.0, -1.0, 3.0, -0.7]], [[False, True]])
    assert len(recognise(current, view, Pose())) == 0
    info = recognise(current, view, Pose(), TrackingParams(match_candidates="all"))
    assert info.view_index.tolist() == [0]
    assert info.candidates.tolist() == [True]
    assert info.distance_m[0] == pytest.approx(0.0, abs=1e-12)


def test_numba_backend_refuses_settings_only_numpy_covers() -> None:
    with pytest.raises(ValueError, match="paper's matching settings"):
        match_surfaces(PRED, VIEW, TrackingParams(line_distance_fallback=True), backend="numba")


def test_all_candidates_are_a_bool_mask() -> None:
    from albot2d.perception.tracking import recognise

    info = recognise(PRED, VIEW, Pose(), TrackingParams(match_candidates="all"))
    assert info.candidates.dtype == np.bool_
    assert info.candidates.tolist() == [True] * 4
