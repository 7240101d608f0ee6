"""The main experiment: a world, a tour driven with a profile, every mapper, all the metrics.

``run_experiment(RunSpec(...))`` builds the run (``setup.build_run``: world, tour,
simulator), drives the simulator, streams the frames through every mapper once
(``drive_mappers``), computes relations from the truth, scores every mapper and raw
odometry (``score_mappers``) and assembles report.json's dict. The spec is recorded in
the report, so ``RunSpec.from_report`` reproduces a run bit for bit.

``albot2d simulate`` builds its run the same way, so with the same options it logs
exactly the frames mapped here.
"""

from __future__ import annotations

import hashlib
import time
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from albot2d.errors import InputError
from albot2d.evaluation.metrics.map_quality import MapQualityParams
from albot2d.evaluation.run.report import make_report
from albot2d.evaluation.run.results import OdometryScores, RunScores
from albot2d.evaluation.run.scoring import EvaluationParams, score_run
from albot2d.evaluation.run.setup import DEFAULT_MAPPERS, EXPLORE_TOUR, RunSpec, build_run
from albot2d.evaluation.run.trace import HomingParams, Trace, drive_mappers
from albot2d.frames import Frame
from albot2d.logs.relations import Relations, RelationsOptions, relations_from_truth
from albot2d.mapping.protocol import Mapper
from worldgen.world import Tour, World

__all__ = [
    "DEFAULT_MAPPERS",
    "ExperimentResult",
    "RunSpec",
    "evaluation_params_from_report",
    "run_experiment",
    "world_digest",
]


def evaluation_params_from_report(report: Mapping[str, Any]) -> EvaluationParams:
    """The scoring parameters recorded in a report."""
    p = report.get("params", {})
    try:
        return EvaluationParams(
            homing=HomingParams(**p["homing"]),
            map_quality=MapQualityParams(**p["map_quality"]),
            relations=RelationsOptions(**p["relations"]),
            rpe_split_s=p["rpe_split_s"],
            snapshots=p["snapshots"],
        )
    except (KeyError, TypeError) as exc:
        raise InputError(f"report params: missing or unknown scoring parameter ({exc})") from None


def evaluation_params_dict(params: EvaluationParams) -> dict[str, Any]:
    return {
        "homing": asdict(params.homing),
        "map_quality": asdict(params.map_quality),
        "relations": asdict(params.relations),
        "rpe_split_s": params.rpe_split_s,
        "snapshots": params.snapshots,
    }


@dataclass(eq=False)
class ExperimentResult:
    """A finished run or replay: its typed scores, the report (``report.json``: a view of
    the scores plus what was run), and what the figures are drawn from."""

    report: dict[str, Any]
    trace: Trace
    world: World | None
    tour: Tour | None
    relations: Relations | None
    title: str
    scores: RunScores  # empty (no mappers, odometry unscored) with run_experiment(score=False)

    def __repr__(self) -> str:
        return f"ExperimentResult({self.title!r}, {self.trace!r}, report keys {list(self.report)})"


def world_digest(world: World) -> str:
    """SHA-256 of the world's JSON: tells whether a reproduction used the same world."""
    from worldgen.io import world_to_json

    return hashlib.sha256(world_to_json(world).encode("utf-8")).hexdigest()


def run_experiment(
    spec: RunSpec,
    params: EvaluationParams | None = None,
    *,
    on_start: Callable[[World, Tour], None] | None = None,
    on_frame: Callable[[Frame, float], None] | None = None,
    on_stage: Callable[[str], None] | None = None,
    on_mappers: Callable[[Mapping[str, Mapper]], None] | None = None,
    score: bool = True,
) -> ExperimentResult:
    """Simulate ``spec`` and score every mapper; see the module docstring.

    ``on_start(world, tour)`` is called once the tour is planned, ``on_frame(frame,
    travelled_m)`` after each frame and ``on_stage("scoring")`` after the last one
    (progress display); ``on_mappers(mappers)`` once the mappers are made, before the
    first frame (to attach invariant checks). ``score=False`` leaves the scoring out (the
    report's ``mappers`` and ``odometry`` are empty, no relations are made): for callers
    that read only a few numbers off the trace and the mappers (``albot2d experiments``).
    """
    params = params or EvaluationParams()
    t0 = time.perf_counter()
    setup = build_run(spec)
    world, tour, profile, sim = setup.world, setup.tour, setup.profile, setup.simulator
    exploring = None
    if tour.kind == EXPLORE_TOUR:
        from albot2d.control.exploration import ExploreDrive

        exploring = ExploreDrive(sim, profile)
        frames = exploring.frames()
    else:
        frames = sim.drive(tour, profile)
    if on_start is not None:
        on_start(world, tour)
    mappers = {name: factory() for name, factory in setup.mapper_factories.items()}
    if on_mappers is not None:
        on_mappers(mappers)
    trace = drive_mappers(
        frames, mappers, homing=params.homing, last_k_views=params.map_quality.last_k_views,
        max_frames=spec.max_frames, on_frame=on_frame,
        # Scored at each stop while driving (memory follows the map, not stops × map);
        # without scoring the stops keep their inputs for a caller's own scores.
        walls=world.obstacle_segments if score else None,
    )  # fmt: skip
    assert trace.true_poses is not None  # the simulator always knows the truth
    if on_stage is not None:
        on_stage("scoring")
    relations: Relations | None = None
    scores = RunScores(OdometryScores(None, None, None))  # score=False: nothing scored
    if score:
        relations = relations_from_truth(
            trace.timestamps, trace.true_poses, options=params.relations
        )
        scores = score_run(trace, relations, params, world)
    world_info = {
        "kind": world.kind, "seed": world.seed, "params": dict(spec.world_params),
        "source": spec.world_file, "width_m": world.width_m, "height_m": world.height_m,
        "sha256": world_digest(world),
    }  # fmt: skip
    run_info = {
        "frames": trace.n_frames,
        "duration_s": float(trace.timestamps[-1] - trace.timestamps[0]),
        "travelled_m": float(trace.travelled_m[-1]),
        "true_travelled_m": float(np.hypot(*np.diff(trace.true_poses[:, :2], axis=0).T).sum()),
        "collided_frames": int(trace.collided.sum()),
        "relations": None if relations is None else len(relations),
        "relations_source": "truth" if score else None,
    }
    extra: dict[str, Any] = {}
    if exploring is not None:  # the tour is the path the explorer drove
        tour = Tour(trace.true_poses[:, :2], kind=EXPLORE_TOUR)
        extra["exploration"] = exploring.result.to_dict()
    report = make_report(
        "run",
        seed=spec.seed,
        world=world_info,
        profile=profile.name,
        params={
            "spec": spec.to_dict(),
            "tour": spec.tour_record(tour),
            **evaluation_params_dict(params),
            "simulator": sim.params(),
        },
        run=run_info,
        odometry=scores.odometry.to_dict(),
        mappers=scores.mappers_dict(),
        **extra,
        # Per-view stage times: mean, p50, p95 and max ms (the rows are in steps.csv).
        timing_ms=trace.step_times.summary_ms(),
        figures=[],
        wall_time_s=time.perf_counter() - t0,
    )
    driven = f"{tour.kind} tour {tour.length_m:.0f} m"
    if spec.max_frames is not None:  # cut short: say how much of the tour was driven
        driven = f"{run_info['travelled_m']:.0f} m of a {driven}"
    title = (
        f"{world.kind} seed {world.seed}  {profile.name}  {driven}  "
        f"odometry noise {spec.noise}  {trace.n_frames} views"
    )
    return ExperimentResult(report, trace, world, tour, relations, title, scores)
