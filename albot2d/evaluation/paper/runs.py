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
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from albot2d.errors import InputError

__all__ = [
    "ALBOT_X",
    "PAPER_NOISE",
    "RUNS",
    "PaperRun",
    "albot_x_available",
    "run_job",
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
    world_params: Mapping[str, Any] = field(default_factory=dict)
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


def _mark_targets(world: Any, run: PaperRun, tour_length_m: float) -> dict[str, float]:
    """True distance along the tour at which each mark is taken."""
    targets: dict[str, float] = {}
    along = {}
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
    mappers: Mapping[str, Any], true_pose: np.ndarray, travelled: float, frame_index: int
) -> dict[str, Any]:
    maps = {}
    for name, m in mappers.items():
        snap = m.global_map()
        counts = m.counts()
        maps[name] = {
            "segments": np.asarray(snap.segments, float).copy(),
            "map_ids": np.asarray(snap.map_ids).copy(),
            "pose": m.pose().as_array(),
            "views": counts.views,
            "local_maps": counts.local_maps,
            "path_integrations": counts.path_integrations,
        }
    return {
        "true_pose": true_pose,
        "true_travelled_m": travelled,
        "frame": frame_index,
        "maps": maps,
    }


def run_mappers(run: PaperRun, albot_x: bool) -> tuple[str, ...]:
    """The mappers a run drives: Albot₁ first, then ``run.mappers`` with Albot_x named."""
    x = ALBOT_X if albot_x else "naive"
    names = ["albot1"] + [x if m == "x" else m for m in run.mappers]
    return tuple(dict.fromkeys(names))


def run_job(
    run_name: str, seed: int, *, quick: bool, albot_x: bool, keep_figures: bool
) -> dict[str, Any]:
    """Run ``RUNS[run_name]`` on ``seed``; the summary the experiments read.

    The run goes through ``run_experiment`` without its scoring (``score=False``): the
    experiments read only counts, homing, the end-pose error, revisits and a few map
    accuracies, which are computed here and nothing else.
    """
    from albot2d.evaluation.run.experiment import RunSpec, run_experiment
    from albot2d.evaluation.run.scoring import (
        REVISIT_GAP_MAPS,
        EvaluationParams,
        counts_section,
        egocentric_at,
        end_pose_error,
        homing_section,
        homing_summary,
        revisits_section,
        trajectory_of,
    )
    from albot2d.evaluation.run.trace import HomingParams

    run = RUNS[run_name]
    mappers = run_mappers(run, albot_x)
    spec = RunSpec(
        seed=seed, kind=run.kind, world_params=dict(run.world_params), profile=run.profile,
        noise=PAPER_NOISE, tour_kind=run.tour_kind, tour_length_m=run.tour_length_m,
        route=run.route, mappers=mappers,
        max_frames=QUICK_MAX_FRAMES if quick and run.quick_cut else None,
    )  # fmt: skip
    params = EvaluationParams(homing=HomingParams(stop_every_m=run.stop_every_m))
    state: dict[str, Any] = {
        "mappers": {},
        "snaps": {},
        "targets": {},
        "travelled": 0.0,
        "last": None,
        "views": [],
    }
    keep_views = keep_figures and run.views

    def on_start(world: Any, tour: Any) -> None:
        state["targets"] = _mark_targets(world, run, tour.length_m)

    def on_mappers(made: Mapping[str, Any]) -> None:
        state["mappers"] = made

    def on_frame(frame: Any, _travelled: float) -> None:
        pose = frame.true_pose.as_array()
        if state["last"] is not None:
            state["travelled"] += math.hypot(*(pose[:2] - state["last"][:2]))
        state["last"] = pose
        if keep_views:
            state["views"].append(_view_record(state["mappers"]["albot1"], frame))
        for mark, target in state["targets"].items():
            if mark not in state["snaps"] and state["travelled"] >= target - 0.05:
                state["snaps"][mark] = _snapshot(
                    state["mappers"], pose, state["travelled"], frame.index
                )

    result = run_experiment(
        spec, params, on_start=on_start, on_frame=on_frame, on_mappers=on_mappers, score=False
    )
    trace = result.trace
    truth, world = trace.true_poses, result.world
    assert truth is not None and world is not None  # the paper's runs are all simulated
    end = _snapshot(state["mappers"], truth[-1], state["travelled"], int(trace.frame_indices[-1]))
    last_waypoint = _last_waypoint(world, run)
    cut = spec.max_frames is not None and trace.n_frames >= spec.max_frames
    for mark in run.marks:
        # The end; a --quick run cut short: the marks it never reached are taken at its
        # end (marked not reached, so figures say where it stopped); a route ending at
        # the mark's waypoint may stop a few cm short of it.
        if mark not in state["snaps"] and (
            mark == "end" or (quick and spec.max_frames) or mark == last_waypoint
        ):
            reached = not cut and (mark == "end" or mark == last_waypoint)
            state["snaps"][mark] = end | {"reached": reached}
    report = result.report
    made = state["mappers"]
    albot1 = made["albot1"]
    results: dict[str, dict[str, Any]] = {}
    for name in mappers:
        poses = trajectory_of(name, made[name], trace.n_frames)
        end_error = end_pose_error(trace, poses)
        results[name] = {
            "counts": counts_section(trace, made[name]).to_dict(),
            "end_pose_error": None if end_error is None else end_error.to_dict(),
        }
    homing = homing_section(trace, "albot1")
    revisits = revisits_section(albot1, REVISIT_GAP_MAPS)
    results["albot1"] |= {
        "homing": [stop.to_dict() for stop in homing],
        "homing_summary": homing_summary(homing).to_dict(),
        "revisits": None if revisits is None else revisits.to_dict(),
    }
    if run.egocentric_end:
        ego = egocentric_at(trace, trace.final, "albot1", world.obstacle_segments)
        results["albot1"]["map"] = {"egocentric": None if ego is None else ego.to_dict()}
    summary: dict[str, Any] = {
        "run": run_name, "seed": seed, "quick": quick, "mappers": list(mappers),
        "frames": report["run"]["frames"], "travelled_m": report["run"]["travelled_m"],
        "true_travelled_m": report["run"]["true_travelled_m"],
        "tour_length_m": result.tour.length_m if result.tour is not None else None,
        "world_sha256": report["world"]["sha256"],
        "mapper_results": results,
        "marks": {mark: {"true_travelled_m": s["true_travelled_m"], "frame": s["frame"],
                         "true_path_sha256": _path_digest(trace, s["frame"]),
                         "counts": {n: {k: m[k] for k in ("views", "local_maps",
                                                          "path_integrations")}
                                    for n, m in s["maps"].items()}}
                  for mark, s in state["snaps"].items()},
    }  # fmt: skip
    if run.steps:
        from albot2d.evaluation.metrics.updates import albot1_update_flags, region_labels

        flags = albot1_update_flags(albot1.steps, trace.frame_indices)
        regions = region_labels(world, truth[:, :2])
        summary["updates"] = {
            "flags": flags.tolist(),
            "regions": regions.tolist(),
            "methods": _methods_per_row(albot1.steps, trace.frame_indices),
            "tracked": _tracked_per_row(albot1.steps, trace.frame_indices),
            "true_xy": truth[:, :2].tolist(),
        }
        if run.route is not None:
            from worldgen.routes import waypoint_arclength_m

            summary["updates"]["waypoint_along_m"] = waypoint_arclength_m(world, run.route)
    summary["path_integration_causes"] = path_integration_causes(albot1, trace, world)
    if "E1#2" in state["snaps"] and "E7" in state["snaps"]:
        from albot2d.evaluation.paper.figdata import deleted_surfaces

        summary["fig10_deleted"] = len(
            deleted_surfaces(state["snaps"]["E1#2"], state["snaps"]["E7"])
        )
    x = ALBOT_X if albot_x else "naive"
    wanted = {mark: tuple(x if m == "x" else m for m in names)
              for mark, names in run.quality.items()}  # fmt: skip
    summary["map_quality_at_marks"] = _quality_at_marks(state["snaps"], wanted, world, truth[0])
    if keep_figures:
        summary["figures"] = {
            "world_walls": np.asarray(world.walls),
            "true_poses": truth,
            "odom_poses": trace.odom_poses,
            "snaps": state["snaps"],
            "waypoints": dict(world.features.get("waypoints", {})),
            "updates": summary.get("updates"),
            "views": state["views"] if keep_views else None,
        }
    return summary


def _view_record(albot1: Any, frame: Any) -> dict[str, Any]:
    """The view Albot₁ saw at ``frame`` (surfaces, robot frame) and its global map just
    after it (map frame), for the Fig. 15 panels."""
    from albot2d.perception.extraction import extract_surfaces

    view = extract_surfaces(frame.scan, albot1.perception())
    return {
        "surfaces": np.asarray(view.segments, float).copy(),
        "global_map": np.asarray(albot1.global_map().segments, float).copy(),
        "pose_in_map": albot1.pose().as_array(),
    }


def path_integration_causes(albot1: Any, trace: Any, world: Any) -> dict[str, Any]:
    """Every local map Albot₁ placed by path integration: its frame, how many tracked
    surfaces were left (0: none to triangulate from; > 0: the triangulation afforded no
    pose within the gates), whether that view ended a turn, and the region kind there."""
    from albot2d.evaluation.metrics.updates import region_labels
    from albot2d.geometry import wrap_angle

    rows = {int(f): k for k, f in enumerate(np.asarray(trace.frame_indices).tolist())}
    pis = [m for m in albot1.route if m.method == "path_integration" and m.frame_index in rows]
    k = np.array([rows[m.frame_index] for m in pis], dtype=np.int64)
    odom = np.asarray(trace.odom_poses)
    prev = np.maximum(k - 1, 0)
    dturn = np.degrees(np.abs(wrap_angle(odom[k, 2] - odom[prev, 2])))
    dmove = np.hypot(*(odom[k, :2] - odom[prev, :2]).T)
    regions = region_labels(world, trace.true_poses[k, :2]) if len(k) else np.array([])
    updates = [m for m in albot1.route if m.frame_index in rows]
    return {
        "frames": [int(m.frame_index) for m in pis],
        "tracked": [int(m.tracked) for m in pis],
        "turning": [bool(t > 0.5 and d < 0.02) for t, d in zip(dturn, dmove, strict=True)],
        "regions": [str(r) for r in regions],
        "update_frames": [int(m.frame_index) for m in updates],
        "update_methods": [str(m.method) for m in updates],
    }


def _path_digest(trace: Any, frame: int) -> str:
    """SHA-256 of the true poses up to ``frame``: whether two runs drove the same path."""
    import hashlib

    rows = np.flatnonzero(np.asarray(trace.frame_indices) <= frame)
    return hashlib.sha256(np.ascontiguousarray(trace.true_poses[rows]).tobytes()).hexdigest()


def _last_waypoint(world: Any, run: PaperRun) -> str | None:
    if run.route is None:
        return None
    return str(world.features.get("routes", {}).get(run.route, [None])[-1])


def _methods_per_row(steps: Any, frame_indices: np.ndarray) -> list[str]:
    """Per trace row: how the view(s) remembered there were localised ('' if none)."""
    rows = {int(f): k for k, f in enumerate(np.asarray(frame_indices).tolist())}
    out = [""] * len(rows)
    for step in steps:
        row = rows.get(int(step.frame_index))
        if row is not None and step.methods:
            out[row] = str(step.methods[-1])
    return out


def _tracked_per_row(steps: Any, frame_indices: np.ndarray) -> list[int]:
    rows = {int(f): k for k, f in enumerate(np.asarray(frame_indices).tolist())}
    out = [-1] * len(rows)
    for step in steps:
        row = rows.get(int(step.frame_index))
        if row is not None:
            out[row] = int(step.tracked)
    return out


def _quality_at_marks(
    snaps: Mapping[str, Any],
    wanted: Mapping[str, tuple[str, ...]],
    world: Any,
    true_start: np.ndarray,
) -> dict[str, dict[str, Any]]:
    """Anchored map accuracy (p95, m) and surface count of the ``wanted`` mappers at each
    mark (mark → mapper names)."""
    from albot2d.evaluation.metrics.map_quality import map_quality
    from albot2d.geometry import Pose

    out: dict[str, dict[str, Any]] = {}
    for mark, names in wanted.items():
        snap = snaps.get(mark)
        if snap is None:
            continue
        out[mark] = {}
        for name in names:
            m = snap["maps"].get(name)
            if m is None:
                continue
            q = map_quality(
                m["segments"], world.obstacle_segments, start_pose=Pose.from_array(true_start)
            )
            out[mark][name] = {"accuracy_m_p95": q.accuracy_m_p95, "surfaces": q.surfaces}
    return out
