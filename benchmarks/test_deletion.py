"""Deletion-rule benchmark: one global-map update under each reading of algorithm #5.

Run: ``python -m pytest benchmarks/test_deletion.py --benchmark-only
--benchmark-group-by=group``. The rules run side by side in one group on the same map and
views (``benchmarks.test_mapping``'s building-density map of 10k surfaces); the
``visible`` rule adds a sight-line test per candidate surface (goal: ≤ 1.5× ``paper``).
"""

from __future__ import annotations

import numpy as np
import pytest

from albot2d.mapping.deletion import GlobalMapParams
from benchmarks.test_mapping import filled_map, time_updates


@pytest.mark.benchmark(group="deletion rule")
@pytest.mark.parametrize("rule", ["paper", "visible", "original"])
def test_update_by_rule(benchmark, rule: str) -> None:  # type: ignore[no-untyped-def]
    rng = np.random.default_rng(0)
    filled, walk = filled_map(10_000, rng)
    filled.params = GlobalMapParams.preset(rule)
    time_updates(benchmark, filled, rng, walk)
    benchmark.extra_info["rule"] = rule
