"""Invariants of a simulated run and its mapper, shared by the tests and the fuzzing campaign.

Each ``check_*`` raises :class:`InvariantError` (an ``AssertionError`` carrying the
invariant's name) when its property fails, so tests use them directly and the campaign
records the name and message. Which checks apply:

- any simulated run: ``robot_clear_of_obstacles`` and ``laser_hits_on_obstacles``, in
  ``albot2d.evaluation.checks.simulator``;
- view-based mappers (with a route map): ``route_connected`` (every local map after the
  first has a pose in its predecessor and composing the chain gives every map's pose),
  ``zero_noise_localisation`` (with no odometry or laser noise, each local map is placed in
  its predecessor within 5 cm / 0.5°);
- every mapper that reports a trajectory: ``heading_error_bound`` (the heading error stays
  within the mapper's own localisation error model, ``albot2d.evaluation.heading_bound``);
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
from albot2d.evaluation.checks.deletion import check_update_deleted_facing_overlap
from albot2d.evaluation.checks.deletion_partition import UpdateRecorder
from albot2d.evaluation.checks.heading_bound import (
    check_heading_error_bound,
    heading_error_bound,
    heading_errors,
)
from albot2d.geometry import Pose, between_arrays, segment_angles, wrap_angle
from albot2d.mapping.albot1.mapper import Albot1, Localisation
from albot2d.mapping.albot1.route_map import RouteMap
from albot2d.perception.surfaces import Surfaces
from albot2d.perception.tracking import (
    TrackingParams,
    recognise,
    trackable_mask,
)
from albot2d.validation import check_non_negative, check_positive

__all__ = [
    "INVARIANTS",
    "InvariantError",
    "InvariantParams",
    "LocalisationRecorder",
    "RecountedStep",
    "UpdateRecorder",
    "ViewRecorder",
    "ZeroNoiseBound",
    "check_heading_error_bound",
    "check_local_map_rule",
    "check_route_connected",
    "check_update_deleted_facing_overlap",
    "check_zero_noise_localisation",
    "end_position_bounds",
    "fail",
    "fit_direction_bounds",
    "heading_error_bound",
    "heading_errors",
    "local_map_errors",
    "recount_tracking",
    "zero_noise_link_bounds",
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
    (The heading bound's constants are ``heading_bound.HeadingBoundParams``.)
    """

    chain_atol_m: float = 1e-9
    overlap_tolerance_m: float = 1e-9
    hit_tolerance_m: float = 1e-6
    hit_sigmas: float = 7.0
    zero_noise_position_m: float = 0.05
    zero_noise_heading_deg: float = 0.5

    def __post_init__(self) -> None:
        check_non_negative(
            self,
            "chain_atol_m",
            "overlap_tolerance_m",
            "hit_tolerance_m",
        )
        check_positive(self, "hit_sigmas", "zero_noise_position_m", "zero_noise_heading_deg")


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
    views: Sequence[tuple[int, Surfaces, Pose]],
    params: TrackingParams,
    min_tracked: int,
    move_using_pi: str = "restated",
) -> list[RecountedStep]:
    """Replay algorithm #2's tracking and remembering decisions from the views as given.

    The first view is remembered. At view c, |RTSV(V(c), S_t)| (line 4) is counted; when it
    is below ``min_tracked`` and V(c-1) is not the current local map (Use-V(c) false),
    V(c-1) is remembered and V(c) re-tracked from it (line 12, goto 4); when (still) below,
    V(c) is remembered. A remembered view restarts the tracked set (``start_tracking``).
    Only the views, the tracking parameters and the rule go in: nothing of the mapper.
    With ``move_using_pi="as_written"`` (algorithm #4 as the paper writes it), a view
    remembered with no trackable surface (``"on_lost_tracking"``: no tracked surface left)
    starts a stretch in which every view is remembered, its ``tracked`` count being its
    trackable surfaces, until one has at least ``min_tracked``.
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
    pi_mode = False
    for (prev_frame, prev_view, _), (frame, view, increment) in itertools.pairwise(views):
        if pi_mode:
            trackable = int(np.count_nonzero(trackable_mask(view, params)))
            out.append(RecountedStep(frame, trackable, (frame,)))
            current = start(view)
            pi_mode = trackable < min_tracked
            use_vc = True
            continue
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
                lost = len(current) == 0
                current = start(view)
                # algorithm #2 line 8: as written, S_t is the remembered view's trackable
                # surfaces (update-maps line 2); read as RTSV's result, the tracked ones
                pi_mode = (move_using_pi == "as_written" and len(current) == 0) or (
                    move_using_pi == "on_lost_tracking" and lost
                )
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
    steps = recount_tracking(views, m.params.tracking, need, m.params.move_using_pi)
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


class LocalisationRecorder:
    """An Albot1 ``on_localise`` hook keeping, per local map after the first, the tracked
    surface pairs (local map, current view) it was localised from; ``resolution_rad`` is
    the laser's angle between beams (set it from a scan, e.g. the first frame's)."""

    def __init__(self, resolution_rad: float | None = None) -> None:
        self.pairs: list[tuple[Surfaces, Surfaces]] = []
        self.resolution_rad = resolution_rad

    def attach(self, mapper: Albot1) -> LocalisationRecorder:
        """Hook into ``mapper`` (its ``on_localise``); returns self."""
        mapper.on_localise = self
        return self

    def __call__(self, localisation: Localisation) -> None:
        tracked = localisation.tracked
        self.pairs.append((tracked.local, tracked.current))


# Beams within ``split_distance_m`` of a surface's line may belong to the next face round
# a corner; at most this many at one end tilt a fit (see ``fit_direction_bounds``).
_STRAY_BEAMS = 2
# Leverage of an end beam in a fit of beams spread unevenly along a surface (a surface seen
# obliquely has its beams denser at the near end), against evenly spread beams.
_UNEVEN_SPREAD = 2.0
# Float rounding of a composed relative pose (exact odometry, exact ranges).
_ZERO_NOISE_ATOL = 1e-6


def fit_direction_bounds(surfaces: Surfaces, split_distance_m: float) -> FloatArray:
    """The most each surface's fitted direction (rad) can be off its wall with exact ranges.

    Extraction keeps a surface's beams within ``split_distance_m`` (e) of its fitted line,
    so a beam of the next face round a corner can join it. Over ``n`` beams spread evenly
    along length ``L``, one such beam at offset e at an end tilts the total-least-squares
    line by about ``6 e / (n L)``; ``_STRAY_BEAMS`` of them and an uneven spread of beams
    (``_UNEVEN_SPREAD``: n and L come from the laser's angular resolution and the surface's
    range and incidence) give ``24 e / (n L)``. Surfaces not from a scan: no bound (inf).
    """
    b = surfaces.beams
    n = np.where(b[:, 0] >= 0, b[:, 1] - b[:, 0] + 1, 0).astype(np.float64)
    length = surfaces.lengths_m
    with np.errstate(divide="ignore"):
        bound = 6.0 * _STRAY_BEAMS * _UNEVEN_SPREAD * split_distance_m / (n * length)
    return np.where((n >= 2) & (length > 0), bound, np.inf)


def end_position_bounds(
    surfaces: Surfaces, resolution_rad: float, split_distance_m: float
) -> FloatArray:
    """``(N, 2)``: how far each end may lie from the wall's real end with exact ranges (m).

    The laser samples a surface only at its beams, so its real end lies between the last
    hit and where the next beam meets its line: the beam spacing on the surface there,
    ``r Δφ / sin β`` (range r, resolution Δφ, β the angle between the beam and the
    surface); the end is the last hit projected onto the fitted line, which moves it by at
    most ``split_distance_m``."""
    segs = surfaces.segments
    ends = segs.reshape(-1, 2, 2)
    d = segs[:, 2:] - segs[:, :2]
    u = d / np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-12)[:, None]
    r = np.hypot(ends[..., 0], ends[..., 1])
    bearing = ends / np.maximum(r, 1e-12)[..., None]
    sin_beta = np.abs(u[:, None, 0] * bearing[..., 1] - u[:, None, 1] * bearing[..., 0])
    return r * resolution_rad / np.maximum(sin_beta, 1e-3) + split_distance_m


@dataclass(frozen=True, slots=True)
class ZeroNoiseBound:
    """One link's zero-noise bound and error: heading (rad) and position (m). ``hull``: the
    largest heading error of the tracked surfaces' own heading affordances (a triangulated
    heading is a weighted mean of them); ``fit``: the largest of their fit bounds
    (``fit_direction_bounds`` of both observations)."""

    heading_err_rad: float
    heading_bound_rad: float
    position_err_m: float
    position_bound_m: float
    hull_rad: float
    fit_rad: float


def zero_noise_link_bounds(
    route: RouteMap,
    frame_indices: NDArray[np.int64],
    true_poses: FloatArray,
    pairs: Sequence[tuple[Surfaces, Surfaces]],
    resolution_rad: float,
    split_distance_m: float,
) -> list[ZeroNoiseBound]:
    """Each link's (local map after the first) error and bound with exact odometry and
    ranges, from the tracked surface pairs it was localised from (``LocalisationRecorder``).

    Heading: a triangulated heading is a weighted mean of the tracked surfaces' heading
    affordances (or one of them), so its error is at most the largest of theirs (the hull),
    each of which is at most the sum of its two fits' bounds (``fit_direction_bounds``):
    the bound is the smaller of the two. Position: the chosen end pair's own errors
    (``end_position_bounds``, both observations) plus the heading error's lever on the end
    seen from the view, the largest over the tracked ends. Path integration is exact.
    """
    if len(pairs) != max(len(route) - 1, 0):
        raise ValueError(f"{len(pairs)} localisations recorded for {len(route)} local maps")
    if len(route) < 2:
        return []
    rows = _rows_of(np.asarray(frame_indices), np.array([lm.frame_index for lm in route]))
    truth = true_poses[rows]
    rel_true = between_arrays(truth[:-1], truth[1:])
    rel_est = route.relative_poses()[1:]
    err = between_arrays(rel_true, rel_est)
    out = []
    for k, (local, current) in enumerate(pairs):
        h_err = abs(float(wrap_angle(err[k, 2])))
        p_err = float(np.hypot(err[k, 0], err[k, 1]))
        if len(local) == 0:
            out.append(ZeroNoiseBound(h_err, _ZERO_NOISE_ATOL, p_err, _ZERO_NOISE_ATOL, 0.0, 0.0))
            continue
        diff = np.asarray(
            wrap_angle(segment_angles(local.segments) - segment_angles(current.segments)
                       - rel_true[k, 2])
        )  # fmt: skip
        flipped = np.abs(diff) > np.pi / 2
        eps = np.abs(np.where(flipped, wrap_angle(diff + np.pi), diff))
        fit = fit_direction_bounds(local, split_distance_m) + fit_direction_bounds(
            current, split_distance_m
        )
        hull, fit_max = float(eps.max()), float(fit.max())
        h_bound = min(hull, fit_max) + _ZERO_NOISE_ATOL
        g_l = end_position_bounds(local, resolution_rad, split_distance_m)
        g_c = end_position_bounds(current, resolution_rad, split_distance_m)
        ends_c = current.segments.reshape(-1, 2, 2)
        rng_c = np.hypot(ends_c[..., 0], ends_c[..., 1])
        # a flipped match pairs end 0 of one observation with end 1 of the other
        g_c = np.where(flipped[:, None], g_c[:, ::-1], g_c)
        rng_c = np.where(flipped[:, None], rng_c[:, ::-1], rng_c)
        p_bound = float((g_l + g_c + h_err * (rng_c + g_c)).max()) + _ZERO_NOISE_ATOL
        out.append(ZeroNoiseBound(h_err, h_bound, p_err, p_bound, hull, fit_max))
    return out


def check_zero_noise_localisation(
    route: RouteMap,
    frame_indices: NDArray[np.int64],
    true_poses: FloatArray,
    params: InvariantParams | None = None,
    *,
    localisations: LocalisationRecorder | None = None,
    split_distance_m: float | None = None,
) -> None:
    """With no noise, every local map is placed in its predecessor within its bound.

    Given the ``localisations`` (a ``LocalisationRecorder`` with the laser's resolution)
    each link has its own bound (``zero_noise_link_bounds``, with the extraction's
    ``split_distance_m``, default ``ExtractionParams``'s); without them, the fixed
    ``zero_noise_position_m`` / ``zero_noise_heading_deg`` of ``params``."""
    p = params or InvariantParams()
    if localisations is not None and localisations.resolution_rad is not None:
        if split_distance_m is None:
            from albot2d.perception import ExtractionParams

            split_distance_m = ExtractionParams().split_distance_m
        bounds = zero_noise_link_bounds(
            route, frame_indices, true_poses, localisations.pairs,
            localisations.resolution_rad, split_distance_m,
        )  # fmt: skip
        ratio = np.array(
            [max(b.heading_err_rad / b.heading_bound_rad, b.position_err_m / b.position_bound_m)
             for b in bounds]
        )  # fmt: skip
        if len(ratio) and ratio.max() > 1.0:
            k = int(np.argmax(ratio))
            b, lm = bounds[k], route[k + 1]
            fail(
                "zero_noise_localisation",
                f"{int((ratio > 1.0).sum())} of {len(ratio)} local maps beyond their bound; "
                f"worst map {lm.map_id} (frame {lm.frame_index}, {lm.method}, {lm.tracked} "
                f"tracked): {b.position_err_m:.3f} m (bound {b.position_bound_m:.3f}), "
                f"{math.degrees(b.heading_err_rad):.3f}° (bound "
                f"{math.degrees(b.heading_bound_rad):.3f}°: its surfaces' headings within "
                f"{math.degrees(b.hull_rad):.3f}°, their fits' bound "
                f"{math.degrees(b.fit_rad):.3f}°)",
            )
        return
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
