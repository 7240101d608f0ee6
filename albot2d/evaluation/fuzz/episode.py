"""One fuzzing episode: its seed, its random world and tour, the run, the invariants checked.

A campaign's episode ``k`` is fully described by the campaign parameters and ``k``: its
seed is child ``k`` of the campaign seed (``SeedSequence(seed).spawn``, built directly as
``SeedSequence(seed, spawn_key=(k,))``), from which it draws the world kind, the world's
size, the tour's minimum length and the run seed (the ``RunSpec`` seed: world and
simulator). Nothing else travels to a worker, so results never depend on the number of
workers or the order they finish in.

``run_episode`` runs the experiment (``run_experiment``, exactly as ``albot2d run`` does
with the same ``RunSpec``) with the invariant checks attached (``albot2d.evaluation.
invariants``), scores only the record's metrics (``albot2d.evaluation.fuzz.episode_metrics``)
and returns an :class:`EpisodeOutcome`: the JSON record for the campaign's
``episodes.jsonl`` and, for a failing episode, the reproducer document (a fully scored
report.json that ``albot2d run --reproduce`` replays, plus the world JSON and the failure).
``run_checked`` also returns the run itself (scored in full unless asked otherwise);
``crash_outcome`` builds the outcome of an episode that crashed, also outside
``run_episode`` (a worker process that died), with a reproducer that replays like any
other; ``albot2d.evaluation.fuzz.reproducer`` re-runs one with its checks.
"""

from __future__ import annotations

import functools
import hashlib
import json
import math
import time
import traceback
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from albot2d.errors import InputError
from albot2d.evaluation.checks import heading_bound as hb
from albot2d.evaluation.checks import invariants as inv
from albot2d.evaluation.checks import simulator as sim_inv
from albot2d.evaluation.fuzz.episode_metrics import complete_scores, episode_metrics
from albot2d.evaluation.run.experiment import (
    ExperimentResult,
    RunSpec,
    evaluation_params_dict,
    run_experiment,
)
from albot2d.evaluation.run.report import make_report, plain
from albot2d.evaluation.run.scoring import EvaluationParams, route_of
from albot2d.evaluation.run.setup import build_world
from albot2d.mapping.albot1.mapper import Albot1
from albot2d.mapping.protocol import Mapper
from albot2d.sim.driving import get_profile
from albot2d.sim.laser import laser_noise_preset
from albot2d.sim.odometry import noise_preset
from albot2d.sim.robot import RobotParams

__all__ = [
    "REPRODUCE_HOW",
    "EpisodeOutcome",
    "EpisodeSpec",
    "crash_outcome",
    "episode_seed",
    "run_checked",
    "run_episode",
]

# The largest run seed drawn for an episode (any non-negative int is a valid RunSpec seed).
_RUN_SEED_BOUND = 2**63
# Sizes and lengths are drawn on a decimetre grid so they print and replay exactly.
_DECIMETRE = 0.1
# At most this many messages are kept per violated invariant (the first ones).
_MESSAGES_KEPT = 5
# What a reproducer says about itself.
REPRODUCE_HOW = "albot2d run --reproduce THIS_FILE --out DIR"


def episode_seed(campaign_seed: int, index: int) -> np.random.SeedSequence:
    """Child ``index`` of the campaign seed, as ``SeedSequence(campaign_seed).spawn`` makes it."""
    return np.random.SeedSequence(campaign_seed, spawn_key=(index,))


def _decimetres(rng: np.random.Generator, low: float, high: float) -> float:
    lo, hi = math.ceil(low / _DECIMETRE - 1e-9), math.floor(high / _DECIMETRE + 1e-9)
    return round(int(rng.integers(lo, max(lo, hi) + 1)) * _DECIMETRE, 1)


@dataclass(frozen=True)
class EpisodeSpec:
    """Everything one episode runs: drawn from the campaign parameters and the index."""

    index: int
    entropy: int
    kind: str
    world_params: Mapping[str, Any]
    tour_length_m: float
    run_seed: int
    profile: str
    noise: str
    laser_noise: str
    tour_kind: str
    mapper: str

    @classmethod
    def draw(cls, campaign: Any, index: int) -> EpisodeSpec:
        """Episode ``index`` of ``campaign`` (a ``CampaignParams``)."""
        from worldgen.kinds import get_kind

        rng = np.random.Generator(np.random.PCG64(episode_seed(campaign.seed, index)))
        kind = campaign.kinds[int(rng.integers(len(campaign.kinds)))]
        low = max(float(get_kind(kind).params.min_size_m), campaign.world_size_min_m)
        high = max(low, campaign.world_size_max_m)
        size = {"width_m": _decimetres(rng, low, high), "height_m": _decimetres(rng, low, high)}
        tour = _decimetres(rng, campaign.tour_length_min_m, campaign.tour_length_max_m)
        return cls(
            index=index, entropy=campaign.seed, kind=kind, world_params=size,
            tour_length_m=tour, run_seed=int(rng.integers(_RUN_SEED_BOUND)),
            profile=campaign.profile, noise=campaign.noise, laser_noise=campaign.laser_noise,
            tour_kind=campaign.tour_kind, mapper=campaign.mapper,
        )  # fmt: skip

    @classmethod
    def from_record(cls, record: Mapping[str, Any]) -> EpisodeSpec:
        """The episode a record (an episodes.jsonl line, a reproducer's episode) describes."""
        try:
            return cls(
                index=record["episode"], entropy=record["seed"]["entropy"],
                kind=record["world"]["kind"], world_params=dict(record["world"]["params"]),
                tour_length_m=record["tour"]["min_length_m"], run_seed=record["run_seed"],
                profile=record["profile"], noise=record["noise"],
                laser_noise=record["laser_noise"], tour_kind=record["tour"]["kind"],
                mapper=record["mapper"],
            )  # fmt: skip
        except (KeyError, TypeError) as exc:
            raise InputError(f"not an episode record: missing {exc}") from None

    @property
    def spawn_key(self) -> tuple[int, ...]:
        return (self.index,)

    def run_spec(self) -> RunSpec:
        return RunSpec(
            seed=self.run_seed, kind=self.kind, world_params=dict(self.world_params),
            profile=self.profile, noise=self.noise, laser_noise=self.laser_noise,
            tour_kind=self.tour_kind, tour_length_m=self.tour_length_m, mappers=(self.mapper,),
            tour_length_is_minimum=True,
        )  # fmt: skip

    def describe(self) -> dict[str, Any]:
        """The record's header: seed, world, tour and driving parameters."""
        return {
            "episode": self.index,
            "seed": {"entropy": self.entropy, "spawn_key": list(self.spawn_key)},
            "run_seed": self.run_seed,
            "world": {"kind": self.kind, "params": dict(self.world_params)},
            "tour": {"kind": self.tour_kind, "min_length_m": self.tour_length_m},
            "profile": self.profile,
            "noise": self.noise,
            "laser_noise": self.laser_noise,
            "mapper": self.mapper,
        }


@dataclass
class EpisodeOutcome:
    """``record``: the episodes.jsonl line; ``reproducer``: the document to save, if failing."""

    record: dict[str, Any]
    reproducer: dict[str, Any] | None = None

    @property
    def failed(self) -> bool:
        return self.record["status"] != "ok"


class _Checks:
    """The invariant hooks of one run, and what they found."""

    def __init__(self, spec: EpisodeSpec) -> None:
        self.spec = spec
        self.laser = laser_noise_preset(spec.laser_noise)
        self.frames: sim_inv.FrameChecker | None = None
        self.clearance: sim_inv.ClearanceChecker | None = None
        self.updates: inv.UpdateRecorder | None = None
        self.views: inv.ViewRecorder | None = None
        self.reference: hb.ReferenceLinks | None = None
        self.localisations: inv.LocalisationRecorder | None = None
        self.world: Any = None
        self.checked: list[str] = []
        self.violations: dict[str, list[str]] = {}

    def on_start(self, world: Any, tour: Any) -> None:
        self.world = world
        self.clearance = sim_inv.ClearanceChecker.for_world(
            world, RobotParams().radius_m, raise_at_once=False
        )
        if not world.dynamic_obstacles:  # hits on moving obstacles are not on the walls
            self.frames = sim_inv.FrameChecker(
                world.obstacle_segments, self.laser, raise_at_once=False
            )

    def on_frame(self, frame: Any, travelled_m: float) -> None:
        if self.localisations is not None and self.localisations.resolution_rad is None:
            angles = np.asarray(frame.scan.angles)
            self.localisations.resolution_rad = float(np.abs(np.diff(angles)).max())
        if self.clearance is not None:  # walls, clutter and moving obstacles at every frame
            self.clearance(frame)
        if self.frames is not None:
            self.frames(frame)
        if self.reference is not None:
            self.reference(frame)

    def chain(self, other: Any) -> Any:
        """``on_frame``, then ``other`` (a progress display) when given."""
        if other is None:
            return self.on_frame

        def both(frame: Any, travelled_m: float) -> None:
            self.on_frame(frame, travelled_m)
            other(frame, travelled_m)

        return both

    def on_mappers(self, mappers: Mapping[str, Mapper]) -> None:
        for mapper in mappers.values():
            if isinstance(mapper, Albot1):
                self.updates = inv.UpdateRecorder(raise_at_once=False).attach(mapper)
                self.views = inv.ViewRecorder().attach(mapper)
                self.localisations = inv.LocalisationRecorder().attach(mapper)
            elif route_of(mapper) is None:  # held to a view-based localiser's links
                self.reference = hb.ReferenceLinks()

    def add(self, name: str, messages: list[str]) -> None:
        if messages:
            self.violations.setdefault(name, []).extend(messages[:_MESSAGES_KEPT])

    def run(self, name: str, check: Any, *args: Any) -> None:
        self.checked.append(name)
        try:
            check(*args)
        except inv.InvariantError as exc:
            self.add(name, [exc.message])

    def finish(self, result: ExperimentResult) -> dict[str, Any]:
        """Run the end-of-run checks; returns the invariant-derived metrics."""
        trace = result.trace
        truth = trace.true_poses
        assert truth is not None and self.world is not None  # a simulated run
        assert self.clearance is not None
        self.checked.append("robot_clear_of_obstacles")
        self.add("robot_clear_of_obstacles", self.clearance.finish())
        if self.frames is not None:
            self.checked.append("laser_hits_on_obstacles")
            self.add("laser_hits_on_obstacles", self.frames.finish())
        metrics: dict[str, Any] = {}
        (mapper,) = trace.mappers.values()
        if isinstance(mapper, Albot1):
            assert self.views is not None  # attached in on_mappers
            self.run("local_map_rule", inv.check_local_map_rule, mapper, self.views.views)
            self.checked.append("update_deletes_facing_overlap")
            assert self.updates is not None
            self.add("update_deletes_facing_overlap", self.updates.violations)
        route = route_of(mapper)
        estimate = np.asarray(mapper.trajectory(), dtype=np.float64)
        if route is not None:
            self.run("route_connected", inv.check_route_connected, route)
            pos, head = inv.local_map_errors(route, trace.frame_indices, truth)
            metrics["local_map_position_error_max_m"] = float(pos.max()) if len(pos) else None
            metrics["local_map_heading_error_max_deg"] = (
                math.degrees(float(head.max())) if len(head) else None
            )
            noise = noise_preset(self.spec.noise)
            if noise.is_zero and self.laser.is_zero:
                # Albot1's links get their own bounds from the surfaces they were
                # localised from; other view-based mappers the fixed ones.
                recorder, split = None, None
                if isinstance(mapper, Albot1):
                    recorder = self.localisations
                    split = mapper.params.extraction.split_distance_m
                self.run(
                    "zero_noise_localisation",
                    functools.partial(
                        inv.check_zero_noise_localisation,
                        localisations=recorder,
                        split_distance_m=split,
                    ),
                    route,
                    trace.frame_indices,
                    truth,
                )
        links = route
        used = self.localisations.pairs if self.localisations is not None else None
        if links is None and self.reference is not None:
            links, used = self.reference.route, self.reference.used
        if links is not None and len(estimate) == len(truth):
            tracking = mapper.params.tracking if isinstance(mapper, Albot1) else None
            extraction = mapper.params.extraction if isinstance(mapper, Albot1) else None
            bound = hb.heading_error_bound(
                links, trace.frame_indices, truth, noise_preset(self.spec.noise),
                get_profile(self.spec.profile), self.laser, tracking,
                extraction=extraction, used=used,
            )  # fmt: skip
            err = hb.heading_errors(estimate, truth)
            metrics["heading_bound_ratio_max"] = float(np.max(err / bound))
            self.run("heading_error_bound", hb.check_heading_error_bound, estimate, truth, bound)
        err = np.degrees(inv.heading_errors(estimate, truth))
        odo = np.degrees(inv.heading_errors(trace.odom_poses, truth))
        metrics |= {
            "heading_error_max_deg": float(err.max()), "heading_error_mean_deg": float(err.mean()),
            "odometry_heading_error_max_deg": float(odo.max()),
            "odometry_heading_error_mean_deg": float(odo.mean()),
        }  # fmt: skip
        return metrics


def _digest(result: ExperimentResult) -> str:
    """SHA-256 of what the run produced (poses and map): equal digests, equal episodes."""
    trace = result.trace
    h = hashlib.sha256()
    for mapper in trace.mappers.values():
        h.update(np.ascontiguousarray(mapper.trajectory(), dtype=np.float64).tobytes())
        snap = mapper.global_map()
        h.update(np.ascontiguousarray(snap.segments, dtype=np.float64).tobytes())
        h.update(np.ascontiguousarray(snap.map_ids, dtype=np.int64).tobytes())
    h.update(trace.odom_poses.tobytes())
    if trace.true_poses is not None:
        h.update(trace.true_poses.tobytes())
    return h.hexdigest()


def _world_document(spec: EpisodeSpec, world: Any) -> Any:
    from worldgen.io import world_to_json

    if world is None:
        try:
            world = build_world(spec.run_spec())
        except Exception:  # the world itself is what failed: the seed still reproduces it
            return None
    return json.loads(world_to_json(world))


def crash_outcome(
    spec: EpisodeSpec | None,
    error: Mapping[str, Any],
    *,
    campaign: Mapping[str, Any] | None = None,
    index: int | None = None,
    params: EvaluationParams | None = None,
    elapsed_s: float | None = None,
    world: Any = None,
) -> EpisodeOutcome:
    """The outcome of an episode that crashed: in the run, in drawing it, or by killing its
    worker process. With ``spec`` the reproducer is a report ``albot2d run --reproduce``
    replays; without (the episode could not even be drawn) it names the campaign."""
    if spec is None:
        record: dict[str, Any] = {
            "episode": index,
            "seed": {"entropy": (campaign or {}).get("seed"), "spawn_key": [index]},
        }
    else:
        record = spec.describe()
    record |= {
        "status": "crash",
        "checked": [],
        "violations": {},
        "error": dict(error),
        "metrics": {},
        "digest": None,
        "timings": {"total_s": elapsed_s, "ms_per_view": None},
    }
    record = plain(record)
    episode = {k: v for k, v in record.items() if k not in ("metrics", "timings")}
    if spec is None:
        return EpisodeOutcome(
            record, plain({"reproducer": {"episode": episode, "campaign": dict(campaign or {})}})
        )
    params = params or EvaluationParams()
    reproducer = make_report(
        "run",
        seed=spec.run_seed,
        params={"spec": spec.run_spec().to_dict(), **evaluation_params_dict(params)},
    )
    reproducer["reproducer"] = {
        "episode": episode,
        "world_json": _world_document(spec, world),
        "how": REPRODUCE_HOW,
    }
    return EpisodeOutcome(record, plain(reproducer))


def run_episode(spec: EpisodeSpec, params: EvaluationParams | None = None) -> EpisodeOutcome:
    """Run one episode with every applicable invariant checked; never raises for a failure
    of the run itself (a crash is recorded with its traceback). Only the record's metrics
    are scored, unless the episode fails (its reproducer is a fully scored report)."""
    return run_checked(spec, params, full_report=False)[0]


def run_checked(
    spec: EpisodeSpec,
    params: EvaluationParams | None = None,
    *,
    full_report: bool = True,
    **hooks: Any,
) -> tuple[EpisodeOutcome, ExperimentResult | None]:
    """``run_episode``, also returning the run itself (``None`` when it crashed), scored in
    full (``albot2d run --reproduce`` writes its report) unless ``full_report`` is false:
    then only a failing episode's run is (``episode_metrics.complete_scores``)."""
    params = params or EvaluationParams()
    record = spec.describe()
    checks = _Checks(spec)
    t0 = time.perf_counter()
    result: ExperimentResult | None = None
    try:
        result = run_experiment(
            spec.run_spec(),
            params,
            on_start=checks.on_start,
            on_frame=checks.chain(hooks.pop("on_frame", None)),
            on_mappers=checks.on_mappers,
            score=full_report,
            **hooks,
        )
        metrics = episode_metrics(result, params)
        metrics |= checks.finish(result)
        if checks.violations:  # the reproducer is a fully scored report
            result = complete_scores(result, params)
    except Exception as exc:  # any failure is a finding, not the end of the campaign
        error = {
            "type": type(exc).__name__,
            "message": str(exc),
            "traceback": traceback.format_exc(),
        }
        return crash_outcome(
            spec, error, params=params, world=checks.world, elapsed_s=time.perf_counter() - t0
        ), None
    elapsed = time.perf_counter() - t0
    status = "violation" if checks.violations else "ok"
    record["world"]["sha256"] = result.report["world"]["sha256"]
    record["tour"]["length_m"] = result.report["params"]["tour"]["length_m"]
    record |= {
        "status": status,
        "checked": sorted(checks.checked),
        "violations": checks.violations,
        "error": None,
        "metrics": metrics,
        "digest": _digest(result),
        "timings": {"total_s": elapsed, "ms_per_view": 1e3 * elapsed / metrics["frames"]},
    }
    record = plain(record)
    if status == "ok":
        return EpisodeOutcome(record), result
    reproducer = dict(result.report)
    reproducer["reproducer"] = {
        "episode": {k: v for k, v in record.items() if k not in ("metrics", "timings")},
        "world_json": _world_document(spec, checks.world),
        "how": REPRODUCE_HOW,
    }
    return EpisodeOutcome(record, plain(reproducer)), result
