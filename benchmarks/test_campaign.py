"""Fuzzing campaign throughput: the same 20 default episodes on 1 and on 2 local workers.

Run: ``python -m pytest benchmarks/test_campaign.py --benchmark-only
--benchmark-group-by=group -s``. Each worker pool is started and warmed up (two episodes,
so every worker has imported albot2d) before the clock starts, so the times are the
campaign's throughput, not the pool's start-up (about a second per spawned worker). The
2-worker row's ``extra_info`` holds its speed-up over the 1-worker row (best of two rounds
each); the goal is ≥ 1.7× on a 2-core machine.
"""

from __future__ import annotations

import tempfile
from typing import Any

import pytest

from albot2d.evaluation.backends import LocalBackend
from albot2d.evaluation.campaign import CampaignParams, run_campaign

EPISODES = 20
PARAMS = CampaignParams(episodes=EPISODES, seed=2024)
WARM_UP = CampaignParams(
    episodes=2,
    seed=1,
    kinds=("rooms",),
    world_size_max_m=15.0,
    tour_length_min_m=10.0,
    tour_length_max_m=10.0,
)
ROUNDS = 2  # the machine is shared: the faster of two rounds is the one compared
_seconds: dict[int, float] = {}


@pytest.mark.parametrize("workers", [1, 2])
@pytest.mark.benchmark(group="campaign-20-episodes")
def test_campaign_throughput(benchmark: Any, workers: int) -> None:
    backend = LocalBackend(workers)
    try:
        with tempfile.TemporaryDirectory() as warm:
            run_campaign(WARM_UP, warm, backend=backend)

        def campaign() -> dict[str, Any]:
            with tempfile.TemporaryDirectory() as out:
                return run_campaign(PARAMS, out, backend=backend)

        summary = benchmark.pedantic(campaign, rounds=ROUNDS, iterations=1)
    finally:
        backend.close()
    assert summary["episodes"] == EPISODES and summary["crashes"] == 0
    _seconds[workers] = benchmark.stats.stats.min
    benchmark.extra_info["episodes_per_min"] = 60.0 * EPISODES / _seconds[workers]
    if workers > 1 and 1 in _seconds:
        speedup = _seconds[1] / _seconds[workers]
        benchmark.extra_info["speedup_vs_1_worker"] = speedup
        print(
            f"\n{workers} workers: {speedup:.2f}× the throughput of 1 worker "
            f"({_seconds[1]:.1f} s vs {_seconds[workers]:.1f} s for {EPISODES} episodes)"
        )
