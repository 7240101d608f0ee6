"""One fuzzing episode: its seed, its random world and tour, the run, the invariants checked.

A campaign's episode ``k`` is fully described by the campaign parameters and ``k``: its
seed is child ``k`` of the campaign seed (``SeedSequence(seed).spawn``, built directly as
``SeedSequence(seed, spawn_key=(k,))``), from which it draws the world kind, the world's
size, the tour's minimum length and the run seed (the ``RunSpec`` seed: world and
simulator; ``record.EpisodeSpec.draw``). Nothing else travels to a worker, so results
never depend on the number of workers or the order they finish in.

``run_episode`` runs the experiment (``run_experiment``, exactly as ``albot2d run`` does
with the same ``RunSpec``) with the invariant checks attached (``albot2d.evaluation.
checks``; what they find is a ``record.CheckOutcome``), scores only the record's metrics
(``albot2d.evaluation.fuzz.episode_metrics``) and returns an :class:`EpisodeOutcome`: the
typed :class:`EpisodeRecord` of the campaign's ``episodes.jsonl`` and, for a failing
episode, the reproducer document (a fully scored report.json that ``albot2d run
--reproduce`` replays, plus the world JSON and the failure).
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
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, cast

import numpy as np

from albot2d.evaluation.checks import heading_bound as hb
from albot2d.evaluation.checks import invariants as inv
from albot2d.evaluation.checks import simulator as sim_inv
from albot2d.evaluation.fuzz.episode_metrics import complete_scores, episode_metrics
from albot2d.evaluation.fuzz.record import (
    CheckMetrics,
    CheckOutcome,
    EpisodeError,
    EpisodeOutcome,
    EpisodeRecord,
    EpisodeSpec,
    EpisodeTimings,
    Json,
    JsonObject,
    episode_seed,
    finite_or_none,
)
from albot2d.evaluation.run.experiment import (
    ExperimentResult,
    evaluation_params_dict,
    run_experiment,
)
from albot2d.evaluation.run.report import make_report, plain
from albot2d.evaluation.run.scoring import EvaluationParams, route_of
from albot2d.evaluation.run.setup import build_world
from albot2d.frames import Frame
from albot2d.mapping.albot1.mapper import Albot1
from albot2d.mapping.protocol import Mapper
from albot2d.sim.driving import get_profile
from albot2d.sim.laser import laser_noise_preset
from albot2d.sim.odometry import noise_preset
from albot2d.sim.robot import RobotParams

if TYPE_CHECKING:
    from worldgen.world import Tour, World

__all__ = [
    "REPRODUCE_HOW",
    "EpisodeOutcome",
    "EpisodeRecord",
    "EpisodeSpec",
    "crash_outcome",
    "episode_seed",
    "run_checked",
    "run_episode",
]

# At most this many messages are kept per violated invariant (the first ones).
_MESSAGES_KEPT = 5
# What a reproducer says about itself.
REPRODUCE_HOW = "albot2d run --reproduce THIS_FILE --out DIR"

FrameHook = Callable[[Frame, float], None]


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
        self.world: World | None = None
        self.checked: list[str] = []
        self.violations: dict[str, list[str]] = {}

    def on_start(self, world: World, tour: Tour) -> None:
        self.world = world
        self.clearance = sim_inv.ClearanceChecker.for_world(
            world, RobotParams().radius_m, raise_at_once=False
        )
        if not world.dynamic_obstacles:  # hits on moving obstacles are not on the walls
            self.frames = sim_inv.FrameChecker(
                world.obstacle_segments, self.laser, raise_at_once=False
            )

    def on_frame(self, frame: Frame, travelled_m: float) -> None:
        if self.localisations is not None and self.localisations.resolution_rad is None:
            angles = np.asarray(frame.scan.angles)
            self.localisations.resolution_rad = float(np.abs(np.diff(angles)).max())
        if self.clearance is not None:  # walls, clutter and moving obstacles at every frame
            self.clearance(frame)
        if self.frames is not None:
            self.frames(frame)
        if self.reference is not None:
            self.reference(frame)

    def chain(self, other: FrameHook | None) -> FrameHook:
        """``on_frame``, then ``other`` (a progress display) when given."""
        if other is None:
            return self.on_frame

        def both(frame: Frame, travelled_m: float) -> None:
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

    def run(self, name: str, check: Callable[..., None], *args: object) -> None:
        self.checked.append(name)
        try:
            check(*args)
        except inv.InvariantError as exc:
            self.add(name, [exc.message])

    def finish(self, result: ExperimentResult) -> CheckOutcome:
        """Run the end-of-run checks; returns what every check found and measured."""
        trace = result.trace
        truth = trace.true_poses
        assert truth is not None and self.world is not None  # a simulated run
        assert self.clearance is not None
        self.checked.append("robot_clear_of_obstacles")
        self.add("robot_clear_of_obstacles", self.clearance.finish())
        if self.frames is not None:
            self.checked.append("laser_hits_on_obstacles")
            self.add("laser_hits_on_obstacles", self.frames.finish())
        local_position_m: float | None = None
        local_heading_deg: float | None = None
        bound_ratio: float | None = None
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
            local_position_m = float(pos.max()) if len(pos) else None
            local_heading_deg = math.degrees(float(head.max())) if len(head) else None
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
            bound_ratio = float(np.max(err / bound))
            self.run("heading_error_bound", hb.check_heading_error_bound, estimate, truth, bound)
        err = np.degrees(inv.heading_errors(estimate, truth))
        odo = np.degrees(inv.heading_errors(trace.odom_poses, truth))
        f = finite_or_none
        metrics = CheckMetrics(
            heading_error_max_deg=f(float(err.max())),
            heading_error_mean_deg=f(float(err.mean())),
            odometry_heading_error_max_deg=f(float(odo.max())),
            odometry_heading_error_mean_deg=f(float(odo.mean())),
            local_map_position_error_max_m=f(local_position_m),
            local_map_heading_error_max_deg=f(local_heading_deg),
            heading_bound_ratio_max=f(bound_ratio),
        )
        violations = {name: tuple(messages) for name, messages in self.violations.items()}
        return CheckOutcome(tuple(sorted(self.checked)), violations, metrics)


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


def _world_document(spec: EpisodeSpec, world: World | None) -> Json:
    from worldgen.io import world_to_json

    if world is None:
        try:
            world = build_world(spec.run_spec())
        except Exception:  # the world itself is what failed: the seed still reproduces it
            return None
    return cast(Json, json.loads(world_to_json(world)))


def crash_outcome(
    spec: EpisodeSpec | None,
    error: EpisodeError,
    *,
    campaign: Mapping[str, Json] | None = None,
    index: int | None = None,
    params: EvaluationParams | None = None,
    elapsed_s: float | None = None,
    world: World | None = None,
) -> EpisodeOutcome:
    """The outcome of an episode that crashed: in the run, in drawing it, or by killing its
    worker process. With ``spec`` the reproducer is a report ``albot2d run --reproduce``
    replays; without (the episode could not even be drawn) it names the campaign."""
    if spec is not None:
        index = spec.index
    assert index is not None  # a spec, or the index of the episode that could not be drawn
    entropy = (campaign or {}).get("seed") if spec is None else spec.entropy
    record = EpisodeRecord(
        episode=index,
        entropy=entropy if isinstance(entropy, int) and not isinstance(entropy, bool) else None,
        spec=spec,
        status="crash",
        error=error,
        timings=EpisodeTimings(total_s=elapsed_s),
    )
    episode = record.to_json(measurements=False)
    if spec is None:
        reproducer = {"reproducer": {"episode": episode, "campaign": dict(campaign or {})}}
        return EpisodeOutcome(record, cast(JsonObject, plain(reproducer)))
    params = params or EvaluationParams()
    doc = make_report(
        "run",
        seed=spec.run_seed,
        params={"spec": spec.run_spec().to_dict(), **evaluation_params_dict(params)},
    )
    doc["reproducer"] = {
        "episode": episode,
        "world_json": _world_document(spec, world),
        "how": REPRODUCE_HOW,
    }
    return EpisodeOutcome(record, cast(JsonObject, plain(doc)))


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
    on_frame: FrameHook | None = None,
    on_stage: Callable[[str], None] | None = None,
) -> tuple[EpisodeOutcome, ExperimentResult | None]:
    """``run_episode``, also returning the run itself (``None`` when it crashed), scored in
    full (``albot2d run --reproduce`` writes its report) unless ``full_report`` is false:
    then only a failing episode's run is (``episode_metrics.complete_scores``).
    ``on_frame`` and ``on_stage`` go to ``run_experiment`` (a progress display)."""
    params = params or EvaluationParams()
    checks = _Checks(spec)
    t0 = time.perf_counter()
    result: ExperimentResult | None = None
    try:
        result = run_experiment(
            spec.run_spec(),
            params,
            on_start=checks.on_start,
            on_frame=checks.chain(on_frame),
            on_stage=on_stage,
            on_mappers=checks.on_mappers,
            score=full_report,
        )
        metrics = episode_metrics(result, params)
        outcome = checks.finish(result)
        if outcome.violations:  # the reproducer is a fully scored report
            result = complete_scores(result, params)
    except Exception as exc:  # any failure is a finding, not the end of the campaign
        return crash_outcome(
            spec,
            EpisodeError.of(exc),
            params=params,
            world=checks.world,
            elapsed_s=time.perf_counter() - t0,
        ), None
    elapsed = time.perf_counter() - t0
    report = result.report
    record = EpisodeRecord(
        episode=spec.index,
        entropy=spec.entropy,
        spec=spec,
        status="violation" if outcome.violations else "ok",
        checks=outcome,
        metrics=metrics,
        digest=_digest(result),
        timings=EpisodeTimings(elapsed, 1e3 * elapsed / metrics.frames),
        world_sha256=report["world"]["sha256"],
        tour_length_m=report["params"]["tour"]["length_m"],
    )
    if not record.failed:
        return EpisodeOutcome(record), result
    reproducer = dict(report)
    reproducer["reproducer"] = {
        "episode": record.to_json(measurements=False),
        "world_json": _world_document(spec, checks.world),
        "how": REPRODUCE_HOW,
    }
    return EpisodeOutcome(record, cast(JsonObject, plain(reproducer))), result
