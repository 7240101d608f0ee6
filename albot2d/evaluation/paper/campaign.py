"""Run the paper's experiments over seeds on a campaign backend and gather the results.

Jobs are (run, seed) pairs (``runs.RUNS``), each run once however many experiments read it;
they go to the backend (``albot2d.evaluation.fuzz.backends``: a local process pool or dask), and
each experiment is computed from the job summaries in seed order once all are in, so the
results are the same bit for bit whatever the number of workers or the backend. Only the
first seed's runs keep the map snapshots the figures are drawn from.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, NotRequired, TypedDict

from albot2d.errors import InputError
from albot2d.evaluation.paper.jobs import FigureRun, JobSummary, PlainObject
from albot2d.evaluation.paper.outputs import ExperimentOutput, FigureSpec
from albot2d.evaluation.paper.registry import EXPERIMENTS, PAPER_FIGURES, runs_needed
from albot2d.evaluation.paper.runs import (
    ALBOT_X,
    PAPER_NOISE,
    RUNS,
    albot_x_available,
    reading_spec,
    run_job_readings,
)

__all__ = [
    "ExperimentsOutcome",
    "check_readings",
    "compute_experiments",
    "compute_readings",
    "plan_jobs",
    "run_experiments",
]

if TYPE_CHECKING:
    from albot2d.evaluation.fuzz.backends import Backend

FORMAT_VERSION = 1


class RunSeedInfo(TypedDict):
    frames: int
    travelled_m: float
    tour_length_m: float | None
    world_sha256: str


class RunInfo(TypedDict):
    spec: dict[str, object]
    per_seed: dict[str, RunSeedInfo]


class ExperimentsData(TypedDict):
    """experiments.json (a JSON document: the page reads it as such)."""

    command: str
    format_version: int
    seeds: list[int]
    quick: bool
    odometry_noise: str
    albot_x: str | None
    verdicts: dict[str, str]
    experiments: dict[str, ExperimentOutput]
    runs: dict[str, RunInfo]
    wall_time_s: float
    readings: NotRequired[dict[str, str]]
    verdicts_by_reading: NotRequired[dict[str, dict[str, str]]]


@dataclass(eq=False)
class ExperimentsOutcome:
    """``data`` is experiments.json's content; ``figures`` per experiment the figure specs
    (file, plot kind, caption, plain data) for the interface layer to draw; ``runs`` the
    job summaries they were computed from (run → one per seed)."""

    data: ExperimentsData
    figures: dict[str, list[FigureSpec]]
    runs: Mapping[str, Sequence[JobSummary]]


class _FigureRuns(Mapping[str, FigureRun]):
    """Each run's figure run (its first seed's, which keeps one), read when a figure asks."""

    def __init__(self, by_run: Mapping[str, Sequence[JobSummary]]) -> None:
        self._by_run = by_run

    def __getitem__(self, run: str) -> FigureRun:
        return self._by_run[run][0].need_figures()

    def __iter__(self) -> Iterator[str]:
        return iter(self._by_run)

    def __len__(self) -> int:
        return len(self._by_run)


def _captioned(spec: FigureSpec, caption: str) -> FigureSpec:
    out = spec.copy()
    out["caption"] = caption
    return out


def _renamed(spec: FigureSpec, file: str) -> FigureSpec:
    out = spec.copy()
    out["file"] = file
    return out


def plan_jobs(names: Sequence[str], seeds: Sequence[int]) -> list[tuple[str, int]]:
    """Every (run, seed) the experiments ``names`` need, runs in order, then seeds."""
    unknown = [n for n in names if n not in EXPERIMENTS]
    if unknown:
        raise InputError(f"unknown experiment {unknown[0]!r}; valid: {', '.join(EXPERIMENTS)}")
    if not seeds:
        raise InputError("no seeds to run")
    return [(run, seed) for run in runs_needed(list(names)) for seed in seeds]


def _job(
    jobs: tuple[tuple[str, int], ...],
    quick: bool,
    albot_x: bool,
    figure_seed: int,
    readings: tuple[str, ...],
    index: int,
) -> dict[str, PlainObject]:
    """What a worker runs: one (run, seed) under every reading; the summaries go back as
    plain data (``JobSummary.to_plain``)."""
    run, seed = jobs[index]
    out = run_job_readings(
        run, seed, quick=quick, albot_x=albot_x, keep_figures=seed == figure_seed,
        readings=readings,
    )  # fmt: skip
    return {reading: summary.to_plain() for reading, summary in out.items()}


def check_readings(readings: Sequence[str]) -> tuple[str, ...]:
    """The readings, each checked (``runs.reading_spec``), duplicates refused."""
    out = tuple(readings)
    if not out:
        raise InputError("--readings: give at least one reading")
    from albot2d.mapping.registry import mapper_factory

    params = [getattr(mapper_factory(reading_spec(r))(), "params", None) for r in out]
    for k, p in enumerate(params):
        if p in params[:k]:
            raise InputError(f"--readings: {out[k]!r} runs the same mapper as an earlier one")
    return out


def run_experiments(
    names: Sequence[str],
    seeds: Sequence[int],
    *,
    quick: bool = False,
    backend: Backend | None = None,
    on_job: Callable[[str, int], None] | None = None,
    readings: Sequence[str] = ("default",),
) -> ExperimentsOutcome:
    """Compute the experiments ``names`` over ``seeds`` under each of ``readings`` (the
    first is the primary one, whose results are also each experiment's top-level
    ``ours``/``verdict``); every reading's Albot₁ drives the same frames of one run per
    (run, seed). ``backend`` defaults to this process; ``on_job(run, seed)`` is called as
    each job finishes (progress)."""
    from albot2d.evaluation.fuzz.backends import LocalBackend

    t0 = time.perf_counter()
    names = list(names)
    seeds = [int(s) for s in seeds]
    jobs = tuple(plan_jobs(names, seeds))
    readings = check_readings(readings)
    albot_x = albot_x_available()
    runner: Backend = backend or LocalBackend(1)
    results: dict[tuple[str, int], dict[str, JobSummary]] = {}
    for index, result in runner.map_unordered(
        _job, range(len(jobs)), jobs, quick, albot_x, seeds[0], readings
    ):
        if isinstance(result, BaseException):
            run, seed = jobs[index]
            raise RuntimeError(f"run {run} seed {seed} failed: {result!r}") from result
        results[jobs[index]] = {
            reading: JobSummary.from_plain(summary) for reading, summary in result.items()
        }
        if on_job is not None:
            on_job(*jobs[index])
    runs = list(dict.fromkeys(r for r, _ in jobs))
    by_reading = {
        reading: {run: [results[(run, s)][reading] for s in seeds] for run in runs}
        for reading in readings
    }
    return compute_readings(names, seeds, by_reading, quick=quick, albot_x=albot_x, started=t0)


def compute_readings(
    names: Sequence[str],
    seeds: Sequence[int],
    by_reading: Mapping[str, Mapping[str, Sequence[JobSummary]]],
    *,
    quick: bool,
    albot_x: bool,
    started: float | None = None,
) -> ExperimentsOutcome:
    """Every experiment under every reading (``by_reading``: reading → run → summaries in
    seed order; the first reading is the primary one). Each experiment's result is the
    primary reading's, with ``readings`` holding every reading's ``ours``, ``verdict`` and
    notes side by side; a non-primary reading's figures are prefixed with its name."""
    t0 = time.perf_counter() if started is None else started
    readings = list(by_reading)
    outcomes = {
        reading: compute_experiments(names, seeds, by_run, quick=quick, albot_x=albot_x,
                                     started=t0, figure_prefix="" if k == 0 else f"{reading}-")
        for k, (reading, by_run) in enumerate(by_reading.items())
    }  # fmt: skip
    primary = outcomes[readings[0]]
    data = primary.data
    figures: dict[str, list[FigureSpec]] = {}
    for name in names:
        result = data["experiments"][name]
        result["reading"] = readings[0]
        result["readings"] = {
            reading: {
                "mapper": reading_spec(reading),
                "ours": out.data["experiments"][name]["ours"],
                "verdict": out.data["experiments"][name]["verdict"],
                "notes": out.data["experiments"][name].get("notes", []),
                "figures": out.data["experiments"][name]["figures"],
            }
            for reading, out in outcomes.items()
        }
        figures[name] = [
            _captioned(f, f"{reading}: {f['caption']}") if len(readings) > 1 else f
            for reading, out in outcomes.items()
            for f in out.figures[name]
        ]
    data["readings"] = {reading: reading_spec(reading) for reading in readings}
    data["verdicts_by_reading"] = {
        name: {r: out.data["verdicts"][name] for r, out in outcomes.items()} for name in names
    }
    data["wall_time_s"] = time.perf_counter() - t0
    return ExperimentsOutcome(data, figures, primary.runs)


def compute_experiments(
    names: Sequence[str],
    seeds: Sequence[int],
    by_run: Mapping[str, Sequence[JobSummary]],
    *,
    quick: bool,
    albot_x: bool,
    started: float | None = None,
    figure_prefix: str = "",
) -> ExperimentsOutcome:
    """Every experiment of ``names`` from the job summaries ``by_run`` (run → one summary
    per seed, in seed order); figure files are named with ``figure_prefix`` first."""
    names, seeds = list(names), list(seeds)
    t0 = time.perf_counter() if started is None else started
    experiments: dict[str, ExperimentOutput] = {}
    figures: dict[str, list[FigureSpec]] = {}
    for name in names:
        exp = EXPERIMENTS[name]
        result = exp.compute(by_run, seeds)
        drawn = _FigureRuns(by_run)
        figures[name] = [_renamed(f, figure_prefix + f["file"]) for f in exp.figures(drawn, result)]
        result["figures"] = [f["file"] for f in figures[name]]
        result["paper_figure"] = PAPER_FIGURES.get(name)
        result["figure_seed"] = seeds[0]
        experiments[name] = result
    runs_info: dict[str, RunInfo] = {
        run: {"spec": {k: v for k, v in vars(RUNS[run]).items() if k != "world_params"}
                      | {"world_params": dict(RUNS[run].world_params)},
              "per_seed": {str(j.seed): {"frames": j.frames,
                                         "travelled_m": j.travelled_m,
                                         "tour_length_m": j.tour_length_m,
                                         "world_sha256": j.world_sha256}
                           for j in rows}}
        for run, rows in by_run.items()
    }  # fmt: skip
    data: ExperimentsData = {
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
