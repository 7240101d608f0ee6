"""What an experiment of the paper is and what it gives: the shapes of experiments.json.

An experiment (``counts``, ``table1``, the ``maps_exp`` and ``process_exp`` figures) is
anything with a ``NAME``, a ``CLAIM``, the ``RUNS`` it reads and two functions:
``compute(jobs, seeds)`` turns the typed job summaries (``jobs.JobSummary``, run → one
per seed) into its :class:`ExperimentOutput`, and ``figures(runs, output)`` turns the
figure seed's runs (``jobs.FigureRun``) into :class:`FigureSpec` s for the interface layer
to draw. Both outputs are JSON documents (experiments.json, the page, the viz layer read
them as such), so they are ``TypedDict`` s: their key order is the file's.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import NotRequired, Protocol, TypedDict

from albot2d.evaluation.paper.jobs import FigureRun, JobSummary

__all__ = ["Experiment", "ExperimentOutput", "FigureSpec", "OverSeeds", "ReadingOutput"]


class OverSeeds(TypedDict):
    """A number over seeds: mean ± sd (sample sd) of the values there are, and each seed's."""

    mean: float | None
    sd: float | None
    n: int
    per_seed: dict[str, float | None]


class FigureSpec(TypedDict):
    """A figure to draw: its file, the plot kind (``albot2d.viz.paper.PLOTS``), its caption
    and the plain data the plot reads."""

    file: str
    plot: str
    caption: str
    data: Mapping[str, object]


class ReadingOutput(TypedDict):
    """One reading's result of an experiment, beside the others'."""

    mapper: str
    ours: Mapping[str, object]
    verdict: str
    notes: list[str]
    figures: list[str]


class ExperimentOutput(TypedDict):
    """An experiment's entry of experiments.json: the paper's claim and numbers, ours, the
    verdict and the rule it follows; then, once computed, its figure files and where in
    the paper it is, and the readings side by side."""

    claim: str
    paper: Mapping[str, object]
    ours: Mapping[str, object]
    verdict: str
    rule: str
    notes: NotRequired[list[str]]
    figures: NotRequired[list[str]]
    paper_figure: NotRequired[str | None]
    figure_seed: NotRequired[int]
    reading: NotRequired[str]
    readings: NotRequired[dict[str, ReadingOutput]]


class Experiment(Protocol):
    """One of the paper's experiments (a module or a class of static methods)."""

    @property
    def NAME(self) -> str: ...  # noqa: N802 - the experiments' own constant
    @property
    def RUNS(self) -> tuple[str, ...]: ...  # noqa: N802

    def compute(
        self, jobs: Mapping[str, Sequence[JobSummary]], seeds: Sequence[int]
    ) -> ExperimentOutput: ...

    def figures(
        self, fig: Mapping[str, FigureRun], result: ExperimentOutput
    ) -> list[FigureSpec]: ...
