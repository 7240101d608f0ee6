"""Deletion-rule benchmark: one global-map update under each reading of algorithm #5.

Run: ``python -m pytest benchmarks/test_deletion.py --benchmark-only
--benchmark-group-by=group``. The rules run side by side in one group on the same map and
views (``benchmarks.test_mapping``'s building-density map of 10k surfaces, laser views of
it); the ``visible`` rule adds a sight-line test per candidate surface (goal: ≤ 1.5× ``paper``).
"""

from __future__ import annotations

import numpy as np
import pytest

from albot2d.mapping.albot1.deletion import GlobalMapParams
from benchmarks.test_mapping import filled_map, maps_and_views, time_updates


@pytest.mark.benchmark(group="deletion rule")
@pytest.mark.parametrize("rule", ["paper", "visible", "original"])
def test_update_by_rule(benchmark, rule: str) -> None:  # type: ignore[no-untyped-def]
    maps, views = maps_and_views((10_000,))
    filled = maps[10_000]
    filled.params = GlobalMapParams.preset(rule)
    time_updates(benchmark, filled, views)
    benchmark.extra_info["rule"] = rule


@pytest.mark.benchmark(group="touching test (default rule)")
@pytest.mark.parametrize("path", ["quick", "geos"])
def test_update_by_touching_path(benchmark, path: str) -> None:  # type: ignore[no-untyped-def]
    """The compiled quick touching test (P built only when it is unsure) against building
    P and testing every candidate with GEOS, side by side on the same map and views."""
    pytest.importorskip("numba")
    maps, views = maps_and_views((10_000,))
    with pytest.MonkeyPatch.context() as mp:
        if path == "geos":
            mp.setattr("albot2d.mapping.albot1.global_map.quick_touch_ring", lambda *a: None)
        time_updates(benchmark, maps[10_000], views)


@pytest.mark.benchmark(group="sight lines (visible_share, 400 updates)")
@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_visible_share(benchmark, backend: str) -> None:  # type: ignore[no-untyped-def]
    if backend == "numba":
        pytest.importorskip("numba")
    from albot2d.geometry import Pose
    from albot2d.mapping.albot1.deletion import visible_share
    from benchmarks.test_mapping import a_view

    rng = np.random.default_rng(1)
    _, walk = filled_map(1_000, rng)
    cases = []
    for _ in range(400):
        view, pose = a_view(rng, walk)
        old = view[rng.permutation(len(view))[:8]] + rng.normal(0.0, 0.3, (8, 4))
        cases.append((old, view, pose))
    visible_share(*cases[0][:2], Pose(), 0.5, backend=backend)  # compile / load first

    def run() -> float:
        return sum(float(visible_share(o, v, p, 0.5, backend=backend).sum()) for o, v, p in cases)

    assert benchmark(run) > 0
