"""Trackable surfaces and Albot1's algorithm #1, RTSV: recognising tracked surfaces in a view.

Trackable (the paper's three criteria, ``TrackingParams``): longer than 40 cm, seen under a
viewing angle (between the bearings of its two endpoints from the robot) of at least 3°,
and with at least one unoccluded endpoint.

RTSV: each tracked surface's latest observation is moved onto the new view by the inverse
of the odometry increment (the full relative pose ``prev⁻¹ ⊕ current``) and recognised as
a trackable surface of the new view when their undirected line directions differ by less
than 5° and, over corresponding endpoints (scan order) unoccluded in both, the nearest pair
is closer than 40 cm. Matching is one-to-one, greedy by that distance (the pseudocode would
allow many-to-many matches). A pair with no endpoint unoccluded in both observations is not
recognised: the paper compares "occluding points", i.e. real corners, and an occluded end
says nothing about where a surface ends. ``TrackingParams.line_distance_fallback`` instead
compares such pairs by the distance of each unoccluded endpoint to the other segment.

Unlike the pseudocode, which replaces S_t by the matched surfaces of the view, the tracker
state (``TrackedSurfaces``) keeps each surface's geometry in the local map too: triangulation
needs both observations.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from albot2d.arrays import readonly
from albot2d.compiled import compiled_kernel
from albot2d.errors import InputError
from albot2d.geometry import (
    Pose,
    point_segment_distance,
    segment_angles,
    undirected_angle_difference,
)
from albot2d.perception.surfaces import Surfaces
from albot2d.validation import check_in_range, check_non_negative, check_positive

__all__ = [
    "MATCH_BACKENDS",
    "MatchInfo",
    "TrackedSurfaces",
    "TrackingParams",
    "key_endpoints",
    "match_fitness",
    "match_surfaces",
    "recognise",
    "rtsv",
    "start_tracking",
    "trackable_mask",
    "view_angles_rad",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]


@dataclass(frozen=True, slots=True)
class TrackingParams:
    """Trackable-surface criteria and RTSV gates; defaults are the paper's values.

    - ``min_length_m``: a trackable surface is strictly longer.
    - ``min_view_angle_deg``: least angle between the bearings of its endpoints.
    - ``match_angle_deg``: recognised only if undirected directions differ by less.
    - ``match_distance_m``: recognised only if corresponding unoccluded endpoints are closer.
    - ``line_distance_fallback``: pairs without an endpoint unoccluded in both views are
      compared by endpoint-to-segment distance instead of being rejected (off: the paper's
      "distance between occluding points" needs a shared real corner).
    - ``match_endpoint``: ``"corresponding"`` (the nearest pair of corresponding endpoints
      unoccluded in both) or ``"key"`` (the authors' code: only the tracked surface's key
      endpoint — its real one, the nearer if both are real — against the candidate's same
      endpoint, whether or not that one is real).
    - ``match_order``: resolve conflicts greedily by smallest ``"distance"`` or by highest
      ``"fitness"`` (the authors' code: length_mm · (400 − d_mm) · (5 − Δθ_deg) /
      max(range_mm, 2000), see ``match_fitness``).
    - ``fitness_floor``: when the best match's fitness is below this, no surface counts as
      tracked (the authors' code: 80, forcing an update); 0 disables it.
    - ``match_candidates``: which surfaces of the new view a tracked surface may be
      recognised as: ``"trackable"`` (the paper: Appendix 1 defines V_c for RTSV as the
      view's surfaces "that satisfy the above three criteria (i.e. those that don't, have
      been removed)"; the authors' code matches against the view's target objects too) or
      ``"all"``, an ablation that is *not* a reading of the paper: every surface of the
      view, e.g. a wall now seen edge-on (under 3°) or shortened below 40 cm by an
      occluder, so a tracked surface is not lost only because its new observation fails a
      criterion ("some of the tracked surfaces could be missed … Albot₁ will lose track of
      these surfaces earlier than expected", the paper says of its RTSV). A local map
      still starts tracking only its trackable surfaces.
    """

    min_length_m: float = 0.40
    min_view_angle_deg: float = 3.0
    match_angle_deg: float = 5.0
    match_distance_m: float = 0.40
    line_distance_fallback: bool = False
    match_endpoint: Literal["corresponding", "key"] = "corresponding"
    match_order: Literal["distance", "fitness"] = "distance"
    fitness_floor: float = 0.0
    match_candidates: Literal["trackable", "all"] = "trackable"

    def __post_init__(self) -> None:
        check_non_negative(self, "min_length_m", "fitness_floor")
        if self.match_endpoint not in ("corresponding", "key"):
            raise InputError(
                "TrackingParams.match_endpoint must be corresponding or key, "
                f"got {self.match_endpoint!r}"
            )
        if self.match_order not in ("distance", "fitness"):
            raise InputError(
                f"TrackingParams.match_order must be distance or fitness, got {self.match_order!r}"
            )
        if self.match_candidates not in ("trackable", "all"):
            raise InputError(
                "TrackingParams.match_candidates must be trackable or all, "
                f"got {self.match_candidates!r}"
            )
        check_in_range(self, "min_view_angle_deg", 0.0, 180.0)
        check_in_range(self, "match_angle_deg", 0.0, 90.0)
        check_positive(self, "match_angle_deg", "match_distance_m")
        if not isinstance(self.line_distance_fallback, bool):
            raise InputError(
                "TrackingParams.line_distance_fallback must be true or false, "
                f"got {self.line_distance_fallback!r}"
            )


def view_angles_rad(surfaces: Surfaces) -> FloatArray:
    """Angle (radians, in [0, pi]) between the bearings of each surface's two endpoints,
    seen from the origin of the surfaces' frame (the robot)."""
    s = surfaces.segments
    cross = s[:, 0] * s[:, 3] - s[:, 1] * s[:, 2]
    dot = s[:, 0] * s[:, 2] + s[:, 1] * s[:, 3]
    return np.arctan2(np.abs(cross), dot)


def trackable_mask(surfaces: Surfaces, params: TrackingParams | None = None) -> BoolArray:
    """``(N,)`` bool, read-only: the surface meets all three of the paper's tracking criteria."""
    if params is None:
        params = TrackingParams()
    # A view is tested again with the same parameters when it is re-tracked or becomes the
    # local map (most updates): the read-only answer is kept with the (immutable) view.
    memo = surfaces.__dict__.get("_trackable")
    if memo is not None and memo[0] is params:
        return memo[1]
    mask = (
        (surfaces.lengths_m > params.min_length_m)
        & (view_angles_rad(surfaces) >= math.radians(params.min_view_angle_deg))
        & ~surfaces.occluded.all(axis=1)
    )
    mask.flags.writeable = False
    object.__setattr__(surfaces, "_trackable", (params, mask))
    return mask


def _readonly_ids(ids: ArrayLike) -> IntArray:
    return readonly(ids, np.int64, (-1,))


@dataclass(frozen=True, eq=False)
class TrackedSurfaces:
    """The tracker state: K surfaces of the current local map still in view.

    - ``ids``: ``(K,)`` identity of each surface, stable across views.
    - ``local``: its geometry in the current local map's frame, as observed when that
      local map was remembered (what triangulation compares against).
    - ``current``: its latest observation, in the latest view's frame.
    """

    ids: IntArray
    local: Surfaces
    current: Surfaces

    def __post_init__(self) -> None:
        ids = _readonly_ids(self.ids)
        if not len(ids) == len(self.local) == len(self.current):
            raise ValueError(
                f"TrackedSurfaces needs one id per surface: {len(ids)} ids, "
                f"{len(self.local)} local, {len(self.current)} current"
            )
        if len(np.unique(ids)) != len(ids):
            raise ValueError(f"TrackedSurfaces ids must be unique, got {ids.tolist()}")
        object.__setattr__(self, "ids", ids)

    @classmethod
    def empty(cls) -> TrackedSurfaces:
        return cls(np.zeros(0, np.int64), Surfaces.empty(), Surfaces.empty())

    def __len__(self) -> int:
        return len(self.ids)

    @property
    def next_id(self) -> int:
        """One past the largest id (0 when empty): a fresh id for new tracks."""
        return int(self.ids.max()) + 1 if len(self.ids) else 0

    def select(self, index: ArrayLike) -> TrackedSurfaces:
        """A subset by boolean mask or integer indices (order of ``index`` kept)."""
        idx = np.asarray(index)
        return TrackedSurfaces(self.ids[idx], self.local.select(idx), self.current.select(idx))


def start_tracking(
    view: Surfaces, params: TrackingParams | None = None, first_id: int = 0
) -> TrackedSurfaces:
    """Track the trackable surfaces of a view that becomes the local map.

    Ids are ``first_id, first_id + 1, …`` in scan order; ``local`` and ``current`` are both
    that view's observations.
    """
    chosen = view.select(trackable_mask(view, params))
    ids = np.arange(first_id, first_id + len(chosen), dtype=np.int64)
    # Fresh, distinct ids, one per surface: TrackedSurfaces' checks hold by construction.
    ids.flags.writeable = False
    state = object.__new__(TrackedSurfaces)
    for name, value in (("ids", ids), ("local", chosen), ("current", chosen)):
        object.__setattr__(state, name, value)
    return state


@dataclass(frozen=True, eq=False)
class MatchInfo:
    """What one RTSV step recognised.

    - ``tracked_index``: ``(M,)`` indices into the tracked set before the step, ascending.
    - ``view_index``: ``(M,)`` indices into the new view's surfaces.
    - ``distance_m``, ``angle_rad``: the matched pairs' endpoint distance and direction gap.
    - ``predicted``: every tracked surface's prediction in the new view's frame.
    - ``candidates``: ``(N,)`` bool over the new view, the trackable surfaces considered.
    """

    tracked_index: IntArray
    view_index: IntArray
    distance_m: FloatArray
    angle_rad: FloatArray
    predicted: Surfaces
    candidates: BoolArray

    def __len__(self) -> int:
        return len(self.tracked_index)


def key_endpoints(surfaces: Surfaces) -> IntArray:
    """``(K,)`` index (0/1) of each surface's key endpoint: its real (unoccluded) end, the
    nearer to the robot if both are real (or both occluded)."""
    pts = surfaces.segments.reshape(-1, 2, 2)
    rng = np.hypot(pts[..., 0], pts[..., 1])
    score = np.where(surfaces.occluded, rng + 1e9, rng)
    return np.argmin(score, axis=1).astype(np.int64)


def match_fitness(
    predicted: Surfaces, view: Surfaces, distance_m: FloatArray, angle_rad: FloatArray
) -> FloatArray:
    """The authors' match fitness for pairs broadcast as ``distance_m``/``angle_rad``:
    length_mm · (400 − d_mm) · (5 − Δθ_deg) / max(range_mm, 2000) (code units: mm, degrees;
    length and range of the view's surface)."""
    seg = view.segments
    length_mm = 1000.0 * view.lengths_m
    mid = 0.5 * (seg[:, :2] + seg[:, 2:])
    range_mm = 1000.0 * np.hypot(mid[:, 0], mid[:, 1])
    return (
        length_mm
        * (400.0 - 1000.0 * distance_m)
        * (5.0 - np.degrees(angle_rad))
        / np.maximum(range_mm, 2000.0)
    )


def _endpoint_distances(
    predicted: Surfaces, view: Surfaces, fallback: bool, mode: str = "corresponding"
) -> FloatArray:
    """``(K, N)`` distance between corresponding endpoints unoccluded in both (inf if none),
    or (``mode="key"``) between each predicted surface's key endpoint and the same end."""
    p = predicted.segments.reshape(-1, 1, 2, 2)
    v = view.segments.reshape(1, -1, 2, 2)
    d = np.hypot(p[..., 0] - v[..., 0], p[..., 1] - v[..., 1])  # (K, N, 2)
    if mode == "key":
        key = key_endpoints(predicted)
        return np.take_along_axis(d, key[:, None, None], axis=2)[..., 0]
    shared = ~predicted.occluded[:, None, :] & ~view.occluded[None, :, :]
    dist = np.where(shared, d, np.inf).min(axis=2)
    if fallback:
        # Unoccluded endpoints of each side against the other side's whole segment.
        k, n = len(predicted), len(view)
        p_to_v = point_segment_distance(predicted.segments.reshape(-1, 2), view.segments)
        p_to_v = np.where(predicted.occluded.reshape(-1, 1), np.inf, p_to_v)
        p_to_v = p_to_v.reshape(k, 2, n).min(axis=1)
        v_to_p = point_segment_distance(view.segments.reshape(-1, 2), predicted.segments)
        v_to_p = np.where(view.occluded.reshape(-1, 1), np.inf, v_to_p)
        v_to_p = v_to_p.reshape(n, 2, k).min(axis=1).T
        dist = np.where(shared.any(axis=2), dist, np.minimum(p_to_v, v_to_p))
    return dist


#: ``match_surfaces(backend=...)``: "auto" takes the compiled matching when numba imports
#: and the settings are the ones it covers (``_compiled_settings``).
MATCH_BACKENDS = ("auto", "numpy", "numba")


def _compiled_match() -> Callable[..., tuple[Any, ...]] | None:
    """The compiled matching kernel, loaded on first use (None when the kernels are off)."""
    return compiled_kernel("albot2d.perception.tracking_numba", "match_kernel")


def _directions(view: Surfaces) -> FloatArray:
    """The view's segment directions (numpy's arctan2, as ``segment_angles``), kept with the
    (immutable) view: a view re-tracked after an update is matched twice."""
    got = view.__dict__.get("_directions")
    if got is None:
        v = view.segments
        got = np.arctan2(v[:, 3] - v[:, 1], v[:, 2] - v[:, 0])
        got.flags.writeable = False
        object.__setattr__(view, "_directions", got)
    return got


def _compiled_settings(params: TrackingParams) -> bool:
    """Whether the compiled kernel covers ``params`` (the paper's matching)."""
    return (params.match_endpoint == "corresponding" and not params.line_distance_fallback
            and params.match_order == "distance" and params.fitness_floor <= 0)  # fmt: skip


def _match_compiled(
    kernel: Callable[..., tuple[Any, ...]],
    predicted: Surfaces,
    view: Surfaces,
    params: TrackingParams,
    cand: BoolArray,
) -> tuple[Any, ...]:
    """The compiled matcher on checked arguments: ``(tracked, view, distance, angle)``."""
    p = predicted.segments
    return kernel(
        p, predicted.occluded, view.segments, view.occluded, cand,
        np.arctan2(p[:, 3] - p[:, 1], p[:, 2] - p[:, 0]), _directions(view),
        math.radians(params.match_angle_deg), params.match_distance_m,
    )  # fmt: skip


def match_surfaces(
    predicted: Surfaces,
    view: Surfaces,
    params: TrackingParams | None = None,
    candidates: ArrayLike | None = None,
    *,
    backend: str = "auto",
) -> tuple[IntArray, IntArray, FloatArray, FloatArray]:
    """One-to-one greedy matching of ``predicted`` to ``view`` surfaces (same frame).

    Only ``view`` surfaces in ``candidates`` (bool mask; default all) may match. Returns
    ``(predicted_index, view_index, distance_m, angle_rad)`` sorted by predicted index.
    Ties in distance go to the lower predicted, then lower view index. ``backend``:
    "numpy", "numba" (the paper's settings only) or "auto" (numba
    when it imports and covers the settings); both give the same matches.
    """
    params = TrackingParams() if params is None else params
    if backend not in MATCH_BACKENDS:
        raise ValueError(f"backend must be one of {MATCH_BACKENDS}, got {backend!r}")
    cand = np.ones(len(view), bool) if candidates is None else np.asarray(candidates, bool)
    if cand.shape != (len(view),):
        raise ValueError(f"candidates must have shape ({len(view)},), got {cand.shape}")
    empty_i = np.zeros(0, np.int64)
    if not len(predicted) or not cand.any():
        return empty_i, empty_i.copy(), np.zeros(0), np.zeros(0)
    if backend != "numpy":
        kernel = _compiled_match() if _compiled_settings(params) else None
        if kernel is not None:
            return _match_compiled(kernel, predicted, view, params, cand)
        if backend == "numba":
            raise ValueError(
                "backend='numba' needs numba (off under ALBOT2D_KERNELS=numpy) and the paper's "
                "matching settings (corresponding, distance, no fallback/floor)"
            )
    angle = undirected_angle_difference(
        segment_angles(predicted.segments)[:, None], segment_angles(view.segments)[None, :]
    )
    dist = _endpoint_distances(
        predicted, view, params.line_distance_fallback, params.match_endpoint
    )
    ok = (
        cand[None, :]
        & (angle < math.radians(params.match_angle_deg))
        & (dist < params.match_distance_m)
    )
    pi, vj = np.nonzero(ok)
    if params.match_order == "fitness" or params.fitness_floor > 0:
        fitness = match_fitness(predicted, view, dist, angle)[pi, vj] if len(pi) else np.zeros(0)
        if params.fitness_floor > 0 and (not len(pi) or fitness.max() < params.fitness_floor):
            return empty_i, empty_i.copy(), np.zeros(0), np.zeros(0)
    if params.match_order == "fitness":
        order = np.lexsort((vj, pi, -fitness))
    else:
        order = np.lexsort((vj, pi, dist[pi, vj]))
    used_p = np.zeros(len(predicted), bool)
    used_v = np.zeros(len(view), bool)
    chosen: list[int] = []
    for o in order:
        i, j = pi[o], vj[o]
        if not (used_p[i] or used_v[j]):
            used_p[i] = used_v[j] = True
            chosen.append(int(o))
    sel = np.asarray(chosen, np.int64)
    sel = sel[np.argsort(pi[sel], kind="stable")]
    mi, mj = pi[sel].astype(np.int64), vj[sel].astype(np.int64)
    return mi, mj, dist[mi, mj], angle[mi, mj]


def recognise(
    current: Surfaces,
    view: Surfaces,
    increment: Pose,
    params: TrackingParams | None = None,
    *,
    candidates: ArrayLike | None = None,
) -> MatchInfo:
    """Algorithm #1's recognition step alone: which of the tracked surfaces' latest
    observations ``current`` (previous view's frame) are recognised in ``view`` after the
    odometry ``increment``. ``rtsv`` is this plus the tracker's bookkeeping (ids, local
    geometry); a replay that only counts (``evaluation.invariants.recount_tracking``)
    keeps ``view.select(info.view_index)`` as the next ``current``."""
    params = TrackingParams() if params is None else params
    cand = trackable_mask(view, params) if candidates is None else np.asarray(candidates, bool)
    if cand.shape != (len(view),):
        raise ValueError(f"candidates must have shape ({len(view)},), got {cand.shape}")
    if candidates is None and params.match_candidates == "all":  # algorithm #1 as printed
        cand = np.ones(len(view), bool)
    predicted = current.transformed(increment.inverse())
    kernel = _compiled_match() if _compiled_settings(params) else None
    if kernel is not None:
        # ``match_surfaces``' compiled path without its argument checks (done above):
        # recognition runs two or three times per view (the mapper and the checks).
        ti, vj, dist, angle = _match_compiled(kernel, predicted, view, params, cand)
    else:
        ti, vj, dist, angle = match_surfaces(predicted, view, params, cand)
    return MatchInfo(ti, vj, dist, angle, predicted, cand)


def rtsv(
    tracked: TrackedSurfaces,
    view: Surfaces,
    increment: Pose,
    params: TrackingParams | None = None,
    *,
    candidates: ArrayLike | None = None,
) -> tuple[TrackedSurfaces, MatchInfo]:
    """Algorithm #1: which tracked surfaces are still in the new ``view``.

    ``increment`` is the odometry motion from the previous view to this one
    (``prev⁻¹ ⊕ current``, in the previous view's frame). ``candidates`` (bool over
    ``view``) overrides which view surfaces may match; by default the trackable ones
    (every one with the ``TrackingParams.match_candidates="all"`` ablation).
    Survivors keep their ``ids`` and ``local`` geometry; ``current`` becomes the matched
    observation in ``view``.
    """
    info = recognise(tracked.current, view, increment, params, candidates=candidates)
    ti = info.tracked_index
    # ti are distinct indices into a valid tracker state: its invariants hold by
    # construction, so the survivors skip TrackedSurfaces' checks (a third of RTSV's time).
    survivors = object.__new__(TrackedSurfaces)
    if len(ti) == len(tracked):
        # Every surface survived (ti is 0…K-1): the read-only ids and local geometry are
        # shared, not copied (most views lose none).
        ids, local = tracked.ids, tracked.local
    else:
        ids, local = tracked.ids[ti], tracked.local.select(ti)
        ids.flags.writeable = False
    current = view.select(info.view_index)
    for name, value in (("ids", ids), ("local", local), ("current", current)):
        object.__setattr__(survivors, name, value)
    return survivors, info
