"""Explore-v0 throughput: ``AsyncVectorEnv`` with 2 workers against 1 (goal ≥ 1.7× the env
steps per second on a 2-core machine), beside the two measurements that say what bounds it.

Run: ``python -m pytest benchmarks/test_envs.py --benchmark-only --benchmark-group-by=group
-s``. Each vector env is made and reset (every worker has imported albot2d and built its
world) before the clock starts; a round is ``STEPS`` env steps in total (``STEPS /
workers`` vector steps) of seeded random actions in the default office world (world
seed 0 in every worker). Three cases,
each with 1 and 2 workers:

- ``explore``: ``albot2d/Explore-v0`` as registered (``dt_s`` 0.1 s: one scan per step);
- ``explore-dt0.5``: the same with ``dt_s=0.5`` (five physics ticks and five scans per
  step), so each step carries five times the work per message;
- ``independent``: no Gymnasium vector at all: ``STEPS`` steps of a plain
  ``Explore-v0`` in one process, against ``STEPS / 2`` in each of two processes started
  together. Its ratio is what the machine gives two copies of this very workload, the
  ceiling of any vectorisation (on a VM whose two vCPUs slow each other down it is well
  under 2).

Each 2-worker row's ``extra_info`` holds its speed-up over the 1-worker row of its case
(best round of each). On a shared machine the ratio is bounded by the cores actually free:
report the load with it.
"""

from __future__ import annotations

import multiprocessing
import os
import time
from typing import Any

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium", reason="the gym extra (gymnasium) is not installed")

import albot2d.envs  # noqa: E402,F401

STEPS = 1000
ROUNDS = 3
_seconds: dict[tuple[str, int], float] = {}


def _independent_worker(share: int, ready: Any, go: Any, times: Any) -> None:
    env = gymnasium.make("albot2d/Explore-v0", max_episode_steps=None)
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    low, high = env.action_space.low, env.action_space.high
    actions = rng.uniform(low, high, size=(share, 2)).astype(np.float32)
    ready.wait()
    go.wait()
    start = time.perf_counter()
    for a in actions:
        _obs, _r, terminated, truncated, _info = env.step(a)
        if terminated or truncated:
            env.reset()
    times.put((start, time.perf_counter()))
    env.close()


class _Independent:
    """``workers`` processes stepping a plain env, released together; ``run`` returns
    when all are done (CLOCK_MONOTONIC, the same clock in every process)."""

    def __init__(self, workers: int) -> None:
        ctx = multiprocessing.get_context("fork")
        self.workers = workers
        self.ready, self.go = ctx.Barrier(workers + 1), ctx.Barrier(workers + 1)
        self.times = ctx.Queue()
        self.procs = [
            ctx.Process(target=_independent_worker,
                        args=(STEPS // workers, self.ready, self.go, self.times))
            for _ in range(workers)
        ]  # fmt: skip
        for proc in self.procs:
            proc.start()
        self.ready.wait()  # every env made and reset: the clock may start

    def run(self) -> float:
        self.go.wait()
        spans = [self.times.get(timeout=600) for _ in range(self.workers)]
        for proc in self.procs:
            proc.join(timeout=60)
        return max(end for _, end in spans) - min(start for start, _ in spans)


def _vector(case: str, workers: int) -> Any:
    options = {"dt_s": 0.5} if case == "explore-dt0.5" else {}
    return gymnasium.make_vec(
        "albot2d/Explore-v0", num_envs=workers, vectorization_mode="async", **options
    )


@pytest.mark.parametrize("workers", [1, 2])
@pytest.mark.parametrize("case", ["explore", "explore-dt0.5"])
@pytest.mark.benchmark(group="explore-v0-async")
def test_async_throughput(benchmark: Any, case: str, workers: int) -> None:
    envs = _vector(case, workers)
    try:
        # The same world in every worker (actions differ): the 1-worker row then does the
        # same work per step as each of the 2, and the ratio is about the scaling alone.
        envs.reset(seed=[0] * workers)
        rng = np.random.default_rng(0)
        space = envs.single_action_space
        actions = rng.uniform(space.low, space.high, size=(STEPS // workers, workers, 2))
        actions = actions.astype(np.float32)
        steps = [0]

        def run() -> None:
            for a in actions:
                envs.step(a)
                steps[0] += workers

        benchmark.pedantic(run, rounds=ROUNDS, iterations=1, warmup_rounds=1)
    finally:
        envs.close()
    assert steps[0] % STEPS == 0 and steps[0] >= STEPS  # every round stepped every env
    _record(benchmark, case, workers, benchmark.stats.stats.min if benchmark.enabled else None)


@pytest.mark.parametrize("workers", [1, 2])
@pytest.mark.benchmark(group="explore-v0-async")
def test_independent_processes(benchmark: Any, workers: int) -> None:
    spans: list[float] = []

    def setup() -> tuple[tuple[_Independent], dict[str, Any]]:
        return (_Independent(workers),), {}

    def run(runner: _Independent) -> None:
        spans.append(runner.run())

    benchmark.pedantic(run, setup=setup, rounds=ROUNDS, warmup_rounds=0)
    assert spans and all(s > 0.0 for s in spans)  # every process stepped and reported
    # The span the processes measured themselves (process start-up and joining excluded).
    _record(benchmark, "independent", workers, min(spans) if benchmark.enabled else None)


def _record(benchmark: Any, case: str, workers: int, seconds: float | None) -> None:
    if seconds is None:  # untimed (as CI runs it): the steps ran, there is nothing to time
        return
    _seconds[case, workers] = seconds
    benchmark.extra_info["env_steps_per_s"] = STEPS / _seconds[case, workers]
    benchmark.extra_info["load_average"] = os.getloadavg()
    if workers > 1 and (case, 1) in _seconds:
        speedup = _seconds[case, 1] / _seconds[case, workers]
        benchmark.extra_info["speedup_vs_1_worker"] = speedup
        print(
            f"\n{case}, {workers} workers: {speedup:.2f}x the env steps/s of 1 worker "
            f"({STEPS / _seconds[case, 1]:.0f} vs {STEPS / _seconds[case, workers]:.0f} "
            f"steps/s; load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores)"
        )
