"""Invariants of a simulated run and its mapper, shared by the tests and the fuzzing campaign.

Each ``check_*`` raises :class:`InvariantError` (an ``AssertionError`` carrying the
invariant's name) when its property fails, so tests use them directly and the campaign
records the name and message. Which checks apply:

- any simulated run: ``robot_clear_of_obstacles`` and ``laser_hits_on_obstacles``, in
  ``albot2d.evaluation.checks.simulator``;
- view-based mappers (with a route map): ``route_connected`` (every local map after the
  first has a pose in its predecessor and composing the chain gives every map's pose),
  ``zero_noise_localisation`` (with no odometry or laser noise, each local map is placed in
  its predecessor within 5 cm / 0.5°) and ``heading_error_bound`` (see
  :func:`heading_error_bound`);
- Albot1 only: ``local_map_rule`` (algorithm #2's remembering rule with Use-Vc, its
  tracked counts recounted from the views a ``ViewRecorder`` kept) and
  ``update_deletes_facing_overlap`` (algorithm #5's postcondition after every update, in
  ``albot2d.evaluation.checks.deletion``).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from albot2d.errors import InvariantError, fail
from albot2d.evaluation.checks.deletion import (
    UpdateRecorder,
    check_update_deleted_facing_overlap,
)
from albot2d.geometry import Pose, between_arrays, wrap_angle
from albot2d.mapping.albot1.mapper import Albot1
from albot2d.mapping.albot1.route_map import RouteMap
from albot2d.perception.surfaces import Surfaces
from albot2d.perception.tracking import TrackingParams, recognise, trackable_mask
from albot2d.sim.driving import DrivingProfile
from albot2d.sim.odometry import OdometryNoise, heading_variance_rad2
from albot2d.validation import check_non_negative, check_positive

__all__ = [
    "INVARIANTS",
    "InvariantError",
    "InvariantParams",
    "RecountedStep",
    "UpdateRecorder",
    "ViewRecorder",
    "check_heading_error_bound",
    "check_local_map_rule",
    "check_route_connected",
    "check_update_deleted_facing_overlap",
    "check_zero_noise_localisation",
    "fail",
    "heading_error_bound",
    "heading_errors",
    "local_map_errors",
    "local_maps_per_row",
    "recount_tracking",
]

FloatArray = NDArray[np.float64]

INVARIANTS: tuple[str, ...] = (
    "route_connected",
    "local_map_rule",
    "update_deletes_facing_overlap",
    "robot_clear_of_obstacles",
    "laser_hits_on_obstacles",
    "zero_noise_localisation",
    "heading_error_bound",
)


@dataclass(frozen=True, slots=True)
class InvariantParams:
    """Tolerances and bounds of the invariants.

    - ``chain_atol_m``: stored vs freshly composed route-map poses (float rounding only).
    - ``overlap_tolerance_m``: how far the robot disc may reach into an obstacle (rounding).
    - ``hit_tolerance_m`` + ``hit_sigmas`` × the laser's range sigma (+ half its resolution,
      + the jitter's lateral offset at that many sigmas): how far a hit may lie off a wall.
    - ``zero_noise_position_m`` / ``zero_noise_heading_deg``: the largest error of a local
      map's pose in its predecessor when neither odometry nor laser is noisy.
    - ``heading_sigmas``, ``heading_floor_deg``, ``triangulation_heading_deg``: the heading
      bound (see :func:`heading_error_bound`).
    """

    chain_atol_m: float = 1e-9
    overlap_tolerance_m: float = 1e-9
    hit_tolerance_m: float = 1e-6
    hit_sigmas: float = 7.0
    zero_noise_position_m: float = 0.05
    zero_noise_heading_deg: float = 0.5
    heading_sigmas: float = 5.0
    heading_floor_deg: float = 1.0
    triangulation_heading_deg: float = 0.6

    def __post_init__(self) -> None:
        check_non_negative(
            self,
            "chain_atol_m",
            "overlap_tolerance_m",
            "hit_tolerance_m",
            "heading_floor_deg",
            "triangulation_heading_deg",
        )
        check_positive(
            self, "hit_sigmas", "zero_noise_position_m", "zero_noise_heading_deg", "heading_sigmas"
        )


# -- the route map and algorithm #2 ---------------------------------------------------------
def check_route_connected(route: RouteMap, atol_m: float = 1e-9) -> None:
    """Every local map after the first has a pose in its predecessor, ids run 0, 1, 2…,
    and composing the chain afresh gives every stored pose."""
    name = "route_connected"
    maps = route.maps
    if [lm.map_id for lm in maps] != list(range(len(maps))):
        fail(name, "local map ids are not 0, 1, 2, … in order")
    for lm in maps[1:]:
        if lm.method == "start":
            fail(
                name,
                f"local map {lm.map_id} (frame {lm.frame_index}) has no pose in its "
                "predecessor (method 'start')",
            )
    if not maps:
        return
    rel = route.relative_poses()
    if not np.all(np.isfinite(rel)):
        bad = int(np.flatnonzero(~np.isfinite(rel).all(axis=1))[0])
        fail(name, f"local map {bad} has a non-finite pose in its predecessor")
    chain = route.compose_chain()
    stored = np.array([lm.pose.as_array() for lm in maps])
    diff = np.abs(chain - stored)
    diff[:, 2] = np.abs(wrap_angle(chain[:, 2] - stored[:, 2]))
    if diff.max() > atol_m:
        bad = int(np.argmax(diff.max(axis=1)))
        fail(
            name,
            f"local map {bad}: composed chain differs from its stored pose by "
            f"{diff[bad].max():.3g}",
        )


class ViewRecorder:
    """An Albot1 ``on_view`` hook keeping every view it is given (frame index, surfaces,
    odometry increment): ``check_local_map_rule`` recounts tracking from them."""

    def __init__(self) -> None:
        self.views: list[tuple[int, Surfaces, Pose]] = []

    def attach(self, mapper: Albot1) -> ViewRecorder:
        """Hook into ``mapper`` (its ``on_view``); returns self."""
        mapper.on_view = self
        return self

    def __call__(self, frame_index: int, view: Surfaces, increment: Pose) -> None:
        self.views.append((frame_index, view, increment))


@dataclass(frozen=True, slots=True)
class RecountedStep:
    """One view as recounted from the views alone (not the mapper's records): the
    ``tracked`` surfaces RTSV (algorithm #1) leaves against the tracked set in force, and
    the frames algorithm #2 must ``remember`` at this view given those counts."""

    frame_index: int
    tracked: int
    remembered: tuple[int, ...]


def recount_tracking(
    views: Sequence[tuple[int, Surfaces, Pose]], params: TrackingParams, min_tracked: int
) -> list[RecountedStep]:
    """Replay algorithm #2's tracking and remembering decisions from the views as given.

    The first view is remembered. At view c, |RTSV(V(c), S_t)| (line 4) is counted; when it
    is below ``min_tracked`` and V(c-1) is not the current local map (Use-V(c) false),
    V(c-1) is remembered and V(c) re-tracked from it (line 12, goto 4); when (still) below,
    V(c) is remembered. A remembered view restarts the tracked set (``start_tracking``).
    Only the views, the tracking parameters and the rule go in: nothing of the mapper.
    """
    out: list[RecountedStep] = []
    if not views:
        return out

    def start(view: Surfaces) -> Surfaces:  # start_tracking's surfaces (ids not needed)
        return view.select(trackable_mask(view, params))

    first, view, _ = views[0]
    out.append(RecountedStep(first, 0, (first,)))
    current = start(view)  # the tracked surfaces' latest observations
    use_vc = True  # V(c-1) (the first view) is the current local map
    for (prev_frame, prev_view, _), (frame, view, increment) in itertools.pairwise(views):
        counted = recognise(current, view, increment, params).view_index
        current = view.select(counted)
        remembered: tuple[int, ...] = ()
        if len(counted) < min_tracked:
            if not use_vc:
                remembered = (prev_frame,)
                kept = recognise(start(prev_view), view, increment, params).view_index
                current = view.select(kept)
            if len(current) < min_tracked:
                remembered += (frame,)
                current = start(view)
        out.append(RecountedStep(frame, len(counted), remembered))
        use_vc = bool(remembered) and remembered[-1] == frame
    return out


def check_local_map_rule(
    m: Albot1, views: Sequence[tuple[int, Surfaces, Pose]], min_tracked: int | None = None
) -> None:
    """A view is remembered exactly when fewer than ``min_tracked`` tracked surfaces remain;
    V(c-1) is remembered unless it already is the current local map (Use-Vc), which holds
    exactly when the previous step remembered V(c-1); the route map is connected.

    The tracked counts and the views to remember are recounted from ``views`` (every view
    the mapper was given, e.g. kept by a ``ViewRecorder``; ``recount_tracking``): the route
    map must hold exactly those views, and the mapper's ``StepRecord``s must agree."""
    name = "local_map_rule"
    need = m.params.min_tracked if min_tracked is None else min_tracked
    steps = recount_tracking(views, m.params.tracking, need)
    if len(steps) != len(m.steps):
        fail(name, f"{len(steps)} views given but {len(m.steps)} steps recorded")
    expected = [f for step in steps for f in step.remembered]
    held = [lm.frame_index for lm in m.route]
    if held != expected:
        k = next((i for i, (a, b) in enumerate(zip(held, expected, strict=False)) if a != b),
                 min(len(held), len(expected)))  # fmt: skip
        fail(
            name,
            f"the route map remembers frames {held[k : k + 3]}… from its local map {k} "
            f"on, the recounted rule gives {expected[k : k + 3]}…",
        )
    use_vc = False
    for step, record in zip(steps, m.steps, strict=True):
        recounted = (step.frame_index, step.tracked, step.remembered, use_vc)
        if (record.frame_index, record.tracked, record.remembered, record.use_vc) != recounted:
            fail(
                name,
                f"frame {step.frame_index}: recorded {record.tracked} tracked, "
                f"{record.remembered} remembered, Use-Vc {record.use_vc}; recounted "
                f"{step.tracked}, {step.remembered}, {use_vc}",
            )
        use_vc = bool(step.remembered) and step.remembered[-1] == step.frame_index
    try:
        check_route_connected(m.route)
    except InvariantError as exc:
        fail(name, exc.message)


# -- localisation accuracy ------------------------------------------------------------------
def _rows_of(frame_indices: NDArray[np.int64], wanted: NDArray[np.int64]) -> NDArray[np.int64]:
    order = np.argsort(frame_indices, kind="stable")
    pos = np.searchsorted(frame_indices[order], wanted)
    return order[np.clip(pos, 0, len(order) - 1)]


def local_map_errors(
    route: RouteMap, frame_indices: NDArray[np.int64], true_poses: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Position (m) and absolute heading (rad) error of each local map's pose in its
    predecessor (maps 1…L-1), against the true relative pose of the two views."""
    if len(route) < 2:
        return np.zeros(0), np.zeros(0)
    rows = _rows_of(np.asarray(frame_indices), np.array([lm.frame_index for lm in route]))
    truth = true_poses[rows]
    rel_true = between_arrays(truth[:-1], truth[1:])
    rel_est = route.relative_poses()[1:]
    err = between_arrays(rel_true, rel_est)
    return np.hypot(err[:, 0], err[:, 1]), np.abs(np.asarray(wrap_angle(err[:, 2])))


def check_zero_noise_localisation(
    route: RouteMap,
    frame_indices: NDArray[np.int64],
    true_poses: FloatArray,
    params: InvariantParams | None = None,
) -> None:
    """With no noise, every local map is placed in its predecessor within the bounds."""
    p = params or InvariantParams()
    pos, head = local_map_errors(route, frame_indices, true_poses)
    bad = (pos > p.zero_noise_position_m) | (head > math.radians(p.zero_noise_heading_deg))
    if bad.any():
        k = int(
            np.argmax(
                np.maximum(
                    pos / p.zero_noise_position_m, head / math.radians(p.zero_noise_heading_deg)
                )
            )
        )
        lm = route[k + 1]
        fail(
            "zero_noise_localisation",
            f"{int(bad.sum())} of {len(pos)} local maps off; worst map {lm.map_id} (frame "
            f"{lm.frame_index}, {lm.method}, {lm.tracked} tracked): {pos[k]:.3f} m, "
            f"{math.degrees(head[k]):.2f}° (bounds {p.zero_noise_position_m} m, "
            f"{p.zero_noise_heading_deg}°)",
        )


def heading_errors(estimate: FloatArray, truth: FloatArray) -> FloatArray:
    """Absolute heading error (rad) of each pose relative to the run's first pose."""
    est = np.asarray(estimate)[:, 2] - estimate[0, 2]
    true = np.asarray(truth)[:, 2] - truth[0, 2]
    return np.abs(np.asarray(wrap_angle(est - true)))


def heading_error_bound(
    true_poses: FloatArray,
    noise: OdometryNoise,
    profile: DrivingProfile,
    local_maps: NDArray[np.int64],
    params: InvariantParams | None = None,
) -> FloatArray:
    """The largest plausible heading error (rad) at each pose of a run, for a view-based
    mapper fed odometry with ``noise`` and driven with ``profile``.

    Odometry's own error envelope over the true motion so far — ``heading_sigmas`` standard
    deviations of its random error (a random walk: variance α1² per radian turned plus α2²
    per metre driven, ``albot2d.sim.odometry.heading_variance_rad2``), plus the systematic
    part at full strength (turn scale error × radians turned, drift × metres, the induced
    error × turn steps) — widened by a random walk of ``triangulation_heading_deg`` per
    local map remembered (the laser-based localisation's own error) and a floor of
    ``heading_floor_deg``. A mapper that places views by the laser should stay well inside
    it; one that breaks (a flipped triangulation, a lost local map) leaves it.
    """
    p = params or InvariantParams()
    poses = np.asarray(true_poses, dtype=np.float64)
    inc = between_arrays(poses[:-1], poses[1:]) if len(poses) > 1 else np.zeros((0, 3))
    dist = np.hypot(inc[:, 0], inc[:, 1])
    turn = np.abs(np.asarray(wrap_angle(inc[:, 2])))
    turn_steps = np.ceil(turn / math.radians(profile.turn_step_deg) - 1e-9)
    var = heading_variance_rad2(noise, dist, turn)
    induced_rad = math.radians(abs(noise.induced_step_deg) + abs(profile.induced_step_deg))
    systematic = (
        abs(noise.turn_scale_error) * turn
        + math.radians(abs(noise.heading_drift_deg_per_m)) * dist
        + induced_rad * turn_steps
    )
    zero = np.zeros(1)
    var_total = np.concatenate([zero, np.cumsum(var)])
    var_total += math.radians(p.triangulation_heading_deg) ** 2 * np.asarray(local_maps)
    sys_total = np.concatenate([zero, np.cumsum(systematic)])
    return math.radians(p.heading_floor_deg) + p.heading_sigmas * np.sqrt(var_total) + sys_total


def local_maps_per_row(route: RouteMap, frame_indices: NDArray[np.int64]) -> NDArray[np.int64]:
    """How many local maps had been remembered by each trace row's view."""
    made = np.sort(np.array([lm.frame_index for lm in route], dtype=np.int64))
    return np.searchsorted(made, np.asarray(frame_indices), side="right").astype(np.int64)


def check_heading_error_bound(
    estimate: FloatArray, true_poses: FloatArray, bound: FloatArray
) -> None:
    """The heading error relative to the start stays within ``bound`` at every pose."""
    err = heading_errors(estimate, true_poses)
    over = err > bound
    if over.any():
        k = int(np.argmax(err - bound))
        fail(
            "heading_error_bound",
            f"row {k}: heading error {math.degrees(err[k]):.2f}° exceeds the bound "
            f"{math.degrees(bound[k]):.2f}° ({int(over.sum())} of {len(err)} poses over)",
        )
