"""A paper job's result as typed values: what the experiments read of one (run, seed).

A job (``runs.run_job_readings``) drives one of ``runs.RUNS`` on one seed and keeps, per
reading of the paper, a :class:`JobSummary`: the run's size, each mapper's scores
(:class:`MapperResult`; Albot₁'s with homing and revisits, :class:`Albot1Result`), the
counts at each named mark, the update flags and path-integration causes, the map
accuracies asked for and, for the seed whose maps are drawn, a :class:`FigureRun` (the
map :class:`Snapshot` at each mark, the paths, the views). The experiments
(``counts``, ``table1``, ``maps_exp``, ``process_exp``) read these objects.

Jobs run on a worker pool or dask: a summary crosses the process boundary as plain data
(``to_plain``/``from_plain``: JSON types, and numpy arrays for the figures' geometry,
which pickle exactly), and nothing of it is written to a file (experiments.json holds what
the experiments computed from it).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass, field, fields
from typing import TypeAlias, TypeVar, cast

import numpy as np
from numpy.typing import NDArray

from albot2d.evaluation.metrics.egocentric import EgocentricQuality
from albot2d.evaluation.metrics.homing import HomingResult
from albot2d.evaluation.run.results import (
    EndPoseError,
    HomingStop,
    HomingSummary,
    ProcessCounts,
    RevisitEvent,
    Revisits,
)

__all__ = [
    "Albot1Result",
    "FigureRun",
    "JobSummary",
    "MapAt",
    "MapQualityAt",
    "MapperResult",
    "MarkCounts",
    "MarkSummary",
    "PathIntegrationCauses",
    "Plain",
    "PlainObject",
    "Snapshot",
    "Updates",
    "ViewAt",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
#: What crosses a process: JSON types and numpy arrays (the figures' geometry).
Plain: TypeAlias = (
    "bool | int | float | str | np.ndarray | list[Plain] | tuple[Plain, ...] "
    "| dict[str, Plain] | None"
)
PlainObject: TypeAlias = "dict[str, Plain]"
T = TypeVar("T")


def _obj(value: Plain) -> Mapping[str, Plain]:
    return cast("Mapping[str, Plain]", value)


def _make(cls: Callable[..., T], value: Plain) -> T:
    """A frozen dataclass from the dict of its fields ``asdict`` made of it (plain data
    from a worker of this very code: every field there, of its type)."""
    return cls(**_obj(value))


# -- one mapper's map at a moment ----------------------------------------------------------
@dataclass(frozen=True, eq=False)
class MapAt:
    """A mapper's global map (segments, local-map ids), pose and counts at a moment."""

    segments: FloatArray
    map_ids: IntArray
    pose: FloatArray
    views: int
    local_maps: int
    path_integrations: int

    def counts(self) -> MarkCounts:
        return MarkCounts(self.views, self.local_maps, self.path_integrations)


@dataclass(frozen=True, eq=False)
class Snapshot:
    """Every mapper's map when the robot's true distance along the route first reached a
    mark; ``reached`` is false for a mark a run cut short (``--quick``) never reached (its
    maps are the run's last)."""

    true_pose: FloatArray
    true_travelled_m: float
    frame: int
    maps: Mapping[str, MapAt]
    reached: bool = True

    def as_albot1(self, name: str, others: Sequence[str]) -> Snapshot:
        """This snapshot with the reading's Albot₁ ``name`` as ``"albot1"`` beside ``others``
        (other readings left out)."""
        maps = {"albot1": self.maps[name]} | {o: self.maps[o] for o in others}
        return Snapshot(self.true_pose, self.true_travelled_m, self.frame, maps, self.reached)


@dataclass(frozen=True, eq=False)
class ViewAt:
    """The view Albot₁ saw at a frame (surfaces, robot frame) and its global map just
    after it (map frame) with its pose there (the Fig. 15 panels)."""

    surfaces: FloatArray
    global_map: FloatArray
    pose_in_map: FloatArray


# -- the summary's parts ---------------------------------------------------------------------
@dataclass(frozen=True, slots=True)
class MarkCounts:
    views: int
    local_maps: int
    path_integrations: int


@dataclass(frozen=True)
class MarkSummary:
    """Where and when a mark was taken, the true path's digest up to it (did two runs
    drive the same path?) and every mapper's counts there."""

    true_travelled_m: float
    frame: int
    true_path_sha256: str
    counts: Mapping[str, MarkCounts]


@dataclass(frozen=True, slots=True)
class MapQualityAt:
    """Anchored map accuracy (p95, m) and surface count of a mapper at a mark."""

    accuracy_m_p95: float | None
    surfaces: int


@dataclass(frozen=True)
class Updates:
    """Per trace row: whether Albot₁ updated its global map, the region kind there, how the
    view remembered there was localised ('' if none), the tracked surfaces (-1 if no step)
    and the true position; ``waypoint_along_m``: the route's waypoints by distance along it."""

    flags: tuple[bool, ...]
    regions: tuple[str, ...]
    methods: tuple[str, ...]
    tracked: tuple[int, ...]
    true_xy: tuple[tuple[float, float], ...]
    waypoint_along_m: Mapping[str, tuple[float, ...]] | None = None


@dataclass(frozen=True)
class PathIntegrationCauses:
    """Every local map Albot₁ placed by path integration: its frame, the tracked surfaces
    left, whether the view ended a turn and the region kind; and every update's frame and
    method."""

    frames: tuple[int, ...]
    tracked: tuple[int, ...]
    turning: tuple[bool, ...]
    regions: tuple[str, ...]
    update_frames: tuple[int, ...]
    update_methods: tuple[str, ...]


@dataclass(frozen=True)
class MapperResult:
    """A mapper's counts over the run and its end-pose error."""

    counts: ProcessCounts
    end_pose_error: EndPoseError | None


@dataclass(frozen=True)
class Albot1Result(MapperResult):
    """Albot₁'s: also homing at every stop, their summary, its revisits and (runs that ask
    for it) its egocentric map quality at the end."""

    homing: tuple[HomingStop, ...] = ()
    homing_summary: HomingSummary = field(default_factory=lambda: HomingSummary(0))
    revisits: Revisits | None = None
    egocentric: EgocentricQuality | None = None


@dataclass(frozen=True, eq=False)
class FigureRun:
    """What the figures draw of the figure seed's run: the true walls, the true and
    odometry poses, the map snapshots, the waypoints, the updates and (runs that keep
    them) every view."""

    world_walls: FloatArray
    true_poses: FloatArray
    odom_poses: FloatArray
    snaps: Mapping[str, Snapshot]
    waypoints: Mapping[str, tuple[float, float]]
    updates: Updates | None
    views: tuple[ViewAt, ...] | None


@dataclass(frozen=True, eq=False)
class JobSummary:
    """One (run, seed) under one reading, in which that reading's Albot₁ is ``"albot1"``."""

    run: str
    seed: int
    quick: bool
    mappers: tuple[str, ...]
    frames: int
    travelled_m: float
    true_travelled_m: float
    tour_length_m: float | None
    world_sha256: str
    albot1: Albot1Result
    others: Mapping[str, MapperResult]
    marks: Mapping[str, MarkSummary]
    path_integration_causes: PathIntegrationCauses
    map_quality_at_marks: Mapping[str, Mapping[str, MapQualityAt]]
    reading: str
    reading_mapper: str
    updates: Updates | None = None
    fig10_deleted: int | None = None
    figures: FigureRun | None = None

    def mapper(self, name: str) -> MapperResult:
        """The results of mapper ``name`` (``"albot1"`` or one beside it)."""
        return self.albot1 if name == "albot1" else self.others[name]

    def quality(self, mark: str, mapper: str) -> MapQualityAt | None:
        """``mapper``'s map accuracy at ``mark`` when it was scored there."""
        return self.map_quality_at_marks.get(mark, {}).get(mapper)

    def counts_at(self, mark: str, mapper: str = "albot1") -> MarkCounts | None:
        """``mapper``'s counts at ``mark`` (``"end"``: over the whole run), if taken."""
        if mark == "end":
            c = self.mapper(mapper).counts
            return MarkCounts(c.views, c.local_maps, c.path_integrations)
        snap = self.marks.get(mark)
        return None if snap is None else snap.counts.get(mapper)

    def need_figures(self) -> FigureRun:
        """The figure run (the first seed's jobs keep one)."""
        if self.figures is None:
            raise ValueError(f"run {self.run} seed {self.seed} kept no figures")
        return self.figures

    # -- across a process -------------------------------------------------------------------
    def to_plain(self) -> PlainObject:
        """Plain data (JSON types and numpy arrays) for ``from_plain`` in another process."""
        return {f.name: _to_plain(getattr(self, f.name)) for f in fields(self)}

    @classmethod
    def from_plain(cls, data: Mapping[str, Plain]) -> JobSummary:
        d = dict(data)
        others = _obj(d["others"])
        quality = _obj(d["map_quality_at_marks"])
        updates, figures = d["updates"], d["figures"]
        return cls(
            run=cast(str, d["run"]), seed=cast(int, d["seed"]), quick=cast(bool, d["quick"]),
            mappers=tuple(cast("list[str]", d["mappers"])), frames=cast(int, d["frames"]),
            travelled_m=cast(float, d["travelled_m"]),
            true_travelled_m=cast(float, d["true_travelled_m"]),
            tour_length_m=cast("float | None", d["tour_length_m"]),
            world_sha256=cast(str, d["world_sha256"]),
            albot1=_albot1_result(_obj(d["albot1"])),
            others={k: _mapper_result(_obj(v)) for k, v in others.items()},
            marks={k: _mark_summary(_obj(v)) for k, v in _obj(d["marks"]).items()},
            path_integration_causes=_causes(_obj(d["path_integration_causes"])),
            map_quality_at_marks={
                mark: {n: _make(MapQualityAt, q) for n, q in _obj(per).items()}
                for mark, per in quality.items()
            },
            reading=cast(str, d["reading"]), reading_mapper=cast(str, d["reading_mapper"]),
            updates=None if updates is None else _updates(_obj(updates)),
            fig10_deleted=cast("int | None", d["fig10_deleted"]),
            figures=None if figures is None else _figure_run(_obj(figures)),
        )  # fmt: skip


def _to_plain(value: object) -> Plain:
    """A typed value as plain data: dataclasses as dicts of their fields (recursively),
    tuples as lists, numpy arrays kept."""
    if isinstance(value, np.ndarray):
        return value
    if isinstance(value, ProcessCounts | EndPoseError | HomingSummary | EgocentricQuality):
        return cast(PlainObject, asdict(value))
    if isinstance(value, HomingStop):
        return {"homing": cast(PlainObject, asdict(value.homing)),
                "travelled_m": value.travelled_m,
                "egocentric": _to_plain(value.egocentric)}  # fmt: skip
    if isinstance(value, Revisits):
        return {"min_gap_maps": value.min_gap_maps,
                "events": [cast(PlainObject, asdict(e)) for e in value.events]}  # fmt: skip
    if isinstance(value, MarkCounts | MapQualityAt):
        return cast(PlainObject, asdict(value))
    if isinstance(
        value, JobSummary | Albot1Result | MapperResult | MarkSummary | Updates
        | PathIntegrationCauses | FigureRun | Snapshot | MapAt | ViewAt,
    ):  # fmt: skip
        return {f.name: _to_plain(getattr(value, f.name)) for f in fields(value)}
    if isinstance(value, Mapping):
        return {str(k): _to_plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_to_plain(v) for v in value]
    return cast(Plain, value)


def _mapper_fields(d: Mapping[str, Plain]) -> tuple[ProcessCounts, EndPoseError | None]:
    end = d["end_pose_error"]
    return _make(ProcessCounts, d["counts"]), None if end is None else _make(EndPoseError, end)


def _mapper_result(d: Mapping[str, Plain]) -> MapperResult:
    return MapperResult(*_mapper_fields(d))


def _albot1_result(d: Mapping[str, Plain]) -> Albot1Result:
    counts, end = _mapper_fields(d)
    rev, ego = d["revisits"], d["egocentric"]
    return Albot1Result(
        counts, end,
        homing=tuple(_homing_stop(_obj(h)) for h in cast("list[Plain]", d["homing"])),
        homing_summary=_make(HomingSummary, d["homing_summary"]),
        revisits=None if rev is None else Revisits(
            cast(int, _obj(rev)["min_gap_maps"]),
            tuple(_make(RevisitEvent, e) for e in cast("list[Plain]", _obj(rev)["events"])),
        ),
        egocentric=None if ego is None else _make(EgocentricQuality, ego),
    )  # fmt: skip


def _homing_stop(d: Mapping[str, Plain]) -> HomingStop:
    ego = d["egocentric"]
    return HomingStop(
        _make(HomingResult, d["homing"]),
        cast(float, d["travelled_m"]),
        None if ego is None else _make(EgocentricQuality, ego),
    )


def _mark_summary(d: Mapping[str, Plain]) -> MarkSummary:
    return MarkSummary(
        cast(float, d["true_travelled_m"]), cast(int, d["frame"]),
        cast(str, d["true_path_sha256"]),
        {k: _make(MarkCounts, v) for k, v in _obj(d["counts"]).items()},
    )  # fmt: skip


def _causes(d: Mapping[str, Plain]) -> PathIntegrationCauses:
    return _make(
        PathIntegrationCauses,
        {f.name: tuple(cast("list[Plain]", d[f.name])) for f in fields(PathIntegrationCauses)},
    )


def _updates(d: Mapping[str, Plain]) -> Updates:
    along = d["waypoint_along_m"]
    return Updates(
        flags=tuple(cast("list[bool]", d["flags"])),
        regions=tuple(cast("list[str]", d["regions"])),
        methods=tuple(cast("list[str]", d["methods"])),
        tracked=tuple(cast("list[int]", d["tracked"])),
        true_xy=tuple((p[0], p[1]) for p in cast("list[list[float]]", d["true_xy"])),
        waypoint_along_m=None if along is None else {
            k: tuple(cast("list[float]", v)) for k, v in _obj(along).items()
        },
    )  # fmt: skip


def _map_at(d: Mapping[str, Plain]) -> MapAt:
    return MapAt(
        cast(FloatArray, d["segments"]), cast(IntArray, d["map_ids"]),
        cast(FloatArray, d["pose"]), cast(int, d["views"]), cast(int, d["local_maps"]),
        cast(int, d["path_integrations"]),
    )  # fmt: skip


def _snapshot(d: Mapping[str, Plain]) -> Snapshot:
    return Snapshot(
        cast(FloatArray, d["true_pose"]), cast(float, d["true_travelled_m"]),
        cast(int, d["frame"]), {k: _map_at(_obj(v)) for k, v in _obj(d["maps"]).items()},
        cast(bool, d["reached"]),
    )  # fmt: skip


def _figure_run(d: Mapping[str, Plain]) -> FigureRun:
    updates, views = d["updates"], d["views"]
    return FigureRun(
        world_walls=cast(FloatArray, d["world_walls"]),
        true_poses=cast(FloatArray, d["true_poses"]),
        odom_poses=cast(FloatArray, d["odom_poses"]),
        snaps={k: _snapshot(_obj(v)) for k, v in _obj(d["snaps"]).items()},
        waypoints={k: cast("tuple[float, float]", tuple(cast("list[float]", v)))
                   for k, v in _obj(d["waypoints"]).items()},
        updates=None if updates is None else _updates(_obj(updates)),
        views=None if views is None else tuple(
            ViewAt(*(cast(FloatArray, _obj(v)[k])
                     for k in ("surfaces", "global_map", "pose_in_map")))
            for v in cast("list[Plain]", views)
        ),
    )  # fmt: skip
