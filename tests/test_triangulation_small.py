"""Triangulation from a few surfaces (the compiled path, fewer than 8) gives the array
path's pose bit for bit: random local maps and views (flipped directions, occluded and
uncertain ends, surfaces without beams, poses near and far from path integration, several
gates and consensus widths) and the views a simulated office run localises."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

import albot2d.mapping.albot1.triangulation as tri
from albot2d.geometry import Pose
from albot2d.mapping.albot1.triangulation import TriangulationParams, triangulate
from albot2d.perception.surfaces import Surfaces


def both_paths(*args, **kwargs) -> tuple[Pose | None, Pose | None]:  # type: ignore[no-untyped-def]
    pytest.importorskip("numba")  # without numba both would be the array path
    fast = triangulate(*args, **kwargs)
    small, tri._SMALL = tri._SMALL, 0  # the array path for every size
    try:
        slow = triangulate(*args, **kwargs)
    finally:
        tri._SMALL = small
    return fast, slow


def random_pair(rng: np.random.Generator, n: int) -> tuple[Surfaces, Surfaces, Pose]:
    a = rng.uniform(-5.0, 5.0, (n, 2))
    ang = rng.uniform(-np.pi, np.pi, n)
    length = rng.uniform(0.3, 4.0, n)
    segs = np.hstack([a, a + length[:, None] * np.column_stack([np.cos(ang), np.sin(ang)])])
    x, y = rng.normal(0.0, 0.3, 2)
    true = Pose(float(x), float(y), float(rng.normal(0.0, 0.05)))
    seen = Surfaces.from_segments(segs).transformed(true.inverse().as_array()).segments
    seen = seen + rng.normal(0.0, 0.02, seen.shape)
    flip = rng.random(n) < 0.3  # the same surface seen with its ends swapped
    seen[flip] = seen[flip][:, [2, 3, 0, 1]]
    beams = rng.integers(0, 180, (n, 2))
    beams[:, 1] += beams[:, 0]
    beams[rng.random(n) < 0.2] = -1
    local = Surfaces(segs, rng.random((n, 2)) < 0.3, beams, rng.random((n, 2)) < 0.2)
    current = Surfaces(seen, rng.random((n, 2)) < 0.3, beams, rng.random((n, 2)) < 0.2)
    return local, current, true


def test_compiled_path_equals_array_path_on_random_views() -> None:
    """260 random views; the comparison counts only where a pose came out (both ``None``
    says nothing), and most views must give one."""
    located = 0
    for seed in range(260):
        rng = np.random.default_rng(seed)
        n = int(rng.integers(1, 8))
        local, current, true = random_pair(rng, n)
        spread = float(rng.choice([0.01, 0.2, 2.0]))
        pi = Pose(true.x + rng.normal(0, spread), true.y + rng.normal(0, spread),
                  float(true.theta + rng.normal(0, spread / 4)))  # fmt: skip
        params = TriangulationParams(
            heading_consensus_deg=float(rng.choice([0.0, 1.0, 3.0, 30.0])),
            max_pi_deviation_m=None if rng.random() < 0.5 else float(rng.uniform(0.05, 1.0)),
            max_pi_deviation_deg=None if rng.random() < 0.5 else float(rng.uniform(1.0, 20.0)),
        )
        steps = int(rng.integers(1, 5))
        fast, slow = both_paths(local, current, pi, params, steps=steps, gate=(0.4, 5.0))
        assert repr(fast) == repr(slow), seed
        located += fast is not None
    assert located >= 130, located


def test_compiled_path_equals_array_path_on_an_office_run() -> None:
    from albot2d.evaluation.run.setup import RunSpec, build_run
    from albot2d.mapping import Albot1

    calls = []
    real = tri.triangulate

    def record(*args, **kwargs):  # type: ignore[no-untyped-def]
        calls.append((args, kwargs))
        return real(*args, **kwargs)

    run = build_run(RunSpec(tour_length_m=25.0))
    m = Albot1()
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr("albot2d.mapping.albot1.mapper.triangulate", record)
        for frame in itertools.islice(run.simulator.drive(run.tour, run.profile), 2000):
            m.observe(frame)
    assert len(calls) > 50
    located = 0
    for args, kwargs in calls:
        fast, slow = both_paths(*args, **kwargs)
        assert repr(fast) == repr(slow)
        located += fast is not None
    assert located > 25


def test_other_heuristics_take_the_array_path() -> None:
    assert tri._small_path_covers(TriangulationParams(max_pi_deviation_m=0.2))
    assert not tri._small_path_covers(TriangulationParams(heading="selected"))
    assert not tri._small_path_covers(TriangulationParams(choose="fitness"))
    assert not tri._small_path_covers(TriangulationParams(use_outlier_heuristic=False))
