"""Typed results of scoring a run (``scoring.score_run``): frozen values, one per section.

report.json's ``odometry`` and ``mappers`` sections, the printed tables
(``report.format_summary_table``/``format_homing_table``), the figures and a fuzzing
episode's metrics are all views of a :class:`RunScores`; ``to_dict()`` gives the exact
report.json section (missing values ``None``, written as ``null``).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from albot2d.evaluation.metrics.alignment import AbsolutePoseError
from albot2d.evaluation.metrics.egocentric import EgocentricQuality
from albot2d.evaluation.metrics.homing import HomingResult
from albot2d.evaluation.metrics.map_quality import MapQuality
from albot2d.evaluation.metrics.rpe import RPEResult

__all__ = [
    "EndPoseError",
    "HomingStop",
    "HomingSummary",
    "MapScore",
    "MapperScores",
    "OdometryScores",
    "ProcessCounts",
    "RevisitEvent",
    "Revisits",
    "RunScores",
    "Snapshot",
]


def _dict_or_none(value: Any) -> Any:
    return None if value is None else value.to_dict()


@dataclass(frozen=True, slots=True)
class HomingStop:
    """Homing at one stop, and the egocentric map quality there (simulation only)."""

    homing: HomingResult
    travelled_m: float
    egocentric: EgocentricQuality | None = None

    def to_dict(self) -> dict[str, Any]:
        h, ego = self.homing, self.egocentric
        return {
            "view": h.view,
            "travelled_m": self.travelled_m,
            "bearing_est_deg": h.bearing_est_deg,
            "bearing_true_deg": h.bearing_true_deg,
            "distance_est_m": h.distance_est_m,
            "distance_true_m": h.distance_true_m,
            "bearing_error_deg": h.bearing_error_deg,
            "distance_error_m": h.distance_error_m,
            "egocentric_completeness": None if ego is None else ego.completeness,
            "egocentric_accuracy_m_p95": None if ego is None else ego.accuracy_m_p95,
        }


@dataclass(frozen=True, slots=True)
class HomingSummary:
    """Worst and mean absolute homing errors (None without truth or stops)."""

    stops: int
    bearing_abs_max_deg: float | None = None
    bearing_abs_mean_deg: float | None = None
    distance_abs_max_m: float | None = None
    distance_abs_mean_m: float | None = None

    @classmethod
    def of(cls, stops: tuple[HomingStop, ...]) -> HomingSummary:
        errors = [
            (s.homing.bearing_error_deg, s.homing.distance_error_m)
            for s in stops
            if s.homing.bearing_error_deg is not None
        ]
        if not errors:
            return cls(len(stops))
        b, d = np.abs(np.array(errors, dtype=np.float64)).T
        return cls(len(stops), float(b.max()), float(b.mean()), float(d.max()), float(d.mean()))

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


@dataclass(frozen=True, slots=True)
class ProcessCounts:
    """What the mapper did: views, local maps, how each was placed, map size, update spacing.

    ``loop_closures`` only for loop-closing mappers (``slam_stats``); absent otherwise.
    """

    views: int
    local_maps: int
    triangulations: int
    path_integrations: int
    global_map_surfaces: int
    moves_between_updates_mean: float | None
    moves_between_updates_max: int | None = None
    metres_between_updates_mean: float | None = None
    loop_closures: Mapping[str, int] | None = None

    def to_dict(self) -> dict[str, Any]:
        out = asdict(self)
        if self.loop_closures is None:
            del out["loop_closures"]
        else:
            out["loop_closures"] = dict(self.loop_closures)
        return out


@dataclass(frozen=True, slots=True)
class EndPoseError:
    """Error of the estimated motion from the first to the last view."""

    trans_m: float
    rot_deg: float

    def to_dict(self) -> dict[str, float]:
        return asdict(self)


@dataclass(frozen=True, slots=True)
class MapScore:
    """Map quality anchored at the start (None fields on real logs) and egocentric."""

    quality: MapQuality
    egocentric: EgocentricQuality | None

    def to_dict(self) -> dict[str, Any]:
        return self.quality.to_dict() | {"egocentric": _dict_or_none(self.egocentric)}


@dataclass(frozen=True, slots=True)
class Snapshot:
    """One moment of a view-based mapper's map history."""

    view: int
    row: int
    travelled_m: float
    update: int
    surfaces: int

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


@dataclass(frozen=True, slots=True)
class RevisitEvent:
    """A global-map update whose view touched a map ``map_id - oldest_map`` maps back."""

    map_id: int
    view: int
    oldest_map: int
    deleted: int

    def to_dict(self) -> dict[str, int]:
        return asdict(self)


@dataclass(frozen=True, slots=True)
class Revisits:
    """Transience on revisits (paper Fig. 10): the revisiting updates and their deletions."""

    min_gap_maps: int
    events: tuple[RevisitEvent, ...]

    @property
    def updates(self) -> int:
        return len(self.events)

    @property
    def deleted_surfaces(self) -> int:
        return int(sum(e.deleted for e in self.events))

    def to_dict(self) -> dict[str, Any]:
        return {
            "min_gap_maps": self.min_gap_maps,
            "updates": self.updates,
            "deleted_surfaces": self.deleted_surfaces,
            "events": [e.to_dict() for e in self.events],
        }


@dataclass(frozen=True, slots=True)
class OdometryScores:
    """Raw odometry scored like a mapper (None where the truth or relations are missing)."""

    rpe: RPEResult | None
    end_pose_error: EndPoseError | None
    ape: AbsolutePoseError | None

    def to_dict(self) -> dict[str, Any]:
        return {
            "rpe": _dict_or_none(self.rpe),
            "end_pose_error": _dict_or_none(self.end_pose_error),
            "ape": _dict_or_none(self.ape),
        }


@dataclass(frozen=True, slots=True)
class MapperScores:
    """Every score of one mapper: report.json's ``mappers.NAME``.

    ``snapshots``/``revisits`` are None for mappers that are not view-based. The
    ``updates_by_region`` section (paper Fig. 14) is scored on simulated runs only
    (``regions_scored``); on a replayed log it is absent from the report.
    """

    counts: ProcessCounts
    homing: tuple[HomingStop, ...]
    homing_summary: HomingSummary
    rpe: RPEResult | None
    end_pose_error: EndPoseError | None
    ape: AbsolutePoseError | None
    map: MapScore
    snapshots: tuple[Snapshot, ...] | None
    revisits: Revisits | None
    timing_ms: Mapping[str, float]
    updates_by_region: Mapping[str, Any] | None = None
    regions_scored: bool = False

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "counts": self.counts.to_dict(),
            "homing": [s.to_dict() for s in self.homing],
            "homing_summary": self.homing_summary.to_dict(),
            "rpe": _dict_or_none(self.rpe),
            "end_pose_error": _dict_or_none(self.end_pose_error),
            "ape": _dict_or_none(self.ape),
            "map": self.map.to_dict(),
            "snapshots": None if self.snapshots is None else [s.to_dict() for s in self.snapshots],
            "revisits": _dict_or_none(self.revisits),
            "timing_ms": dict(self.timing_ms),
        }
        if self.regions_scored:
            out["updates_by_region"] = self.updates_by_region
        return out


@dataclass(frozen=True, slots=True)
class RunScores:
    """Raw odometry's and every mapper's scores (mappers in the order they were given)."""

    odometry: OdometryScores
    mappers: Mapping[str, MapperScores] = field(default_factory=dict)

    def mappers_dict(self) -> dict[str, dict[str, Any]]:
        """report.json's ``mappers`` section."""
        return {name: scores.to_dict() for name, scores in self.mappers.items()}
