"""The ``heading_error_bound`` invariant: a mapper's heading error stays within what its own
localisation error model allows (the derivation is in ``docs/invariants.md``).

A view-based mapper places each local map in its predecessor by a *link*, and every
frame in between by path integration from its local map. Each link contributes its own
error, and errors of successive links add up as a random walk:

- a **triangulation** link takes its heading from the directions of the surfaces tracked
  from one view to the other (``albot2d.mapping.albot1.triangulation``). A surface's
  direction is a line fit of its ``n`` laser points over its length ``L``, with two
  independent errors. The laser's noise: per-point error ``σ_p`` across the line from
  its range noise, range resolution and angular jitter at the surface's range,
  ``σ_dir = σ_p √(12 / n) / L`` (``direction_sigma``). The laser's discrete sampling,
  which remains with exact ranges: a beam of the next face within extraction's split
  distance ``e`` of the line joins the fit at an end, at most ``δ_max = e / (1 - h)`` off
  the wall (``h`` the end beam's leverage), tilting it by ``g δ``,
  ``g = 6 (n-1) / (n (n+1) L)``; where the corner falls between two beams is uniform, so
  the offset is uniform over the beam spacing ``s = r Δφ`` at that end's range, and kept
  only within ``δ_max``: ``σ_disc² = g² Σ_ends min(s, δ_max)³ / (3 s)``
  (``discretisation_sigma``; ``n`` is the beams the laser's angular resolution ``Δφ`` puts
  on ``L`` at that range and incidence).
  A surface's heading is the difference of two such fits (``σ² = σ_local² +
  σ_current²``, each ``σ_dir² + σ_disc²``), and ``m`` of them are
  averaged with inverse-variance weights (``1/σ² = Σ 1/σ_i²``). The surfaces are those
  the mapper reports for the link (``used``: Albot1's ``on_localise`` hook, recorded by the
  fuzz episode and by ``ReferenceLinks``); given none, the bound takes the ``m`` *least*
  precise of the surfaces seen in both views (found here with the true relative pose) —
  ``m`` the link's recorded tracked count: no ``m``-subset does worse.
- a **path-integration** link has odometry's error over that link only: ``k`` standard
  deviations of its random heading error over the true motion of the link, plus its
  systematic part at full strength (``odometry_heading_envelope``).
- a frame between local maps adds odometry's error from its local map's view to it.

The bound at a frame is ``floor + k √(Σ var) + Σ systematic`` over its chain (the floor:
float rounding only). A mapper
that reports a route map (``ViewBasedMapper``) is held to its own links; any other mapper
that reports a trajectory has no links of its own to claim, and is held to the links a
view-based localiser (Albot1, run alongside on the same frames: ``ReferenceLinks``) finds
on that run: path integration only where the laser afforded no triangulation. Raw
odometry (``naive``) has odometry's error over the whole run and leaves the bound; a
mapper that corrects odometry by the laser stays inside it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from albot2d.errors import fail
from albot2d.frames import Frame
from albot2d.geometry import between_arrays, segment_angles, wrap_angle
from albot2d.mapping.albot1.mapper import Albot1, Localisation
from albot2d.mapping.albot1.route_map import RouteMap
from albot2d.perception.extraction import ExtractionParams
from albot2d.perception.surfaces import Surfaces
from albot2d.perception.tracking import TrackingParams, trackable_mask
from albot2d.sim.driving import DrivingProfile
from albot2d.sim.laser import LaserNoise
from albot2d.sim.odometry import OdometryNoise, heading_variance_rad2
from albot2d.validation import check_non_negative, check_positive

__all__ = [
    "HeadingBoundParams",
    "LinkErrors",
    "ReferenceLinks",
    "check_heading_error_bound",
    "common_surfaces",
    "direction_sigma",
    "discretisation_sigma",
    "heading_error_bound",
    "heading_errors",
    "link_errors",
    "link_heading_variance",
    "odometry_heading_envelope",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


@dataclass(frozen=True, slots=True)
class HeadingBoundParams:
    """The bound's constants (see the module docstring).

    - ``sigmas``: ``k``, standard deviations of the accumulated random error allowed: 4,
      so that a mapper whose link errors follow the model leaves the bound somewhere in a
      run of up to 1000 links with probability ≤ 0.5 % (a random walk against its own
      ``k √t`` boundary: 0.12 % at 50 links, 0.15 % at 200, 0.21 % at 1000; derivation
      in ``docs/invariants.md``).
    - ``floor_deg``: added everywhere: float rounding only (composing thousands of
      relative poses in float64 rounds a heading by ~1e-13 rad; 1e-6° is 1.7e-8 rad).
      Line extraction's own error with exact ranges is modelled, per surface
      (``discretisation_sigma``), not floored: the previous 1° floor stood in for it.
    - ``match_angle_deg`` / ``match_distance_m``: two surfaces of two views, placed by the
      true relative pose, are the same physical surface when their directions differ by
      less and the ends of the shorter lie this close to the other's line (RTSV's gates).
    """

    sigmas: float = 4.0
    floor_deg: float = 1e-6
    match_angle_deg: float = 5.0
    match_distance_m: float = 0.2

    def __post_init__(self) -> None:
        check_positive(self, "sigmas", "match_angle_deg", "match_distance_m")
        check_non_negative(self, "floor_deg")


class LinkErrors(NamedTuple):
    """Per local map ``j`` (row 0: the first map, zero): the heading variance (rad²) and
    systematic error (rad) of its link from map ``j - 1``, its row in the trace, and the
    link's method."""

    variance: FloatArray
    systematic: FloatArray
    rows: IntArray
    methods: tuple[str, ...]


def heading_errors(estimate: FloatArray, truth: FloatArray) -> FloatArray:
    """Absolute heading error (rad) of each pose relative to the run's first pose."""
    est = np.asarray(estimate)[:, 2] - estimate[0, 2]
    true = np.asarray(truth)[:, 2] - truth[0, 2]
    return np.abs(np.asarray(wrap_angle(est - true)))


# -- odometry over a stretch ----------------------------------------------------------------
def odometry_heading_envelope(
    true_poses: FloatArray, noise: OdometryNoise, profile: DrivingProfile
) -> tuple[FloatArray, FloatArray]:
    """Prefix sums over the trace rows of odometry's heading error: ``(variance, systematic)``
    (each ``(F,)``, 0 at row 0), so a stretch from row ``a`` to row ``b`` has variance
    ``var[b] - var[a]`` and systematic error ``sys[b] - sys[a]``.

    Per row increment (true motion ``d`` metres, turn ``φ``): the random part of the
    odometry model, a random walk along the motion (variance α1² per radian turned plus
    α2² per metre driven: ``albot2d.sim.odometry.heading_variance_rad2``), and the
    systematic part at full strength (turn scale error × φ, drift × d, the induced error ×
    turn steps of the driving profile)."""
    poses = np.asarray(true_poses, dtype=np.float64)
    inc = between_arrays(poses[:-1], poses[1:]) if len(poses) > 1 else np.zeros((0, 3))
    dist = np.hypot(inc[:, 0], inc[:, 1])
    turn = np.abs(np.asarray(wrap_angle(inc[:, 2])))
    var = heading_variance_rad2(noise, dist, turn)
    turn_steps = np.ceil(turn / math.radians(profile.turn_step_deg) - 1e-9)
    induced_rad = math.radians(abs(noise.induced_step_deg) + abs(profile.induced_step_deg))
    systematic = (
        abs(noise.turn_scale_error) * turn
        + math.radians(abs(noise.heading_drift_deg_per_m)) * dist
        + induced_rad * turn_steps
    )
    zero = np.zeros(1)
    return np.concatenate([zero, np.cumsum(var)]), np.concatenate([zero, np.cumsum(systematic)])


# -- triangulation from the laser -----------------------------------------------------------
def direction_sigma(surfaces: Surfaces, laser: LaserNoise) -> FloatArray:
    """``(N,)``: the standard deviation (rad) of each surface's fitted direction.

    A least-squares line through ``n`` points spread evenly over length ``L``, each off
    the line by ``σ_p``, has a direction error ``σ_p √(12 / (n (n+1)/(n-1))) / L`` ≈
    ``σ_p √(12/n) / L``. ``σ_p`` is taken at the surface's farther end ``r``: the range
    sigma ``σ_r + σ_per_m r``, the range quantisation ``resolution / √12`` and the angular
    jitter's lateral offset ``r σ_α``, all as if across the line (the worst incidence)."""
    segs = surfaces.segments
    beams = surfaces.beams
    n = np.where(beams[:, 0] >= 0, beams[:, 1] - beams[:, 0] + 1, 2).astype(np.float64)
    n = np.maximum(n, 2.0)
    r = np.maximum(np.hypot(segs[:, 0], segs[:, 1]), np.hypot(segs[:, 2], segs[:, 3]))
    sigma_p = np.sqrt(
        (laser.range_sigma_m + laser.range_sigma_per_m * r) ** 2
        + laser.range_resolution_m**2 / 12.0
        + (r * math.radians(laser.angle_jitter_deg)) ** 2
    )
    spread = n * (n + 1.0) / (n - 1.0)
    length = np.maximum(surfaces.lengths_m, 1e-9)
    return sigma_p * np.sqrt(12.0 / spread) / length


# Both ends of a surface may carry a beam of another face (``discretisation_sigma``).
_ENDS = 2


def _end_leverage(n: FloatArray) -> FloatArray:
    """The leverage of an end beam in a least-squares line through ``n`` evenly spread
    beams: ``1/n + (L/2)² / S_xx`` with ``S_xx = L² n (n+1) / (12 (n-1))``."""
    return 1.0 / n + 3.0 * (n - 1.0) / (n * (n + 1.0))


def discretisation_sigma(surfaces: Surfaces, split_distance_m: float) -> FloatArray:
    """``(N,)``: the standard deviation (rad) of each surface's fitted direction from the
    laser's discrete sampling alone, with exact ranges (derivation in ``docs/invariants.md``).

    With exact ranges every beam of the surface's own wall lies on its line; a fit errs
    only when a beam of another face joins it at an end: the split beam at a corner (it
    belongs to both halves) or the next face's first beams, or at a run's end a piece too
    short to stand alone (fewer than ``min_points`` beams) grown back into the surface.
    Extraction keeps such a beam while its residual from the fitted line is at most the
    split distance ``e``. Alone among ``n`` beams spread evenly over length ``L`` (the
    laser's angular resolution, the range and the incidence set ``n`` for a given ``L``),
    a beam at offset ``δ`` at an end has residual ``δ (1 - h)``, ``h`` its leverage
    (``_end_leverage``), and tilts the line by ``g δ``, ``g = 6 (n-1) / (n (n+1) L)``; so
    ``δ ≤ δ_max = e / (1 - h)``. Where a corner falls between two beams is uniform, so the
    offset of the first beam past it is uniform over the beam spacing ``s``: taken as the
    arc between two beams at that end's range, ``s = r Δφ``, with the laser's angle between
    beams ``Δφ`` read from the surface itself (the bearings of its end beams over its
    ``n - 1`` steps). Kept only when within ``δ_max``, its second moment is
    ``E[δ²] = min(s, δ_max)³ / (3 s)``. A stray is assumed at both ends, whichever kind of
    end (the view need not show the neighbouring face): ``σ² = g² (E[δ²]_0 + E[δ²]_1)``.
    Surfaces not from a scan (no beams): 0; fewer than three beams: a
    line through two beams fits any stray, so ``inf``."""
    beams = surfaces.beams
    from_scan = beams[:, 0] >= 0
    n = np.where(from_scan, beams[:, 1] - beams[:, 0] + 1, 3).astype(np.float64)
    fits = n >= 3.0
    n = np.maximum(n, 3.0)
    length = np.maximum(surfaces.lengths_m, 1e-9)
    offset = split_distance_m / (1.0 - _end_leverage(n))
    gain = 6.0 * (n - 1.0) / (n * (n + 1.0) * length)
    # The laser's angle between beams, from the bearings of the surface's end beams.
    ends = surfaces.segments.reshape(-1, 2, 2)
    bearing = np.arctan2(ends[..., 1], ends[..., 0])
    step = np.abs(np.asarray(wrap_angle(bearing[:, 1] - bearing[:, 0]))) / (n - 1.0)
    spacing = np.hypot(ends[..., 0], ends[..., 1]) * step[:, None]  # (N, 2): r Δφ per end
    spacing = np.maximum(spacing, 1e-12)
    kept = np.minimum(spacing, offset[:, None])
    second_moment = (kept**3 / (3.0 * spacing)).sum(axis=1)
    sigma = gain * np.sqrt(second_moment)
    return np.where(from_scan, np.where(fits, sigma, np.inf), 0.0)


def common_surfaces(
    earlier: Surfaces,
    later: Surfaces,
    relative_pose: FloatArray,
    params: HeadingBoundParams | None = None,
) -> tuple[IntArray, IntArray]:
    """Pairs ``(i, j)``: surface ``i`` of ``earlier`` and ``j`` of ``later`` are the same
    physical surface, judged with ``relative_pose`` (the later view's pose in the earlier
    one's frame, the true one in the invariant): their undirected directions differ by less
    than ``match_angle_deg`` and both ends of the shorter lie within ``match_distance_m`` of
    the other's line, with their extents along it overlapping. Each ``j`` is paired with
    its nearest match (by the mean end distance) only."""
    p = params or HeadingBoundParams()
    a = earlier.segments
    if len(a) == 0 or len(later) == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    x, y, th = (float(v) for v in relative_pose)
    c, s = math.cos(th), math.sin(th)
    b = later.segments
    bx = np.column_stack(
        [x + c * b[:, 0] - s * b[:, 1], y + s * b[:, 0] + c * b[:, 1],
         x + c * b[:, 2] - s * b[:, 3], y + s * b[:, 2] + c * b[:, 3]]
    )  # fmt: skip
    da = segment_angles(a)[:, None]
    db = segment_angles(bx)[None, :]
    diff = np.abs(np.asarray(wrap_angle(2.0 * (da - db)))) / 2.0  # undirected
    close = diff < math.radians(p.match_angle_deg)
    # distances of b's ends to a's lines, and a's ends to b's lines
    dist_ba, along_ba = _to_lines(a, bx)  # (Na, Nb, 2)
    dist_ab, _ = _to_lines(bx, a)
    la = np.hypot(a[:, 2] - a[:, 0], a[:, 3] - a[:, 1])[:, None]
    lb = np.hypot(bx[:, 2] - bx[:, 0], bx[:, 3] - bx[:, 1])[None, :]
    shorter_b = lb <= la
    off = np.where(shorter_b, dist_ba.max(axis=2), dist_ab.transpose(1, 0, 2).max(axis=2))
    overlap = (along_ba.max(axis=2) > 0.0) & (along_ba.min(axis=2) < la)
    ok = close & (off < p.match_distance_m) & overlap
    mean_off = np.where(ok, off, np.inf)
    j = np.flatnonzero(ok.any(axis=0))
    i = np.argmin(mean_off[:, j], axis=0)
    return i.astype(np.int64), j.astype(np.int64)


def _to_lines(lines: FloatArray, pts_segs: FloatArray) -> tuple[FloatArray, FloatArray]:
    """``(Nl, Np, 2)`` perpendicular distances of each segment's two ends to each line,
    and their coordinates along it (0 at the line's first end)."""
    p0 = lines[:, None, None, :2]
    d = lines[:, 2:] - lines[:, :2]
    length = np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-12)
    u = (d / length[:, None])[:, None, None, :]
    ends = pts_segs.reshape(-1, 2, 2)[None, :, :, :]
    rel = ends - p0
    along = (rel * u).sum(axis=3)
    across = np.abs(rel[..., 0] * u[..., 1] - rel[..., 1] * u[..., 0])
    return across, along


def _triangulation_variance(
    earlier: Surfaces,
    later: Surfaces,
    relative_pose: FloatArray,
    used: int,
    laser: LaserNoise,
    tracking: TrackingParams,
    params: HeadingBoundParams,
    split_distance_m: float,
) -> float:
    """The heading variance of a triangulation link that used ``used`` surfaces: the
    inverse-variance mean of the ``used`` least precise trackable surfaces seen in both
    views (every surface of the later view, when none is found in both: the link's
    heading then rests on surfaces the views do not share)."""
    ta = np.flatnonzero(trackable_mask(earlier, tracking))
    tb = np.flatnonzero(trackable_mask(later, tracking))
    sa = np.hypot(direction_sigma(earlier, laser), discretisation_sigma(earlier, split_distance_m))
    sb = np.hypot(direction_sigma(later, laser), discretisation_sigma(later, split_distance_m))
    i, j = common_surfaces(earlier.select(ta), later.select(tb), relative_pose, params)
    if len(i):
        var = sa[ta[i]] ** 2 + sb[tb[j]] ** 2
    else:
        pool = tb if len(tb) else np.arange(len(later))
        if len(pool) == 0:
            return math.inf
        var = 2.0 * sb[pool] ** 2
    worst = np.sort(var)[::-1][: max(1, min(int(used), len(var)))]
    worst = np.maximum(worst, 1e-30)
    with np.errstate(divide="ignore"):  # every surface unbounded (inf): so is the link
        return float(1.0 / np.sum(1.0 / worst))


def link_heading_variance(
    local: Surfaces, current: Surfaces, laser: LaserNoise, split_distance_m: float
) -> float:
    """The heading variance (rad²) of a link triangulated from the surface pairs it reported
    (``local[i]`` in the local map, ``current[i]`` in the view): each pair's heading is the
    difference of its two fits (the laser's noise and its discrete sampling in each), the
    pairs averaged with inverse-variance weights."""
    split = split_distance_m
    var = (
        direction_sigma(local, laser) ** 2 + discretisation_sigma(local, split) ** 2
        + direction_sigma(current, laser) ** 2 + discretisation_sigma(current, split) ** 2
    )  # fmt: skip
    var = np.maximum(var, 1e-30)
    with np.errstate(divide="ignore"):
        return float(1.0 / np.sum(1.0 / var))


def _rows_of(frame_indices: IntArray, wanted: IntArray) -> IntArray:
    order = np.argsort(frame_indices, kind="stable")
    pos = np.searchsorted(frame_indices[order], wanted)
    return order[np.clip(pos, 0, len(order) - 1)]


def link_errors(
    route: RouteMap,
    frame_indices: IntArray,
    true_poses: FloatArray,
    odometry: tuple[FloatArray, FloatArray],
    laser: LaserNoise,
    tracking: TrackingParams | None = None,
    params: HeadingBoundParams | None = None,
    extraction: ExtractionParams | None = None,
    used: Sequence[tuple[Surfaces, Surfaces]] | None = None,
) -> LinkErrors:
    """Each local map's link error from the error model (module docstring).
    ``odometry``: ``odometry_heading_envelope``'s prefix sums over the same rows; ``used``:
    per local map after the first, the surface pairs (local map, view) the mapper
    reported localising it from (``Albot1.on_localise``); without them (or when they do
    not match the route), the least precise of the surfaces both views share."""
    p = params or HeadingBoundParams()
    tracking = tracking or TrackingParams()
    split = (extraction or ExtractionParams()).split_distance_m
    var_odo, sys_odo = odometry
    n = len(route)
    rows = _rows_of(np.asarray(frame_indices), np.array([lm.frame_index for lm in route], np.int64))
    var = np.zeros(n)
    sys = np.zeros(n)
    truth = np.asarray(true_poses, dtype=np.float64)
    if used is not None and len(used) != max(n - 1, 0):
        used = None
    for k in range(1, n):
        lm, prev = route[k], route[k - 1]
        a, b = int(rows[k - 1]), int(rows[k])
        if lm.method == "triangulation" and used is not None and len(used[k - 1][0]):
            var[k] = link_heading_variance(*used[k - 1], laser, split)
        elif lm.method == "triangulation":
            rel = between_arrays(truth[a], truth[b])
            var[k] = _triangulation_variance(
                prev.view, lm.view, rel, max(lm.tracked, 1), laser, tracking, p, split
            )
        else:  # path integration (or anything else): odometry over this link only
            var[k] = var_odo[b] - var_odo[a]
            sys[k] = sys_odo[b] - sys_odo[a]
    return LinkErrors(var, sys, rows.astype(np.int64), tuple(lm.method for lm in route))


def heading_error_bound(
    route: RouteMap,
    frame_indices: IntArray,
    true_poses: FloatArray,
    noise: OdometryNoise,
    profile: DrivingProfile,
    laser: LaserNoise,
    tracking: TrackingParams | None = None,
    params: HeadingBoundParams | None = None,
    extraction: ExtractionParams | None = None,
    used: Sequence[tuple[Surfaces, Surfaces]] | None = None,
) -> FloatArray:
    """The largest heading error (rad, relative to the start) the model allows at each row
    of a run whose frames are placed on ``route`` (module docstring)."""
    p = params or HeadingBoundParams()
    frame_indices = np.asarray(frame_indices, dtype=np.int64)
    odo = odometry_heading_envelope(true_poses, noise, profile)
    links = link_errors(route, frame_indices, true_poses, odo, laser, tracking, p, extraction, used)
    var_chain = np.cumsum(links.variance)
    sys_chain = np.cumsum(links.systematic)
    # Each row's local map: the last one remembered at or before its frame.
    made = np.array([lm.frame_index for lm in route], dtype=np.int64)
    k = np.clip(np.searchsorted(made, frame_indices, side="right") - 1, 0, max(len(made) - 1, 0))
    if len(made) == 0:
        anchor = np.zeros(len(frame_indices), np.int64)
        var = odo[0] - odo[0][0]
        sys = odo[1] - odo[1][0]
    else:
        anchor = links.rows[k]
        rows = np.arange(len(frame_indices))
        after = np.maximum(rows, anchor)  # a row before the first map: from the start
        var = var_chain[k] + odo[0][after] - odo[0][anchor]
        sys = sys_chain[k] + odo[1][after] - odo[1][anchor]
    return math.radians(p.floor_deg) + p.sigmas * np.sqrt(var) + sys


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


class ReferenceLinks:
    """An ``on_frame``-style hook running Albot1 (default parameters) on the same frames,
    so a mapper without a route map of its own is held to the links a view-based
    localiser finds on that run (``route``) and the surfaces it localised each from
    (``used``)."""

    def __init__(self, mapper: Albot1 | None = None) -> None:
        self.mapper = mapper if mapper is not None else Albot1()
        self.used: list[tuple[Surfaces, Surfaces]] = []
        self._chained = self.mapper.on_localise
        self.mapper.on_localise = self._localised

    def _localised(self, localisation: Localisation) -> None:
        """The surface pairs each local map was localised from (``used``), then any hook
        the mapper already had."""
        self.used.append((localisation.tracked.local, localisation.tracked.current))
        if self._chained is not None:
            self._chained(localisation)

    def __call__(self, frame: Frame, travelled_m: float = 0.0) -> None:
        self.mapper.observe(frame)

    @property
    def route(self) -> RouteMap:
        return self.mapper.route
