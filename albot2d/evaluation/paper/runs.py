"""The simulated runs the paper's experiments are computed from, one job per (run, seed).

Every run goes through the one setup path, ``run_experiment(RunSpec(...), score=False)``,
and is scored here only for what the experiments read; a job returns a small JSON-ready
summary (counts, homing stops, the map accuracies asked for, update flags, why each
path integration happened) and, for the seed whose maps are drawn, the map snapshots the
figures need. Snapshots are taken while
the run goes (``on_frame``) when the robot's *true* distance along the route first reaches
a named waypoint, so "the map at E5" is the map when the robot got to E5.

Albot_x (the paper's SLAM robot) is the ``slam`` mapper when it can be made here (the
``slam`` extra), otherwise ``naive`` stands in and the experiments say so; ``naive`` is
the paper's "Albot_x without correcting sensor errors" of Fig. 16.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from albot2d.errors import InputError
from albot2d.evaluation.paper.jobs import (
    Albot1Result,
    FigureRun,
    FloatArray,
    JobSummary,
    MapAt,
    MapperResult,
    MapQualityAt,
    MarkSummary,
    PathIntegrationCauses,
    Snapshot,
    Updates,
    ViewAt,
)

if TYPE_CHECKING:
    from albot2d.evaluation.run.experiment import ExperimentResult
    from albot2d.evaluation.run.setup import RunSpec
    from albot2d.evaluation.run.trace import Trace
    from albot2d.frames import Frame
    from albot2d.mapping.albot1.mapper import Albot1, StepRecord
    from albot2d.mapping.protocol import Mapper
    from worldgen.world import Tour, World

__all__ = [
    "ALBOT_X",
    "DEFAULT_READINGS",
    "PAPER_NOISE",
    "READINGS",
    "RUNS",
    "PaperRun",
    "albot_x_available",
    "reading_spec",
    "run_job",
    "run_job_readings",
]

ALBOT_X = "slam"
# odometry noise of every paper run: the preset derived from the P3-DX's published data
PAPER_NOISE = "pioneer3dx"
# In --quick mode every continuous run stops after this many views (start-stop runs,
# a few dozen views each, are run whole).
QUICK_MAX_FRAMES = 150


@dataclass(frozen=True)
class PaperRun:
    """One kind of run: world, route or tour, driving profile, and what to keep of it.

    ``mappers``: the mappers beside Albot₁ (``"x"`` is Albot_x: the ``slam`` mapper, or
    ``naive`` where slam cannot be made). ``marks`` names the moments at which every
    mapper's map is kept (for figures): a waypoint name (its first passage; ``NAME#2`` the
    second) or ``half`` / ``end``. ``quality``: mark → the mappers whose map accuracy is
    scored there (the only map scoring done, as the experiments read nothing else);
    ``egocentric_end``: Albot₁'s egocentric map quality at the end is scored.
    """

    name: str
    kind: str
    profile: str
    route: str | None = None
    tour_kind: str = "loop"
    tour_length_m: float = 100.0
    world_params: Mapping[str, float] = field(default_factory=dict)
    mappers: tuple[str, ...] = ()
    stop_every_m: float = 20.0
    marks: tuple[str, ...] = ()
    quality: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    egocentric_end: bool = False
    steps: bool = False  # keep Albot1's per-view step records (Figs. 14, 15)
    views: bool = False  # keep every view and Albot1's map after it, for the figure seed
    quick_cut: bool = True  # shortened in --quick mode


RUNS: dict[str, PaperRun] = {
    r.name: r
    for r in (
        PaperRun("fig6_dataset1", "fig6", "dataset1", route="fig6", mappers=("naive", "x"),
                 marks=("E5", "E1#2", "E7", "end"),
                 quality={"E5": ("albot1", "x"), "E7": ("albot1", "naive")}),
        # Fig. 16 and the path-integration count read dataset 2 at E7 only: its route ends there
        PaperRun("fig6_dataset2", "fig6", "dataset2", route="fig16", mappers=("naive",),
                 marks=("E7",), quality={"E7": ("albot1", "naive")}),
        PaperRun("fig6_dataset3", "fig6", "dataset3", route="fig6", mappers=("x",),
                 marks=("E5", "end"), egocentric_end=True),
        PaperRun("fig6_start_stop", "fig6", "start_stop", route="fig6", marks=("E5",),
                 steps=True),
        PaperRun("fig8_anticlockwise", "fig6", "start_stop", route="fig8_anticlockwise",
                 stop_every_m=4.0),
        PaperRun("fig8_clockwise", "fig6", "start_stop", route="fig8_clockwise",
                 stop_every_m=4.0),
        PaperRun("fig15_room", "fig6", "start_stop", route="fig15", steps=True,
                 views=True),
        # Fig. 16's route (S → E7) with dataset 1 and Albot₁ alone: path-integration counts
        # of several readings (``paper.readings_counts``); no experiment reads it
        PaperRun("fig16_dataset1", "fig6", "dataset1", route="fig16", marks=("E7",)),
        PaperRun("fig16_dataset2", "fig6", "dataset2", route="fig16", marks=("E7",)),
        PaperRun("fig11_open", "open", "dataset3", tour_kind="loop", tour_length_m=130.0,
                 mappers=("x",), marks=("half", "end"),
                 quality={"half": ("albot1",), "end": ("albot1", "x")}, egocentric_end=True),
    )
}  # fmt: skip


def albot_x_available() -> bool:
    """Whether the ``slam`` mapper (Albot_x) can be made in this environment."""
    from albot2d.mapping.registry import resolve_mappers

    try:
        resolve_mappers([ALBOT_X])["slam"]()
    except (InputError, ImportError):
        return False
    return True


def _mark_targets(world: World, run: PaperRun, tour_length_m: float) -> dict[str, float]:
    """True distance along the tour at which each mark is taken."""
    targets: dict[str, float] = {}
    along: dict[str, list[float]] = {}
    if run.route is not None:
        from worldgen.routes import waypoint_arclength_m

        along = waypoint_arclength_m(world, run.route)
    for mark in run.marks:
        if mark == "end":
            continue  # taken after the last frame
        if mark == "half":
            targets[mark] = 0.5 * tour_length_m
            continue
        name, _, nth = mark.partition("#")
        visits = along.get(name, [])
        k = int(nth or 1) - 1
        if k < len(visits):
            targets[mark] = visits[k]
    return targets


def _snapshot(
    mappers: Mapping[str, Mapper], true_pose: FloatArray, travelled: float, frame_index: int
) -> Snapshot:
    maps = {}
    for name, m in mappers.items():
        snap = m.global_map()
        counts = m.counts()
        maps[name] = MapAt(
            segments=np.asarray(snap.segments, float).copy(),
            map_ids=np.asarray(snap.map_ids).copy(),
            pose=m.pose().as_array(),
            views=counts.views,
            local_maps=counts.local_maps,
            path_integrations=counts.path_integrations,
        )
    return Snapshot(true_pose, travelled, frame_index, maps)


#: named readings of the paper → the Albot₁ mapper spec each one runs (any other
#: ``albot1[...]`` spec is a reading too, named by itself)
READINGS: dict[str, str] = {
    "default": "albot1",
    "paper_literal": "albot1[preset=paper_literal]",
    "original": "albot1[preset=original]",
    "start_stop": "albot1[preset=start_stop]",
}
DEFAULT_READINGS = ("default", "paper_literal")


def reading_spec(reading: str) -> str:
    """The mapper spec of a reading: a name of ``READINGS`` or an ``albot1[...]`` spec."""
    if reading in READINGS:
        return READINGS[reading]
    if reading.startswith("albot1[") and reading.endswith("]"):
        from albot2d.mapping.registry import mapper_factory

        mapper_factory(reading)  # checks its options now
        return reading
    raise InputError(
        f"unknown reading {reading!r}; valid: {', '.join(READINGS)} or an albot1[KEY=VALUE,...] "
        "spec"
    )


def run_mappers(
    run: PaperRun, albot_x: bool, albot1_specs: tuple[str, ...] = ("albot1",)
) -> tuple[str, ...]:
    """The mappers a run drives: Albot₁ (one per reading) first, then ``run.mappers`` with
    Albot_x named."""
    x = ALBOT_X if albot_x else "naive"
    names = [*albot1_specs] + [x if m == "x" else m for m in run.mappers]
    return tuple(dict.fromkeys(names))


def run_job(
    run_name: str, seed: int, *, quick: bool, albot_x: bool, keep_figures: bool
) -> JobSummary:
    """Run ``RUNS[run_name]`` on ``seed`` with the default Albot₁; the summary the
    experiments read (``run_job_readings`` for several readings in one run)."""
    return run_job_readings(
        run_name, seed, quick=quick, albot_x=albot_x, keep_figures=keep_figures,
        readings=("default",),
    )["default"]  # fmt: skip


class _RunState:
    """What a job keeps while its run goes: the mappers, the snapshots taken so far, the
    marks' target distances, the true distance travelled, the views (figure runs)."""

    def __init__(self, albot1_specs: Sequence[str]) -> None:
        self.mappers: Mapping[str, Mapper] = {}
        self.snaps: dict[str, Snapshot] = {}
        self.targets: dict[str, float] = {}
        self.travelled = 0.0
        self.last: FloatArray | None = None
        self.views: dict[str, list[ViewAt]] = {name: [] for name in albot1_specs}

    def albot1(self, name: str) -> Albot1:
        from albot2d.mapping.albot1.mapper import Albot1

        mapper = self.mappers[name]
        assert isinstance(mapper, Albot1)  # a reading's mapper is an Albot1 spec
        return mapper


def run_job_readings(
    run_name: str,
    seed: int,
    *,
    quick: bool,
    albot_x: bool,
    keep_figures: bool,
    readings: tuple[str, ...] = ("default",),
) -> dict[str, JobSummary]:
    """Run ``RUNS[run_name]`` on ``seed`` with one Albot₁ per reading beside the run's
    other mappers, all on the same frames; per reading, the summary the experiments read,
    in which that reading's Albot₁ is ``"albot1"``.

    The run goes through ``run_experiment`` without its scoring (``score=False``): the
    experiments read only counts, homing, the end-pose error, revisits and a few map
    accuracies, which are computed here and nothing else.
    """
    from albot2d.evaluation.run.experiment import RunSpec, run_experiment
    from albot2d.evaluation.run.scoring import EvaluationParams
    from albot2d.evaluation.run.trace import HomingParams

    run = RUNS[run_name]
    specs = {reading: reading_spec(reading) for reading in readings}
    albot1_specs = tuple(dict.fromkeys(specs.values()))
    mappers = run_mappers(run, albot_x, albot1_specs)
    spec = RunSpec(
        seed=seed, kind=run.kind, world_params=dict(run.world_params), profile=run.profile,
        noise=PAPER_NOISE, tour_kind=run.tour_kind, tour_length_m=run.tour_length_m,
        route=run.route, mappers=mappers,
        max_frames=QUICK_MAX_FRAMES if quick and run.quick_cut else None,
    )  # fmt: skip
    params = EvaluationParams(homing=HomingParams(stop_every_m=run.stop_every_m))
    state = _RunState(albot1_specs)
    keep_views = keep_figures and run.views

    def on_start(world: World, tour: Tour) -> None:
        state.targets = _mark_targets(world, run, tour.length_m)

    def on_mappers(made: Mapping[str, Mapper]) -> None:
        state.mappers = made

    def on_frame(frame: Frame, _travelled: float) -> None:
        assert frame.true_pose is not None  # the paper's runs are all simulated
        pose = frame.true_pose.as_array()
        if state.last is not None:
            state.travelled += math.hypot(*(pose[:2] - state.last[:2]))
        state.last = pose
        if keep_views:
            for name in albot1_specs:
                state.views[name].append(_view_record(state.albot1(name), frame))
        for mark, target in state.targets.items():
            if mark not in state.snaps and state.travelled >= target - 0.05:
                state.snaps[mark] = _snapshot(state.mappers, pose, state.travelled, frame.index)

    result = run_experiment(
        spec, params, on_start=on_start, on_frame=on_frame, on_mappers=on_mappers, score=False
    )
    trace = result.trace
    truth, world = trace.true_poses, result.world
    assert truth is not None and world is not None  # the paper's runs are all simulated
    end = _snapshot(state.mappers, truth[-1], state.travelled, int(trace.frame_indices[-1]))
    last_waypoint = _last_waypoint(world, run)
    cut = spec.max_frames is not None and trace.n_frames >= spec.max_frames
    for mark in run.marks:
        # The end; a --quick run cut short: the marks it never reached are taken at its
        # end (marked not reached, so figures say where it stopped); a route ending at
        # the mark's waypoint may stop a few cm short of it.
        if mark not in state.snaps and (
            mark == "end" or (quick and spec.max_frames) or mark == last_waypoint
        ):
            reached = not cut and (mark == "end" or mark == last_waypoint)
            state.snaps[mark] = Snapshot(
                end.true_pose, end.true_travelled_m, end.frame, end.maps, reached
            )
    others = tuple(m for m in mappers if m not in albot1_specs)
    shared = _mapper_results(trace, state.mappers, others)
    x = ALBOT_X if albot_x else "naive"
    shared_quality = _quality_at_marks(
        state.snaps,
        {mark: tuple(x if m == "x" else m for m in names if m != "albot1")
         for mark, names in run.quality.items()},
        world, truth[0],
    )  # fmt: skip
    return {
        reading: _reading_summary(
            run, seed, spec, result, state, name, others, shared, shared_quality,
            albot_x=albot_x, quick=quick, keep_figures=keep_figures, keep_views=keep_views,
            reading=reading,
        )
        for reading, name in specs.items()
    }  # fmt: skip


def _mapper_results(
    trace: Trace, made: Mapping[str, Mapper], names: tuple[str, ...]
) -> dict[str, MapperResult]:
    """Counts and end-pose error of each mapper in ``names``."""
    from albot2d.evaluation.run.scoring import counts_section, end_pose_error, trajectory_of

    results: dict[str, MapperResult] = {}
    for name in names:
        poses = trajectory_of(name, made[name], trace.n_frames)
        results[name] = MapperResult(
            counts_section(trace, made[name]), end_pose_error(trace, poses)
        )
    return results


def _reading_summary(
    run: PaperRun,
    seed: int,
    spec: RunSpec,
    result: ExperimentResult,
    state: _RunState,
    name: str,
    others: tuple[str, ...],
    shared: Mapping[str, MapperResult],
    shared_quality: Mapping[str, Mapping[str, MapQualityAt]],
    *,
    albot_x: bool,
    quick: bool,
    keep_figures: bool,
    keep_views: bool,
    reading: str,
) -> JobSummary:
    """The job summary with the Albot₁ mapper ``name`` as ``"albot1"``."""
    from albot2d.evaluation.run.scoring import (
        REVISIT_GAP_MAPS,
        egocentric_at,
        homing_section,
        homing_summary,
        revisits_section,
    )

    trace = result.trace
    truth, world = trace.true_poses, result.world
    assert truth is not None and world is not None  # the paper's runs are all simulated
    snaps = {mark: s.as_albot1(name, others) for mark, s in state.snaps.items()}
    report = result.report
    albot1 = state.albot1(name)
    mine = _mapper_results(trace, state.mappers, (name,))[name]
    homing = homing_section(trace, name)
    ego = None
    if run.egocentric_end:
        ego = egocentric_at(trace, trace.final, name, world.obstacle_segments)
    albot1_result = Albot1Result(
        mine.counts, mine.end_pose_error, homing=homing, homing_summary=homing_summary(homing),
        revisits=revisits_section(albot1, REVISIT_GAP_MAPS), egocentric=ego,
    )  # fmt: skip
    marks = {
        mark: MarkSummary(
            s.true_travelled_m, s.frame, _path_digest(trace, s.frame),
            {n: m.counts() for n, m in s.maps.items()},
        )
        for mark, s in snaps.items()
    }  # fmt: skip
    updates = None
    if run.steps:
        from albot2d.evaluation.metrics.updates import albot1_update_flags, region_labels

        along = None
        if run.route is not None:
            from worldgen.routes import waypoint_arclength_m

            along = {k: tuple(v) for k, v in waypoint_arclength_m(world, run.route).items()}
        updates = Updates(
            flags=tuple(albot1_update_flags(albot1.steps, trace.frame_indices).tolist()),
            regions=tuple(region_labels(world, truth[:, :2]).tolist()),
            methods=tuple(_methods_per_row(albot1.steps, trace.frame_indices)),
            tracked=tuple(_tracked_per_row(albot1.steps, trace.frame_indices)),
            true_xy=tuple((x, y) for x, y in truth[:, :2].tolist()),
            waypoint_along_m=along,
        )
    deleted = None
    if "E1#2" in snaps and "E7" in snaps:
        from albot2d.evaluation.paper.figdata import deleted_surfaces

        deleted = len(deleted_surfaces(snaps["E1#2"], snaps["E7"]))
    x = ALBOT_X if albot_x else "naive"
    wanted = {mark: tuple(x if m == "x" else m for m in names)
              for mark, names in run.quality.items()}  # fmt: skip
    own = _quality_at_marks(
        snaps, {mark: ("albot1",) for mark, names in wanted.items() if "albot1" in names},
        world, truth[0],
    )  # fmt: skip
    quality: dict[str, dict[str, MapQualityAt]] = {}
    for mark, names in wanted.items():
        if mark in snaps:
            both = {**own.get(mark, {}), **shared_quality.get(mark, {})}
            quality[mark] = {n: both[n] for n in names if n in both}
    figures = None
    if keep_figures:
        figures = FigureRun(
            world_walls=np.asarray(world.walls),
            true_poses=truth,
            odom_poses=trace.odom_poses,
            snaps=snaps,
            waypoints=dict(world.features.get("waypoints", {})),
            updates=updates,
            views=tuple(state.views[name]) if keep_views else None,
        )
    mappers = ("albot1", *others)
    return JobSummary(
        run=run.name, seed=seed, quick=quick, mappers=mappers,
        frames=report["run"]["frames"], travelled_m=report["run"]["travelled_m"],
        true_travelled_m=report["run"]["true_travelled_m"],
        tour_length_m=result.tour.length_m if result.tour is not None else None,
        world_sha256=report["world"]["sha256"],
        albot1=albot1_result, others=dict(shared), marks=marks,
        path_integration_causes=path_integration_causes(albot1, trace, world),
        map_quality_at_marks=quality, reading=reading, reading_mapper=name,
        updates=updates, fig10_deleted=deleted, figures=figures,
    )  # fmt: skip


def _view_record(albot1: Albot1, frame: Frame) -> ViewAt:
    """The view Albot₁ saw at ``frame`` (surfaces, robot frame) and its global map just
    after it (map frame), for the Fig. 15 panels."""
    from albot2d.perception.extraction import extract_surfaces

    view = extract_surfaces(frame.scan, albot1.perception())
    return ViewAt(
        surfaces=np.asarray(view.segments, float).copy(),
        global_map=np.asarray(albot1.global_map().segments, float).copy(),
        pose_in_map=albot1.pose().as_array(),
    )


def path_integration_causes(albot1: Albot1, trace: Trace, world: World) -> PathIntegrationCauses:
    """Every local map Albot₁ placed by path integration: its frame, how many tracked
    surfaces were left (0: none to triangulate from; > 0: the triangulation afforded no
    pose within the gates), whether that view ended a turn, and the region kind there."""
    from albot2d.evaluation.metrics.updates import region_labels
    from albot2d.geometry import wrap_angle

    assert trace.true_poses is not None  # a simulated run
    rows = {int(f): k for k, f in enumerate(np.asarray(trace.frame_indices).tolist())}
    pis = [m for m in albot1.route if m.method == "path_integration" and m.frame_index in rows]
    k = np.array([rows[m.frame_index] for m in pis], dtype=np.int64)
    odom = np.asarray(trace.odom_poses)
    prev = np.maximum(k - 1, 0)
    dturn = np.degrees(np.abs(wrap_angle(odom[k, 2] - odom[prev, 2])))
    dmove = np.hypot(*(odom[k, :2] - odom[prev, :2]).T)
    regions = region_labels(world, trace.true_poses[k, :2]) if len(k) else np.array([])
    updates = [m for m in albot1.route if m.frame_index in rows]
    return PathIntegrationCauses(
        frames=tuple(int(m.frame_index) for m in pis),
        tracked=tuple(int(m.tracked) for m in pis),
        turning=tuple(bool(t > 0.5 and d < 0.02) for t, d in zip(dturn, dmove, strict=True)),
        regions=tuple(str(r) for r in regions),
        update_frames=tuple(int(m.frame_index) for m in updates),
        update_methods=tuple(str(m.method) for m in updates),
    )


def _path_digest(trace: Trace, frame: int) -> str:
    """SHA-256 of the true poses up to ``frame``: whether two runs drove the same path."""
    import hashlib

    assert trace.true_poses is not None  # a simulated run
    rows = np.flatnonzero(np.asarray(trace.frame_indices) <= frame)
    return hashlib.sha256(np.ascontiguousarray(trace.true_poses[rows]).tobytes()).hexdigest()


def _last_waypoint(world: World, run: PaperRun) -> str | None:
    if run.route is None:
        return None
    return str(world.features.get("routes", {}).get(run.route, [None])[-1])


def _methods_per_row(steps: Sequence[StepRecord], frame_indices: np.ndarray) -> list[str]:
    """Per trace row: how the view(s) remembered there were localised ('' if none)."""
    rows = {int(f): k for k, f in enumerate(np.asarray(frame_indices).tolist())}
    out = [""] * len(rows)
    for step in steps:
        row = rows.get(int(step.frame_index))
        if row is not None and step.methods:
            out[row] = str(step.methods[-1])
    return out


def _tracked_per_row(steps: Sequence[StepRecord], frame_indices: np.ndarray) -> list[int]:
    rows = {int(f): k for k, f in enumerate(np.asarray(frame_indices).tolist())}
    out = [-1] * len(rows)
    for step in steps:
        row = rows.get(int(step.frame_index))
        if row is not None:
            out[row] = int(step.tracked)
    return out


def _quality_at_marks(
    snaps: Mapping[str, Snapshot],
    wanted: Mapping[str, tuple[str, ...]],
    world: World,
    true_start: FloatArray,
) -> dict[str, dict[str, MapQualityAt]]:
    """Anchored map accuracy (p95, m) and surface count of the ``wanted`` mappers at each
    mark (mark → mapper names)."""
    from albot2d.evaluation.metrics.map_quality import map_quality
    from albot2d.geometry import Pose

    out: dict[str, dict[str, MapQualityAt]] = {}
    for mark, names in wanted.items():
        snap = snaps.get(mark)
        if snap is None:
            continue
        out[mark] = {}
        for name in names:
            m = snap.maps.get(name)
            if m is None:
                continue
            q = map_quality(
                m.segments, world.obstacle_segments, start_pose=Pose.from_array(true_start)
            )
            out[mark][name] = MapQualityAt(q.accuracy_m_p95, q.surfaces)
    return out
