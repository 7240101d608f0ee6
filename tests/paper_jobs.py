"""Hand-built job summaries of the paper's experiments (``albot2d.evaluation.paper.jobs``):
a whole ``JobSummary`` with neutral values, and the parts the experiment tests vary."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from albot2d.evaluation.metrics.homing import HomingResult
from albot2d.evaluation.paper.jobs import (
    Albot1Result,
    FigureRun,
    JobSummary,
    MapQualityAt,
    MarkCounts,
    MarkSummary,
    PathIntegrationCauses,
    Updates,
)
from albot2d.evaluation.run.results import HomingStop, HomingSummary, ProcessCounts

__all__ = [
    "JobSummary",
    "Updates",
    "counts",
    "homing_stop",
    "job",
    "mark",
    "no_causes",
    "quality",
    "updates",
]


def counts(views: int = 0, local_maps: int = 0, path_integrations: int = 0) -> ProcessCounts:
    return ProcessCounts(views, local_maps, local_maps - path_integrations, path_integrations,
                         0, None)  # fmt: skip


def mark(
    frame: int = 0, mapper_counts: Mapping[str, MarkCounts] | None = None, path: str = "0" * 64
) -> MarkSummary:
    return MarkSummary(0.0, frame, path, dict(mapper_counts or {}))


def homing_stop(distance_true_m: float, bearing_error_deg: float, distance_error_m: float,
                travelled_m: float = 1.0) -> HomingStop:  # fmt: skip
    """A stop ``distance_true_m`` from S, its bearing and distance off by the errors given."""
    return HomingStop(
        HomingResult(view=1, bearing_est_deg=bearing_error_deg, bearing_true_deg=0.0,
                     distance_est_m=distance_true_m + distance_error_m,
                     distance_true_m=distance_true_m),
        travelled_m,
    )  # fmt: skip


def quality(**p95_by_mapper: float) -> dict[str, MapQualityAt]:
    return {name: MapQualityAt(p95, 100) for name, p95 in p95_by_mapper.items()}


def no_causes() -> PathIntegrationCauses:
    return PathIntegrationCauses((), (), (), (), (), ())


def updates(
    true_xy: Sequence[Sequence[float]], methods: Sequence[str], tracked: Sequence[int],
    regions: Sequence[str], along: Mapping[str, Sequence[float]] | None = None,
) -> Updates:  # fmt: skip
    return Updates(
        flags=tuple(bool(m) for m in methods), regions=tuple(regions), methods=tuple(methods),
        tracked=tuple(tracked), true_xy=tuple((float(x), float(y)) for x, y in true_xy),
        waypoint_along_m=None if along is None else {k: tuple(v) for k, v in along.items()},
    )  # fmt: skip


def job(
    *,
    seed: int = 0,
    run: str = "toy",
    end_counts: ProcessCounts | None = None,
    homing: Sequence[HomingStop] = (),
    marks: Mapping[str, MarkSummary] | None = None,
    quality_at: Mapping[str, Mapping[str, MapQualityAt]] | None = None,
    causes: PathIntegrationCauses | None = None,
    steps: Updates | None = None,
    figures: FigureRun | None = None,
    **fields: Any,
) -> JobSummary:
    """A job summary of Albot₁ alone, every part neutral unless given."""
    values: dict[str, Any] = dict(
        run=run, seed=seed, quick=False, mappers=("albot1",), frames=10, travelled_m=30.0,
        true_travelled_m=30.0, tour_length_m=30.0, world_sha256="0" * 64,
        albot1=Albot1Result(end_counts or counts(), None, homing=tuple(homing),
                            homing_summary=HomingSummary(len(homing))),
        others={}, marks=dict(marks or {}), path_integration_causes=causes or no_causes(),
        map_quality_at_marks={k: dict(v) for k, v in (quality_at or {}).items()},
        reading="default", reading_mapper="albot1", updates=steps, figures=figures,
    )  # fmt: skip
    values.update(fields)
    return JobSummary(**values)
