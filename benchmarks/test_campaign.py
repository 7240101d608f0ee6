"""Fuzzing campaign throughput: the same 20 default episodes on 1 and on 2 local workers, and
on 1 worker against an older checkout (issue 12: ≥ 3× the throughput of commit 2725c59).

Run: ``python -m pytest benchmarks/test_campaign.py --benchmark-only
--benchmark-group-by=group -s``. Each worker pool is started and warmed up (two episodes,
so every worker has imported albot2d) before the clock starts, so the times are the
campaign's throughput, not the pool's start-up (about a second per spawned worker). The
2-worker row's ``extra_info`` holds its speed-up over the 1-worker row (best of two rounds
each); the goal is ≥ 1.7× on a 2-core machine.

Against a baseline: set ``ALBOT2D_BASELINE`` to a checkout of the code to compare with
(``git worktree add ../baseline12 2725c59``); the baseline's campaign runs in a child
process (``PYTHONPATH`` at the checkout) before each round of this checkout's, warmed up
and timed the same way (wall and CPU time of ``run_campaign`` on one worker, this process).
``extra_info`` holds both throughputs and their ratio (best round of each); CPU time is
the fairer measure on a shared machine. Without the variable the test is skipped.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import pytest

from albot2d.evaluation.fuzz.backends import LocalBackend
from albot2d.evaluation.fuzz.campaign import CampaignParams, run_campaign

EPISODES = 20
SEED = 2024
PARAMS = CampaignParams(episodes=EPISODES, seed=SEED)
WARM_UP = CampaignParams(
    episodes=2,
    seed=1,
    kinds=("rooms",),
    world_size_max_m=15.0,
    tour_length_min_m=10.0,
    tour_length_max_m=10.0,
)
ROUNDS = 2  # the machine is shared: the faster of two rounds is the one compared
BASELINE_ENV = "ALBOT2D_BASELINE"
_seconds: dict[int, float] = {}

# What the baseline's child process runs: the same warm-up and campaign as this module,
# with the API both checkouts share (CampaignParams, run_campaign on this process).
_CHILD = """
import json, sys, tempfile, time
from albot2d.evaluation.fuzz.campaign import CampaignParams, run_campaign
episodes, seed = int(sys.argv[1]), int(sys.argv[2])
warm = CampaignParams(episodes=2, seed=1, kinds=("rooms",), world_size_max_m=15.0,
                      tour_length_min_m=10.0, tour_length_max_m=10.0)
with tempfile.TemporaryDirectory() as out:
    run_campaign(warm, out)
with tempfile.TemporaryDirectory() as out:
    wall, cpu = time.perf_counter(), time.process_time()
    summary = run_campaign(CampaignParams(episodes=episodes, seed=seed), out)
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
print(json.dumps({"wall_s": wall, "cpu_s": cpu, "episodes": summary["episodes"],
                  "crashes": summary["crashes"]}))
"""


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


def _baseline_campaign(checkout: Path) -> dict[str, float]:
    """The baseline checkout's campaign in a child process: its wall and CPU seconds."""
    env = {**os.environ, "PYTHONPATH": str(checkout)}
    done = subprocess.run(
        [sys.executable, "-c", _CHILD, str(EPISODES), str(SEED)],
        capture_output=True, text=True, env=env, cwd=str(checkout), timeout=1800, check=False,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert result["episodes"] == EPISODES and result["crashes"] == 0
    return result


@pytest.mark.benchmark(group="campaign-vs-baseline")
def test_campaign_throughput_against_a_baseline_checkout(benchmark: Any) -> None:
    baseline = os.environ.get(BASELINE_ENV)
    if not baseline:
        pytest.skip(
            f"set {BASELINE_ENV} to a checkout to compare with (issue 12's baseline: "
            "`git worktree add ../baseline12 2725c59`)"
        )
    checkout = Path(baseline).resolve()
    if not (checkout / "albot2d" / "evaluation" / "campaign.py").is_file():
        pytest.fail(f"{BASELINE_ENV}={baseline}: not an albot2d checkout with campaigns")
    with tempfile.TemporaryDirectory() as warm:
        run_campaign(WARM_UP, warm)
    base: list[dict[str, float]] = []
    cpu: list[float] = []

    def campaign() -> dict[str, Any]:
        with tempfile.TemporaryDirectory() as out:
            start = time.process_time()
            summary = run_campaign(PARAMS, out)
            cpu.append(time.process_time() - start)
            return summary

    summary = benchmark.pedantic(
        campaign,
        setup=lambda: base.append(_baseline_campaign(checkout)),  # in alternation
        rounds=ROUNDS,
        iterations=1,
    )
    assert summary["episodes"] == EPISODES and summary["crashes"] == 0
    wall = benchmark.stats.stats.min
    base_wall = min(b["wall_s"] for b in base)
    base_cpu = min(b["cpu_s"] for b in base)
    info = {
        "episodes_per_min": 60.0 * EPISODES / wall,
        "baseline_episodes_per_min": 60.0 * EPISODES / base_wall,
        "speedup_wall": base_wall / wall,
        "episodes_per_cpu_min": 60.0 * EPISODES / min(cpu),
        "baseline_episodes_per_cpu_min": 60.0 * EPISODES / base_cpu,
        "speedup_cpu": base_cpu / min(cpu),
    }
    benchmark.extra_info.update(info)
    print(
        f"\nagainst {checkout.name}: {info['speedup_cpu']:.2f}× per CPU second "
        f"({info['episodes_per_cpu_min']:.0f} vs {info['baseline_episodes_per_cpu_min']:.0f} "
        f"episodes per CPU minute), {info['speedup_wall']:.2f}× wall "
        f"({info['episodes_per_min']:.0f} vs {info['baseline_episodes_per_min']:.0f} per minute)"
    )
