"""The simulated runs the paper's experiments are computed from, one job per (run, seed).

Every run goes through the one setup path, ``run_experiment(RunSpec(...))``; a job returns
a small JSON-ready summary (counts, homing stops, map quality, update flags) and, for the
seed whose maps are drawn, the map snapshots the figures need. Snapshots are taken while
the run goes (``on_frame``) when the robot's *true* distance along the route first reaches
a named waypoint, so "the map at E5" is the map when the robot got to E5.

Albot_x (the paper's SLAM robot) is the ``slam`` mapper when it can be made here (the
``slam`` extra), otherwise it is left out and the experiments say so; ``naive`` is the
paper's "Albot_x without correcting sensor errors" of Fig. 16.
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
    """One kind of run: world, route or tour, driving profile, and what to snapshot.

    ``marks`` names the moments at which every mapper's map is kept (for figures): a
    waypoint name (its first passage; ``NAME#2`` the second) or ``half`` / ``end``.
    """

    name: str
    kind: str
    profile: str
    route: str | None = None
    tour_kind: str = "loop"
    tour_length_m: float = 100.0
    world_params: Mapping[str, Any] = field(default_factory=dict)
    with_albot_x: bool = False
    stop_every_m: float = 20.0
    marks: tuple[str, ...] = ()
    steps: bool = False  # keep Albot1's per-view step records (Figs. 14, 15)
    quick_cut: bool = True  # shortened in --quick mode


RUNS: dict[str, PaperRun] = {
    r.name: r
    for r in (
        PaperRun("fig6_dataset1", "fig6", "dataset1", route="fig6", with_albot_x=True,
                 marks=("E5", "E1#2", "E7", "end"), quick_cut=True),
        PaperRun("fig6_dataset2", "fig6", "dataset2", route="fig6", marks=("E7", "end"),
                 quick_cut=True),
        PaperRun("fig6_dataset3", "fig6", "dataset3", route="fig6", with_albot_x=True,
                 marks=("E5", "end")),
        PaperRun("fig6_start_stop", "fig6", "start_stop", route="fig6", marks=("E5",),
                 steps=True),
        PaperRun("fig8_anticlockwise", "fig6", "start_stop", route="fig8_anticlockwise",
                 stop_every_m=4.0),
        PaperRun("fig8_clockwise", "fig6", "start_stop", route="fig8_clockwise",
                 stop_every_m=4.0),
        PaperRun("fig11_open", "open", "dataset3", tour_kind="loop", tour_length_m=130.0,
                 with_albot_x=True, marks=("half", "end")),
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


def run_job(
    run_name: str, seed: int, *, quick: bool, albot_x: bool, keep_figures: bool
) -> dict[str, Any]:
    """Run ``RUNS[run_name]`` on ``seed``; the summary the experiments read."""
    from albot2d.evaluation.experiment import RunSpec, run_experiment
    from albot2d.evaluation.scoring import EvaluationParams
    from albot2d.evaluation.trace import HomingParams

    run = RUNS[run_name]
    mappers = ("albot1", "naive", "truth") + ((ALBOT_X,) if albot_x and run.with_albot_x else ())
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
        "frames": [],
    }

    def on_start(world: Any, tour: Any) -> None:
        state["world"], state["tour"] = world, tour
        state["targets"] = _mark_targets(world, run, tour.length_m)

    def on_mappers(made: Mapping[str, Any]) -> None:
        state["mappers"] = made

    def on_frame(frame: Any, _travelled: float) -> None:
        pose = frame.true_pose.as_array()
        if state["last"] is not None:
            state["travelled"] += math.hypot(*(pose[:2] - state["last"][:2]))
        state["last"] = pose
        for mark, target in state["targets"].items():
            if mark not in state["snaps"] and state["travelled"] >= target - 0.05:
                state["snaps"][mark] = _snapshot(
                    state["mappers"], pose, state["travelled"], frame.index
                )

    result = run_experiment(
        spec, params, on_start=on_start, on_frame=on_frame, on_mappers=on_mappers
    )
    trace = result.trace
    truth, world = trace.true_poses, result.world
    assert truth is not None and world is not None  # the paper's runs are all simulated
    end = _snapshot(
        state["mappers"], truth[-1], state["travelled"], int(trace.frame_indices[-1])
    )
    for mark in run.marks:
        # a --quick run is cut short: the marks it never reached are taken at its end
        if mark == "end" or (quick and spec.max_frames and mark not in state["snaps"]):
            state["snaps"][mark] = end
    report = result.report
    summary: dict[str, Any] = {
        "run": run_name, "seed": seed, "quick": quick, "mappers": list(mappers),
        "frames": report["run"]["frames"], "travelled_m": report["run"]["travelled_m"],
        "true_travelled_m": report["run"]["true_travelled_m"],
        "tour_length_m": result.tour.length_m if result.tour is not None else None,
        "world_sha256": report["world"]["sha256"],
        "mapper_results": {
            name: {k: report["mappers"][name][k] for k in
                   ("counts", "homing", "homing_summary", "map", "end_pose_error", "revisits")
                   if k in report["mappers"][name]}
            for name in mappers
        },
        "marks": {mark: {"true_travelled_m": s["true_travelled_m"], "frame": s["frame"],
                         "counts": {n: {k: m[k] for k in ("views", "local_maps",
                                                          "path_integrations")}
                                    for n, m in s["maps"].items()}}
                  for mark, s in state["snaps"].items()},
    }  # fmt: skip
    albot1 = state["mappers"]["albot1"]
    if run.steps:
        from albot2d.evaluation.updates import albot1_update_flags, region_labels

        flags = albot1_update_flags(albot1.steps, trace.frame_indices)
        regions = region_labels(world, truth[:, :2])
        summary["updates"] = {
            "flags": flags.tolist(),
            "regions": regions.tolist(),
            "methods": _methods_per_row(albot1.steps, trace.frame_indices),
            "tracked": _tracked_per_row(albot1.steps, trace.frame_indices),
            "true_xy": truth[:, :2].tolist(),
        }
    if "E1#2" in state["snaps"] and "E7" in state["snaps"]:
        from albot2d.evaluation.paper.figdata import deleted_surfaces

        summary["fig10_deleted"] = len(
            deleted_surfaces(state["snaps"]["E1#2"], state["snaps"]["E7"])
        )
    summary["map_quality_at_marks"] = _quality_at_marks(
        state["snaps"], world, truth[0]
    )
    if keep_figures:
        summary["figures"] = {
            "world_walls": np.asarray(world.walls),
            "true_poses": truth,
            "odom_poses": trace.odom_poses,
            "snaps": state["snaps"],
            "waypoints": dict(world.features.get("waypoints", {})),
            "updates": summary.get("updates"),
        }
    return summary


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
    snaps: Mapping[str, Any], world: Any, true_start: np.ndarray
) -> dict[str, dict[str, Any]]:
    """Anchored map accuracy (p95, m) and surface count of every mapper at every mark."""
    from albot2d.evaluation.map_quality import map_quality
    from albot2d.geometry import Pose

    out: dict[str, dict[str, Any]] = {}
    for mark, snap in snaps.items():
        out[mark] = {}
        for name, m in snap["maps"].items():
            q = map_quality(
                m["segments"], world.obstacle_segments, start_pose=Pose.from_array(true_start)
            )
            out[mark][name] = {"accuracy_m_p95": q.accuracy_m_p95, "surfaces": q.surfaces}
    return out
