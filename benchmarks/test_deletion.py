"""Deletion-rule benchmark: one global-map update under each reading of algorithm #5.

Run: ``python -m pytest benchmarks/test_deletion.py --benchmark-only
--benchmark-group-by=group``. The rules run side by side in one group on the same map and
views (``benchmarks.test_mapping``'s building-density map of 10k surfaces); the
``visible`` rule adds a sight-line test per candidate surface (goal: ≤ 1.5× ``paper``).
"""

from __future__ import annotations

import copy

import numpy as np
import pytest

from albot2d.geometry import Pose
from albot2d.mapping import GlobalMap
from albot2d.mapping.deletion import GlobalMapParams
from benchmarks.test_mapping import a_view, filled_map


@pytest.mark.benchmark(group="deletion rule")
@pytest.mark.parametrize("rule", ["paper", "visible", "original"])
def test_update_by_rule(benchmark, rule: str) -> None:  # type: ignore[no-untyped-def]
    rng = np.random.default_rng(0)
    filled, walk = filled_map(10_000, rng)
    filled.params = GlobalMapParams.preset(rule)
    views = [a_view(rng, walk) for _ in range(16)]
    rounds = iter(range(10**9))

    def setup():  # type: ignore[no-untyped-def]
        segs, pose = views[next(rounds) % len(views)]
        return (copy.deepcopy(filled), segs, pose), {}

    def update(g: GlobalMap, segs: np.ndarray, pose: Pose) -> None:
        g.add_view(segs, g.last_map_id + 1, pose)  # type: ignore[operator]

    benchmark.pedantic(update, setup=setup, rounds=32, iterations=1)
    benchmark.extra_info["rule"] = rule
