"""Explore-v0 throughput: ``AsyncVectorEnv`` with 2 workers against 1 (goal ≥ 1.7× the env
steps per second on a 2-core machine), beside the two measurements that say what bounds it.

Run: ``python -m pytest benchmarks/test_envs.py --benchmark-only --benchmark-group-by=group
-s``. Each vector env is made and reset (every worker has imported albot2d and built its
world) before the clock starts; a round is ``STEPS`` env steps in total (``STEPS /
workers`` vector steps) of seeded random actions in the default office world. Three cases,
each with 1 and 2 workers:

- ``explore``: ``albot2d/Explore-v0`` as registered (``dt_s`` 0.1 s: one scan per step);
- ``explore-dt0.5``: the same with ``dt_s=0.5`` (five physics ticks and five scans per
  step), so each step carries five times the work per message;
- ``stand-in``: Gymnasium's CartPole holding the CPU for ``STANDIN_S`` per step in a busy
  loop: a step of pure computation, no memory traffic, the same messages. Its ratio is
  what ``AsyncVectorEnv`` itself allows on this machine for a step that long.

Each 2-worker row's ``extra_info`` holds its speed-up over the 1-worker row of its case
(best round of each). On a shared machine the ratio is bounded by the cores actually free:
report the load with it.
"""

from __future__ import annotations

import os
import time
from typing import Any

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium", reason="the gym extra (gymnasium) is not installed")

import albot2d.envs  # noqa: E402,F401

STEPS = 400
ROUNDS = 3
#: The stand-in's busy time per step (s): about one Explore-v0 step on a quiet core.
STANDIN_S = 0.0004
_seconds: dict[tuple[str, int], float] = {}


class _BusyStep(gymnasium.Wrapper):  # type: ignore[type-arg]
    """Holds the CPU for ``STANDIN_S`` per step (and resets CartPole when it falls)."""

    def step(self, action: Any) -> Any:
        end = time.perf_counter() + STANDIN_S
        while time.perf_counter() < end:
            pass
        obs, reward, terminated, truncated, info = self.env.step(action)
        if terminated or truncated:
            obs, info = self.env.reset()
        return obs, reward, False, False, info


def _standin() -> Any:
    return _BusyStep(gymnasium.make("CartPole-v1"))


def _vector(case: str, workers: int) -> Any:
    if case == "stand-in":
        return gymnasium.vector.AsyncVectorEnv([_standin] * workers)
    options = {"dt_s": 0.5} if case == "explore-dt0.5" else {}
    return gymnasium.make_vec(
        "albot2d/Explore-v0", num_envs=workers, vectorization_mode="async", **options
    )


@pytest.mark.parametrize("workers", [1, 2])
@pytest.mark.parametrize("case", ["explore", "explore-dt0.5", "stand-in"])
@pytest.mark.benchmark(group="explore-v0-async")
def test_async_throughput(benchmark: Any, case: str, workers: int) -> None:
    envs = _vector(case, workers)
    try:
        envs.reset(seed=list(range(workers)))
        rng = np.random.default_rng(0)
        space = envs.single_action_space
        actions = np.stack(
            [np.stack([space.sample() for _ in range(workers)]) for _ in range(STEPS // workers)]
        ) if case == "stand-in" else rng.uniform(
            space.low, space.high, size=(STEPS // workers, workers, 2)
        ).astype(np.float32)  # fmt: skip
        steps = [0]

        def run() -> None:
            for a in actions:
                envs.step(a)
                steps[0] += workers

        benchmark.pedantic(run, rounds=ROUNDS, iterations=1, warmup_rounds=1)
    finally:
        envs.close()
    assert steps[0] % STEPS == 0 and steps[0] >= STEPS  # every round stepped every env
    if benchmark.disabled:  # untimed (as CI runs it): the steps ran, there is nothing to time
        return
    _seconds[case, workers] = benchmark.stats.stats.min
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
