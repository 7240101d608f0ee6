"""Run the paper's experiments over seeds on a campaign backend and gather the results.

Jobs are (run, seed) pairs (``runs.RUNS``), each run once however many experiments read it;
they go to the backend (``albot2d.evaluation.fuzz.backends``: a local process pool or dask), and
each experiment is computed from the job summaries in seed order once all are in, so the
results are the same bit for bit whatever the number of workers or the backend. Only the
first seed's runs keep the map snapshots the figures are drawn from.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from albot2d.errors import InputError
from albot2d.evaluation.paper.registry import EXPERIMENTS, runs_needed
from albot2d.evaluation.paper.runs import ALBOT_X, PAPER_NOISE, RUNS, albot_x_available, run_job

__all__ = ["ExperimentsOutcome", "compute_experiments", "plan_jobs", "run_experiments"]

FORMAT_VERSION = 1


@dataclass(eq=False)
class ExperimentsOutcome:
    """``data`` is experiments.json's content; ``figures`` per experiment the figure specs
    (file, plot kind, caption, plain data) for the interface layer to draw."""

    data: dict[str, Any]
    figures: dict[str, list[dict[str, Any]]]
    runs: dict[str, list[dict[str, Any]]]


def plan_jobs(names: Sequence[str], seeds: Sequence[int]) -> list[tuple[str, int]]:
    """Every (run, seed) the experiments ``names`` need, runs in order, then seeds."""
    unknown = [n for n in names if n not in EXPERIMENTS]
    if unknown:
        raise InputError(f"unknown experiment {unknown[0]!r}; valid: {', '.join(EXPERIMENTS)}")
    if not seeds:
        raise InputError("no seeds to run")
    return [(run, seed) for run in runs_needed(list(names)) for seed in seeds]


def _job(
    jobs: tuple[tuple[str, int], ...], quick: bool, albot_x: bool, figure_seed: int, index: int
) -> dict[str, Any]:
    run, seed = jobs[index]
    return run_job(run, seed, quick=quick, albot_x=albot_x, keep_figures=seed == figure_seed)


def run_experiments(
    names: Sequence[str],
    seeds: Sequence[int],
    *,
    quick: bool = False,
    backend: Any = None,
    on_job: Callable[[str, int], None] | None = None,
) -> ExperimentsOutcome:
    """Compute the experiments ``names`` over ``seeds``; ``backend`` defaults to this
    process; ``on_job(run, seed)`` is called as each job finishes (progress)."""
    from albot2d.evaluation.fuzz.backends import LocalBackend

    t0 = time.perf_counter()
    names = list(names)
    seeds = [int(s) for s in seeds]
    jobs = tuple(plan_jobs(names, seeds))
    albot_x = albot_x_available()
    backend = backend or LocalBackend(1)
    results: dict[tuple[str, int], dict[str, Any]] = {}
    for index, result in backend.map_unordered(
        _job, range(len(jobs)), jobs, quick, albot_x, seeds[0]
    ):
        if isinstance(result, BaseException):
            run, seed = jobs[index]
            raise RuntimeError(f"run {run} seed {seed} failed: {result!r}") from result
        results[jobs[index]] = result
        if on_job is not None:
            on_job(*jobs[index])
    by_run = {run: [results[(run, s)] for s in seeds] for run in dict.fromkeys(r for r, _ in jobs)}
    return compute_experiments(names, seeds, by_run, quick=quick, albot_x=albot_x, started=t0)


def compute_experiments(
    names: Sequence[str],
    seeds: Sequence[int],
    by_run: dict[str, list[dict[str, Any]]],
    *,
    quick: bool,
    albot_x: bool,
    started: float | None = None,
) -> ExperimentsOutcome:
    """Every experiment of ``names`` from the job summaries ``by_run`` (run → one summary
    per seed, in seed order)."""
    names, seeds = list(names), list(seeds)
    t0 = time.perf_counter() if started is None else started
    figure_runs = {run: rows[0]["figures"] for run, rows in by_run.items()}
    experiments: dict[str, Any] = {}
    figures: dict[str, list[dict[str, Any]]] = {}
    for name in names:
        exp = EXPERIMENTS[name]
        result = exp.compute(by_run, seeds)
        figures[name] = exp.figures(figure_runs, result)
        result["figures"] = [f["file"] for f in figures[name]]
        result["figure_seed"] = seeds[0]
        experiments[name] = result
    runs_info = {
        run: {"spec": {k: v for k, v in vars(RUNS[run]).items() if k != "world_params"}
                      | {"world_params": dict(RUNS[run].world_params)},
              "per_seed": {str(j["seed"]): {"frames": j["frames"],
                                            "travelled_m": j["travelled_m"],
                                            "tour_length_m": j["tour_length_m"],
                                            "world_sha256": j["world_sha256"]}
                           for j in rows}}
        for run, rows in by_run.items()
    }  # fmt: skip
    data = {
        "command": "experiments",
        "format_version": FORMAT_VERSION,
        "seeds": seeds,
        "quick": quick,
        "odometry_noise": PAPER_NOISE,
        "albot_x": ALBOT_X if albot_x else None,
        "verdicts": {n: experiments[n]["verdict"] for n in names},
        "experiments": experiments,
        "runs": runs_info,
        "wall_time_s": time.perf_counter() - t0,
    }
    return ExperimentsOutcome(data, figures, by_run)
