"""Experiment benchmarks: a small ``run_experiment`` end to end, its scoring, its figures.

Run: ``python -m pytest benchmarks/test_experiment.py --benchmark-only
--benchmark-group-by=group``. The run is a 15 × 15 m rooms world, a loop of ≥ 20 m driven
with dataset1 (≈ 2000 views) and the three built-in mappers; scoring is dominated by map
quality over the integrators' maps (one surface set per view).
"""

from __future__ import annotations

from typing import Any

import pytest

from albot2d.evaluation import EvaluationParams, RunSpec, run_experiment, score_mappers

SPEC = RunSpec(
    kind="rooms",
    world_params={"width_m": 15.0, "height_m": 15.0},
    profile="dataset1",
    tour_length_m=20.0,
)


@pytest.fixture(scope="module")
def result() -> Any:
    return run_experiment(SPEC)


@pytest.mark.benchmark(group="experiment")
def test_run_experiment_small(benchmark: Any) -> None:
    out = benchmark.pedantic(run_experiment, args=(SPEC,), rounds=2, iterations=1)
    assert out.report["run"]["frames"] > 1000


@pytest.mark.benchmark(group="experiment")
def test_scoring_small(benchmark: Any, result: Any) -> None:
    world = result.world.obstacle_segments
    scores = benchmark.pedantic(
        score_mappers,
        args=(result.trace, result.relations, world, EvaluationParams()),
        rounds=3,
        iterations=1,
    )
    assert set(scores) == {"albot1", "naive", "truth"}


@pytest.mark.benchmark(group="experiment")
def test_figures_small(benchmark: Any, result: Any) -> None:
    from albot2d.viz.run_figures import render_experiment_figures

    figures = benchmark.pedantic(render_experiment_figures, args=(result,), rounds=2, iterations=1)
    assert "maps.png" in figures
