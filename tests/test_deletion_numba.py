"""The compiled (numba) sight-line test of the deletion rule gives the numpy path's shares,
bit for bit: random scenes (surfaces across, along and behind the view's, degenerate ones,
sample counts other than 8) and the updates of a simulated office run. Skipped where numba
is not installed."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from albot2d.geometry import Pose
from albot2d.mapping.deletion import visible_share

pytest.importorskip("numba")


def random_segments(rng: np.random.Generator, n: int) -> np.ndarray:
    a = rng.uniform(-6.0, 6.0, (n, 2))
    ang = rng.uniform(-np.pi, np.pi, n)
    length = rng.uniform(0.0, 4.0, n) * (rng.random(n) > 0.1)  # some zero-length
    return np.hstack([a, a + length[:, None] * np.column_stack([np.cos(ang), np.sin(ang)])])


def assert_same(segs: np.ndarray, view: np.ndarray, robot: Pose, beyond: float, k: int) -> None:
    want = visible_share(segs, view, robot, beyond, k, backend="numpy")
    got = visible_share(segs, view, robot, beyond, k, backend="numba")
    assert got.dtype == want.dtype and got.shape == want.shape
    np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize("seed", range(40))
def test_numba_share_equals_numpy_on_random_scenes(seed: int) -> None:
    rng = np.random.default_rng(seed)
    view = random_segments(rng, int(rng.integers(0, 14)))
    # Old surfaces: jittered copies of view surfaces (near the beyond_m limit) and clutter.
    near = view + rng.normal(0.0, 0.4, view.shape) * (rng.random((len(view), 1)) < 0.8)
    segs = np.vstack([near, random_segments(rng, int(rng.integers(0, 10)))])
    robot = Pose(*rng.uniform(-1.0, 1.0, 2), rng.uniform(-np.pi, np.pi))
    assert_same(segs, view, robot, float(rng.uniform(0.0, 1.0)), int(rng.integers(1, 12)))


def test_numba_share_equals_numpy_on_an_office_run() -> None:
    from albot2d.evaluation.setup import RunSpec, build_run
    from albot2d.geometry import transform_segments
    from albot2d.mapping import Albot1

    run = build_run(RunSpec(tour_length_m=25.0))
    m = Albot1()
    checked = 0
    for frame in itertools.islice(run.simulator.drive(run.tour, run.profile), 600):
        before = m.map.snapshot()
        n_maps = len(m.route)
        m.observe(frame)
        for lm in m.route.maps[n_maps:]:
            view = transform_segments(lm.pose.as_array(), lm.view.segments)
            if len(before.segments):
                assert_same(before.segments, view, lm.pose, 0.5, 8)
                checked += 1
    assert checked > 50
