"""The main experiment: a world, a tour driven with a profile, every mapper, all the metrics.

``run_experiment(RunSpec(...))`` builds (or loads) the world, plans the tour, drives the
simulator, streams the frames through every mapper once (``drive_mappers``), computes
relations from the truth, scores every mapper and raw odometry (``score_mappers``) and
assembles report.json's dict. The spec is recorded in the report, so ``RunSpec.from_report``
reproduces a run bit for bit.

Seeds follow ``albot2d simulate``: the tour is planned from the world's seed (stream 1 of
``spawn_rngs(world.seed, 2)``) and the simulator is seeded with child 2 of the run seed,
so ``albot2d simulate`` with the same options logs exactly the frames mapped here.
"""

from __future__ import annotations

import dataclasses
import hashlib
import math
import time
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from albot2d.errors import InputError
from albot2d.evaluation.map_quality import MapQualityParams
from albot2d.evaluation.report import make_report
from albot2d.evaluation.scoring import EvaluationParams, odometry_section, score_mappers
from albot2d.evaluation.trace import HomingParams, Trace, drive_mappers
from albot2d.evaluation.updates import updates_section
from albot2d.frames import Frame
from albot2d.logs.relations import Relations, RelationsOptions, relations_from_truth
from albot2d.mapping.protocol import Mapper
from albot2d.mapping.registry import resolve_mappers
from worldgen.tours import TOUR_KINDS
from worldgen.tours import plan_tour as _plan_tour
from worldgen.world import Tour, World

__all__ = [
    "DEFAULT_MAPPERS",
    "LASER_NOISE_CHOICES",
    "ExperimentResult",
    "RunSpec",
    "evaluation_params_from_report",
    "make_simulator",
    "plan_tour",
    "run_experiment",
    "world_digest",
]

DEFAULT_MAPPERS = ("albot1", "naive", "truth")
LASER_NOISE_CHOICES = ("sick_lms200", "zero")
# Child of the run seed that seeds the simulator (the same as ``albot2d simulate``).
_SIMULATION_STREAM = 2


@dataclass(frozen=True)
class RunSpec:
    """What to simulate: everything needed to reproduce the run.

    Give ``kind`` (a generated world, with ``world_params`` overrides) or ``world_file``.
    ``noise``/``laser_noise`` name presets; ``max_frames`` cuts the run short.
    """

    seed: int = 0
    kind: str | None = "office"
    world_file: str | None = None
    world_params: Mapping[str, Any] = field(default_factory=dict)
    profile: str = "dataset1"
    noise: str = "typical"
    laser_noise: str = "sick_lms200"
    tour_kind: str = "loop"
    tour_length_m: float = 100.0
    # a route named by the world (``worldgen.routes``, e.g. the fig6 kind's "fig6"): the
    # tour drives its waypoints from its first one; tour_kind/tour_length_m are then unused
    route: str | None = None
    mappers: tuple[str, ...] = DEFAULT_MAPPERS
    max_frames: int | None = None

    def __post_init__(self) -> None:
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise InputError(f"RunSpec.seed must be a non-negative integer, got {self.seed!r}")
        if (self.kind is None) == (self.world_file is None):
            raise InputError("RunSpec needs a world kind or a world file (not both)")
        if self.world_file is not None and self.world_params:
            raise InputError("RunSpec.world_params apply to generated worlds, not a world file")
        length = self.tour_length_m
        if isinstance(length, bool) or not isinstance(length, int | float) or not (
            math.isfinite(length) and length > 0
        ):
            raise InputError(f"RunSpec.tour_length_m must be a positive number, got {length!r}")
        if self.tour_kind not in TOUR_KINDS:
            raise InputError(
                f"unknown tour kind {self.tour_kind!r}; valid: {', '.join(TOUR_KINDS)}"
            )
        if self.laser_noise not in LASER_NOISE_CHOICES:
            raise InputError(
                f"unknown laser noise {self.laser_noise!r}; valid: {', '.join(LASER_NOISE_CHOICES)}"
            )
        if self.max_frames is not None and (
            isinstance(self.max_frames, bool) or not isinstance(self.max_frames, int)
            or self.max_frames <= 0
        ):  # fmt: skip
            raise InputError(f"max_frames must be a positive integer, got {self.max_frames!r}")
        if not self.mappers:
            raise InputError("give at least one mapper")
        object.__setattr__(self, "mappers", tuple(self.mappers))
        object.__setattr__(self, "world_params", dict(self.world_params))

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_report(cls, report: Mapping[str, Any], where: str = "report") -> RunSpec:
        """The spec recorded in a report written by ``albot2d run``."""
        if report.get("command") != "run":
            raise InputError(f"{where}: not a report of `albot2d run` (command "
                             f"{report.get('command')!r}); only runs can be reproduced")
        spec = report.get("params", {}).get("spec")
        if not isinstance(spec, dict):
            raise InputError(f"{where}: params.spec is missing; cannot reproduce the run")
        values = dict(spec)
        values["mappers"] = tuple(values.get("mappers", DEFAULT_MAPPERS))
        fields = set(cls.__dataclass_fields__)
        unknown = sorted(set(values) - fields)
        if unknown:
            raise InputError(f"{where}: params.spec has unknown field(s) {', '.join(unknown)}")
        return cls(**values)


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
    """A finished run or replay: the report, and what the figures are drawn from."""

    report: dict[str, Any]
    trace: Trace
    world: World | None
    tour: Tour | None
    relations: Relations | None
    title: str

    def __repr__(self) -> str:
        return f"ExperimentResult({self.title!r}, {self.trace!r}, report keys {list(self.report)})"


def world_digest(world: World) -> str:
    """SHA-256 of the world's JSON: tells whether a reproduction used the same world."""
    from worldgen.io import world_to_json

    return hashlib.sha256(world_to_json(world).encode("utf-8")).hexdigest()


def build_world(spec: RunSpec) -> World:
    if spec.world_file is not None:
        from worldgen.io import load

        return load(spec.world_file)
    from worldgen.generate import generate

    return generate(spec.kind, seed=spec.seed, **spec.world_params)  # type: ignore[arg-type]


def plan_tour(world: World, kind: str, min_length_m: float) -> Tour:
    """``worldgen.plan_tour``: the same tour as ``albot2d world``/``simulate`` plan."""
    return _plan_tour(world, kind=kind, length_m=min_length_m)


def make_simulator(world: World, spec: RunSpec) -> Any:
    """The simulator of a run, seeded like ``albot2d simulate``."""
    from albot2d.sim.laser import LaserNoise
    from albot2d.sim.odometry import noise_preset
    from albot2d.sim.simulator import Simulator

    laser = LaserNoise.zero() if spec.laser_noise == "zero" else LaserNoise.sick_lms200()
    seed = np.random.SeedSequence(spec.seed).spawn(_SIMULATION_STREAM + 1)[_SIMULATION_STREAM]
    return Simulator(world, seed=seed, odometry=noise_preset(spec.noise), laser_noise=laser)


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
    from albot2d.sim.driving import get_profile

    params = params or EvaluationParams()
    t0 = time.perf_counter()
    factories = resolve_mappers(list(spec.mappers))
    profile = get_profile(spec.profile)
    world = build_world(spec)
    if spec.route is not None:
        from worldgen.routes import route_start, route_tour

        tour = route_tour(world, spec.route)
        world = dataclasses.replace(world, start=route_start(world, spec.route))
    else:
        tour = plan_tour(world, spec.tour_kind, spec.tour_length_m)
    sim = make_simulator(world, spec)
    frames = sim.drive(tour, profile)
    if on_start is not None:
        on_start(world, tour)
    mappers = {name: factory() for name, factory in factories.items()}
    if on_mappers is not None:
        on_mappers(mappers)
    trace = drive_mappers(
        frames, mappers, homing=params.homing, last_k_views=params.map_quality.last_k_views,
        max_frames=spec.max_frames, on_frame=on_frame,
    )  # fmt: skip
    assert trace.true_poses is not None  # the simulator always knows the truth
    if on_stage is not None:
        on_stage("scoring")
    relations: Relations | None = None
    scores: dict[str, dict[str, Any]] = {}
    if score:
        relations = relations_from_truth(
            trace.timestamps, trace.true_poses, options=params.relations
        )
        scores = score_mappers(trace, relations, world.obstacle_segments, params)
        for name, mapper in trace.mappers.items():
            # Fig. 14: instructions and moves per global-map update, by region kind.
            scores[name]["updates_by_region"] = updates_section(world, trace, mapper)
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
    report = make_report(
        "run",
        seed=spec.seed,
        world=world_info,
        profile=profile.name,
        params={
            "spec": spec.to_dict(),
            "tour": {"kind": tour.kind, "min_length_m": spec.tour_length_m,
                     "length_m": tour.length_m, "waypoints": len(tour.waypoints)},
            **evaluation_params_dict(params),
            "simulator": sim.params(),
        },
        run=run_info,
        odometry=odometry_section(trace, relations, params) if score else {},
        mappers=scores,
        # Per-view stage times: mean, p50, p95 and max ms (the rows are in steps.csv).
        timing_ms=trace.step_times.summary_ms(),
        figures=[],
        wall_time_s=time.perf_counter() - t0,
    )
    driven = f"{tour.kind} tour {tour.length_m:.0f} m"
    if spec.max_frames is not None:  # cut short: say how much of the tour was driven
        driven = f"{run_info['travelled_m']:.0f} m of a {driven}"
    title = (f"{world.kind} seed {world.seed}  {profile.name}  {driven}  "
             f"odometry noise {spec.noise}  {trace.n_frames} views")
    return ExperimentResult(report, trace, world, tour, relations, title)
