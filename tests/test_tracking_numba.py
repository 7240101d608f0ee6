"""The compiled (numba) RTSV matching gives the numpy path's matches, bit for bit.

Random tracked sets and views with near-duplicates, shared distances (ties) and occluded
ends; RTSV over a simulated office run. Skipped where numba is not installed.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from albot2d.perception import Surfaces, extract_surfaces
from albot2d.perception.tracking import (
    TrackingParams,
    match_surfaces,
    rtsv,
    start_tracking,
    trackable_mask,
)

pytest.importorskip("numba")


def random_surfaces(rng: np.random.Generator, n: int) -> Surfaces:
    a = rng.uniform(-4.0, 4.0, (n, 2))
    ang = rng.uniform(-np.pi, np.pi, n)
    length = rng.uniform(0.2, 3.0, n)
    segs = np.hstack([a, a + length[:, None] * np.column_stack([np.cos(ang), np.sin(ang)])])
    return Surfaces.from_segments(segs, rng.random((n, 2)) < 0.3)


def assert_same_matches(a: tuple, b: tuple) -> None:  # type: ignore[type-arg]
    assert len(a) == len(b) == 4
    for x, y in zip(a, b, strict=True):
        assert x.dtype == y.dtype
        np.testing.assert_array_equal(x, y)


@pytest.mark.parametrize("seed", range(40))
def test_numba_matching_equals_numpy_on_random_views(seed: int) -> None:
    rng = np.random.default_rng(seed)
    predicted = random_surfaces(rng, int(rng.integers(0, 12)))
    # The view: jittered copies of the predictions (some exact: distance ties) and clutter.
    near = predicted.segments + rng.normal(0.0, 0.1, predicted.segments.shape) * (
        rng.random((len(predicted), 1)) < 0.7)  # fmt: skip
    clutter = random_surfaces(rng, int(rng.integers(0, 8)))
    view = Surfaces.from_segments(
        np.vstack([near, near[::-1], clutter.segments]),
        np.vstack([predicted.occluded, predicted.occluded[::-1], clutter.occluded]),
    )
    cand = rng.random(len(view)) < 0.9
    params = TrackingParams(match_distance_m=float(rng.choice([0.4, 1.0])))
    assert_same_matches(match_surfaces(predicted, view, params, cand, backend="numpy"),
                        match_surfaces(predicted, view, params, cand, backend="numba"))  # fmt: skip


def test_numba_matching_equals_numpy_over_a_simulated_run() -> None:
    from albot2d.evaluation.run.setup import RunSpec, build_world, make_simulator
    from albot2d.sim.driving import get_profile
    from worldgen import plan_tour

    spec = RunSpec(kind="office", seed=2)
    world = build_world(spec)
    tour = plan_tour(world, kind=spec.tour_kind, length_m=40.0)
    frames = itertools.islice(make_simulator(world, spec).drive(tour, get_profile("dataset1")),
                              400)  # fmt: skip
    tracked, prev, matched = None, None, 0
    for frame in frames:
        view = extract_surfaces(frame.scan)
        if tracked is None or len(tracked) < 2:
            tracked = start_tracking(view)
        else:
            increment = prev.between(frame.odom_pose)
            predicted = tracked.current.transformed(increment.inverse().as_array())
            cand = trackable_mask(view)
            expected = match_surfaces(predicted, view, None, cand, backend="numpy")
            assert_same_matches(expected, match_surfaces(predicted, view, None, cand,
                                                         backend="numba"))  # fmt: skip
            tracked, info = rtsv(tracked, view, increment)
            np.testing.assert_array_equal(info.tracked_index, expected[0])
            matched += len(info)
        prev = frame.odom_pose
    assert matched > 500


def test_numba_backend_refuses_settings_it_does_not_cover() -> None:
    s = Surfaces.from_segments([[0.0, 1.0, 1.0, 1.0]])
    with pytest.raises(ValueError, match="paper's matching"):
        match_surfaces(s, s, TrackingParams(match_order="fitness"), backend="numba")
    with pytest.raises(ValueError, match="backend"):
        match_surfaces(s, s, backend="gpu")
    # auto falls back to numpy for them
    assert len(match_surfaces(s, s, TrackingParams(match_order="fitness"))[0]) == 1
