"""Localising a view in the current local map from tracked surfaces (Albot1's triangulation).

Each tracked surface seen both in the local map and in the view affords one pose of the
view in the local map: heading from the difference of the surface's directions, position
from an endpoint that is a real corner (unoccluded) in both observations. The paper's two
heuristics pick one affordance:

1. drop affordances farther from the mean position than the "standard deviation" (here the
   RMS distance of the positions to their mean; at least the one nearest the mean survives);
2. of the rest, take the one nearest the path-integration estimate.

Before the heuristics, an affordance that disagrees with the path-integration estimate by
more than the paper's own recognition thresholds (RTSV's ``match_distance_m`` = 40 cm and
``match_angle_deg`` = 5°, read from ``TrackingParams`` unless ``max_pi_deviation_m`` /
``max_pi_deviation_deg`` are set) per step since the local map's origin is discarded: at each
step the surface was recognised as the same precisely because its prediction by the
odometry increment agreed that well, so after ``k`` steps a pose that disagrees with path
integration by more than ``k`` times that is a bad fit (typically a short surface seen
with few beams), not information. Set both to ``inf`` for the paper's bare heuristics.

The paper localises by a point and does not say where the heading comes from. Options:

- ``heading="weighted"`` (default): each tracked surface affords a heading, the difference
  of two line fits' directions, whose variance falls as (points × length²) of each fit;
  a direction needs no corner, so every tracked surface counts, not only those with a
  usable endpoint. Headings that contradict path integration beyond the gate below are
  left out, the rest averaged with those inverse-variance weights, and headings more
  than ``heading_consensus_deg`` from that estimate (mis-tracked surfaces) are dropped
  once before averaging again;
- ``heading="inlier_mean"``: the plain mean of inlier headings within
  ``heading_consensus_deg`` of the chosen one;
- ``heading="selected"``: the chosen affordance's own heading.

The chosen surface's position is then recomputed with the fused heading.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal, NamedTuple

import numpy as np
from numpy.typing import NDArray

from albot2d.compiled import compiled_kernel
from albot2d.errors import InputError
from albot2d.geometry import Pose, segment_angles, wrap_angle
from albot2d.perception.surfaces import Surfaces
from albot2d.perception.tracking import TrackingParams, key_endpoints
from albot2d.validation import check_non_negative

__all__ = [
    "Affordances",
    "TriangulationParams",
    "gate_limits",
    "heading_from_directions",
    "outlier_kept",
    "pi_consistent",
    "pose_affordances",
    "triangulate",
]


@dataclass(frozen=True, slots=True)
class TriangulationParams:
    """Options of the triangulation heuristics.

    - ``use_outlier_heuristic``: heuristic 1 (drop affordances beyond one standard
      deviation from the mean); the spec reports that dropping it measurably hurts.
    - ``prefer_nearer_endpoint``: when both endpoints are usable, take the one nearer the
      robot (range errors grow with distance).
    - ``choose``: heuristic 2, the affordance ``"nearest_to_pi"`` (the paper's text) or the
      one of highest ``"fitness"`` (the authors' code: the surface's length, how well its
      corner and direction agree with path integration, and its range; see
      ``albot2d.perception.tracking.match_fitness``).
    - ``position_endpoint``: which endpoint pairs may give a position: ``"both"`` (an end
      precisely located in both observations: unoccluded and not ``uncertain``, the
      paper's "occluding points" read strictly); ``"local_key"`` (the authors' programs,
      ``Mapping.cpp:recognizeTargetObjects``: the tracked surface's key point, its end
      unoccluded in the local map, the nearer if both, whatever it is in the current view;
      the code has no ``uncertain`` flag); or ``"current_real"`` (the code's older
      ``mfisOp.cpp`` path: an end unoccluded in the current view, whatever it was in the
      local map). With either code reading every tracked surface affords a position, so
      path integration is left for views with no tracked surface, as in the code.
    """

    use_outlier_heuristic: bool = True
    prefer_nearer_endpoint: bool = True
    heading: Literal["weighted", "inlier_mean", "selected"] = "weighted"
    heading_consensus_deg: float = 1.0
    max_pi_deviation_m: float | None = None
    max_pi_deviation_deg: float | None = None
    choose: Literal["nearest_to_pi", "fitness"] = "nearest_to_pi"
    position_endpoint: Literal["both", "local_key", "current_real"] = "both"

    def __post_init__(self) -> None:
        check_non_negative(self, "heading_consensus_deg")
        for name in ("max_pi_deviation_m", "max_pi_deviation_deg"):
            value = getattr(self, name)
            if value is None:
                continue
            if isinstance(value, bool) or not isinstance(value, int | float) or not value > 0:
                raise InputError(f"TriangulationParams.{name} must be > 0, got {value!r}")
        if self.heading not in ("weighted", "inlier_mean", "selected"):
            raise InputError(
                "TriangulationParams.heading must be weighted, inlier_mean or selected, "
                f"got {self.heading!r}"
            )
        if self.choose not in ("nearest_to_pi", "fitness"):
            raise InputError(
                f"TriangulationParams.choose must be nearest_to_pi or fitness, got {self.choose!r}"
            )
        if self.position_endpoint not in ("both", "local_key", "current_real"):
            raise InputError(
                "TriangulationParams.position_endpoint must be both, local_key or "
                f"current_real, got {self.position_endpoint!r}"
            )


class Affordances(NamedTuple):
    """Per-surface pose affordances: ``poses (K, 3)`` in the local map, ``surface (K,)``
    indices, and the endpoint each used: ``local_points``/``current_points`` ``(K, 2)``."""

    poses: NDArray[np.float64]
    surface: NDArray[np.int64]
    local_points: NDArray[np.float64]
    current_points: NDArray[np.float64]


def _no_affordances() -> Affordances:
    return Affordances(np.zeros((0, 3)), np.zeros(0, np.int64), np.zeros((0, 2)), np.zeros((0, 2)))


def _position_for(heading: float, local_pt: NDArray, current_pt: NDArray) -> NDArray:
    c, s = np.cos(heading), np.sin(heading)
    return local_pt - np.array(
        [c * current_pt[0] - s * current_pt[1], s * current_pt[0] + c * current_pt[1]]
    )


def pose_affordances(
    local: Surfaces,
    current: Surfaces,
    heading_hint_rad: float,
    params: TriangulationParams = TriangulationParams(),
) -> Affordances:
    """The pose of the current view in the local map afforded by each surface pair.

    ``local[i]`` and ``current[i]`` are the same physical surface seen in the local map and
    in the current view. Directions are compared as undirected lines, and the ambiguity of
    pi is resolved towards ``heading_hint_rad`` (the path-integration heading).
    """
    n = len(local)
    if n != len(current):
        raise ValueError(f"local has {n} surfaces but current has {len(current)}")
    if n == 0:
        return _no_affordances()
    dtheta = wrap_angle(segment_angles(local.segments) - segment_angles(current.segments))
    flipped = np.abs(wrap_angle(dtheta - heading_hint_rad)) > np.pi / 2
    dtheta = np.where(flipped, wrap_angle(dtheta + np.pi), dtheta)

    cur_pts = current.segments.reshape(n, 2, 2)
    loc_pts = local.segments.reshape(n, 2, 2)
    loc_ok = local.localisable
    # A flipped match pairs endpoint 0 of one observation with endpoint 1 of the other.
    loc_pts = np.where(flipped[:, None, None], loc_pts[:, ::-1, :], loc_pts)
    loc_ok = np.where(flipped[:, None], loc_ok[:, ::-1], loc_ok)
    usable = loc_ok & current.localisable  # (n, 2): a precisely located real end in both
    if params.position_endpoint == "current_real":  # the code's mfisOp.cpp: real in the view
        usable = ~current.occluded
    elif params.position_endpoint == "local_key":  # the code's programs: the tracked key end
        rows = np.arange(n)
        key = key_endpoints(local)  # in the local observation's own endpoint order
        usable = np.zeros((n, 2), bool)
        usable[rows, np.where(flipped, 1 - key, key)] = ~local.occluded[rows, key]

    dist = np.hypot(cur_pts[..., 0], cur_pts[..., 1])
    if params.prefer_nearer_endpoint:
        score = np.where(usable, dist, np.inf)
    else:
        score = np.where(usable, np.arange(2)[None, :], np.inf)
    best = np.argmin(score, axis=1)
    has = np.isfinite(score[np.arange(n), best])
    idx = np.flatnonzero(has)
    if len(idx) == 0:
        return _no_affordances()
    th = dtheta[idx]
    c, s = np.cos(th), np.sin(th)
    pc = cur_pts[idx, best[idx]]
    pl = loc_pts[idx, best[idx]]
    x = pl[:, 0] - (c * pc[:, 0] - s * pc[:, 1])
    y = pl[:, 1] - (s * pc[:, 0] + c * pc[:, 1])
    return Affordances(np.column_stack([x, y, th]), idx.astype(np.int64), pl, pc)


def _weighted_heading_offset(
    local: Surfaces,
    current: Surfaces,
    path_integration: Pose,
    chosen_heading: float,
    consensus_rad: float,
    pi_gate_rad: float,
) -> tuple[float, int] | None:
    """Correction to ``chosen_heading`` from every tracked surface's direction.

    A direction needs no corner, so surfaces without a usable endpoint (long walls seen
    at a grazing angle: the most precise directions of all) count too. Directions that
    contradict path integration beyond the gate are left out; the rest are averaged with
    inverse-variance weights, then once more without those farther than the consensus
    from that mean. Returns the correction and how many directions agreed with it, or
    ``None`` when every direction contradicts path integration.
    """
    dtheta = wrap_angle(segment_angles(local.segments) - segment_angles(current.segments))
    flipped = np.abs(wrap_angle(dtheta - path_integration.theta)) > np.pi / 2
    dtheta = np.where(flipped, wrap_angle(dtheta + np.pi), dtheta)
    ok = np.abs(wrap_angle(dtheta - path_integration.theta)) <= pi_gate_rad
    if not ok.any():
        return None
    idx = np.flatnonzero(ok)
    dev = np.asarray(wrap_angle(dtheta[idx] - chosen_heading))
    w = 1.0 / (1.0 / _fit_weight(local, idx) + 1.0 / _fit_weight(current, idx))
    offset = float(np.average(dev, weights=w))
    agree = np.abs(dev - offset) <= consensus_rad
    if agree.any():
        offset = float(np.average(dev[agree], weights=w[agree]))
    return offset, int(agree.sum())


def _fit_weight(surfaces: Surfaces, index: NDArray[np.int64]) -> NDArray[np.float64]:
    """Inverse variance (up to a constant) of each surface's fitted direction: n · L².

    Surfaces not from a scan (no beams) count as one point each."""
    beams = surfaces.beams[index]
    n = np.where(beams[:, 0] >= 0, beams[:, 1] - beams[:, 0] + 1, 1).astype(np.float64)
    length = surfaces.lengths_m[index]
    return np.maximum(n * length**2, 1e-12)


def _pi_fitness(aff: Affordances, current: Surfaces, path_integration: Pose) -> NDArray:
    """The authors' fitness of each affordance's surface under path integration:
    length_mm · (400 − d_mm) · (5 − Δθ_deg) / max(range_mm, 2000), where d and Δθ are how far
    its corner and heading land from the local map's when moved by path integration."""
    pts = aff.current_points
    c, s = np.cos(path_integration.theta), np.sin(path_integration.theta)
    moved = np.column_stack(
        [
            path_integration.x + c * pts[:, 0] - s * pts[:, 1],
            path_integration.y + s * pts[:, 0] + c * pts[:, 1],
        ]
    )
    d_mm = 1000.0 * np.hypot(*(moved - aff.local_points).T)
    dth_deg = np.degrees(np.abs(wrap_angle(aff.poses[:, 2] - path_integration.theta)))
    length_mm = 1000.0 * current.lengths_m[aff.surface]
    range_mm = 1000.0 * np.hypot(pts[:, 0], pts[:, 1])
    return (
        length_mm
        * np.maximum(400.0 - d_mm, 0.0)
        * np.maximum(5.0 - dth_deg, 0.0)
        / np.maximum(range_mm, 2000.0)
    )


def gate_limits(
    params: TriangulationParams, gate: tuple[float, float] | None
) -> tuple[float, float]:
    """The per-step (metres, degrees) an affordance may deviate from path integration:
    ``max_pi_deviation_*`` where set, else ``gate``, else RTSV's recognition thresholds."""
    if gate is None:
        defaults = TrackingParams()
        gate = (defaults.match_distance_m, defaults.match_angle_deg)
    gate_m = params.max_pi_deviation_m if params.max_pi_deviation_m is not None else gate[0]
    gate_deg = params.max_pi_deviation_deg if params.max_pi_deviation_deg is not None else gate[1]
    return gate_m, gate_deg


def pi_consistent(
    poses: NDArray[np.float64], path_integration: Pose, steps: int, gate_m: float, gate_deg: float
) -> NDArray[np.bool_]:
    """Which affordances ``(K, 3)`` lie within ``steps`` times the per-step gate (metres,
    degrees) of the path-integration pose: the gate every affordance must pass."""
    k = max(int(steps), 1)
    return (
        np.hypot(poses[:, 0] - path_integration.x, poses[:, 1] - path_integration.y) <= k * gate_m
    ) & (np.abs(wrap_angle(poses[:, 2] - path_integration.theta)) <= k * np.radians(gate_deg))


def outlier_kept(poses: NDArray[np.float64]) -> NDArray[np.bool_]:
    """The paper's heuristic 1: keep the affordances whose position lies within one RMS
    distance of their mean (the nearest to it when none does)."""
    mean = poses[:, :2].mean(axis=0)
    d = np.hypot(*(poses[:, :2] - mean).T)
    keep = d <= float(np.sqrt(np.mean(d**2)))
    return keep if keep.any() else d == d.min()


def triangulate(
    local: Surfaces,
    current: Surfaces,
    path_integration: Pose,
    params: TriangulationParams = TriangulationParams(),
    *,
    steps: int = 1,
    gate: tuple[float, float] | None = None,
) -> Pose | None:
    """The view's pose in the local map, or ``None`` when no surface affords one.

    ``steps``: odometry steps integrated since the local map's origin (scales the gate).
    ``gate``: the per-step (metres, degrees) used where ``max_pi_deviation_*`` is ``None``;
    by default RTSV's recognition thresholds (``TrackingParams`` defaults).
    """
    gate_m, gate_deg = gate_limits(params, gate)
    k = max(int(steps), 1)
    if 0 < len(local) < _SMALL and len(local) == len(current) and _small_path_covers(params):
        kernel = compiled_kernel("albot2d.mapping.albot1.triangulation_numba", "triangulate_kernel")
        if kernel is not None:
            return _triangulate_compiled(
                kernel, local, current, path_integration, params, k, gate_m, gate_deg
            )
    aff = pose_affordances(local, current, path_integration.theta, params)
    consistent = pi_consistent(aff.poses, path_integration, k, gate_m, gate_deg)
    if not consistent.all():
        aff = Affordances._make(field[consistent] for field in aff)
    poses = aff.poses
    if len(poses) == 0:
        return None
    keep = np.ones(len(poses), bool)
    if params.use_outlier_heuristic and len(poses) > 2:
        keep = outlier_kept(poses)
    kept = np.flatnonzero(keep)
    if params.choose == "fitness":
        best = int(kept[np.argmax(_pi_fitness(aff, current, path_integration)[kept])])
    else:
        d_pi = np.hypot(poses[kept, 0] - path_integration.x, poses[kept, 1] - path_integration.y)
        best = int(kept[np.argmin(d_pi)])
    if params.heading == "selected":
        return Pose.from_array(poses[best])
    consensus = float(np.radians(params.heading_consensus_deg))
    if params.heading == "inlier_mean":
        if len(kept) == 1:
            return Pose.from_array(poses[best])
        dev = np.asarray(wrap_angle(poses[kept, 2] - poses[best, 2]))
        offset = float(dev[np.abs(dev) <= consensus].mean())
    else:
        fused = _weighted_heading_offset(
            local,
            current,
            path_integration,
            float(poses[best, 2]),
            consensus,
            k * float(np.radians(gate_deg)),
        )
        offset = 0.0 if fused is None else fused[0]
    heading = float(wrap_angle(poses[best, 2] + offset))
    x, y = _position_for(heading, aff.local_points[best], aff.current_points[best])
    return Pose(float(x), float(y), heading)


def heading_from_directions(
    local: Surfaces,
    current: Surfaces,
    path_integration: Pose,
    params: TriangulationParams = TriangulationParams(),
    *,
    steps: int = 1,
    gate: tuple[float, float] | None = None,
    min_agreeing: int = 1,
) -> float | None:
    """The view's heading in the local map from the tracked surfaces' directions alone, or
    ``None`` when fewer than ``min_agreeing`` of them agree (within the PI gate, then within
    ``heading_consensus_deg`` of their mean).

    For views whose tracked surfaces afford no position (no end precisely located in both
    observations): a direction needs no corner. The same inverse-variance mean, PI gate
    and consensus as ``heading="weighted"``, centred on the path-integration heading.
    """
    if len(local) != len(current):
        raise ValueError(f"local has {len(local)} surfaces but current has {len(current)}")
    if len(local) == 0:
        return None
    _, gate_deg = gate_limits(params, gate)
    k = max(int(steps), 1)
    fused = _weighted_heading_offset(
        local,
        current,
        path_integration,
        path_integration.theta,
        float(np.radians(params.heading_consensus_deg)),
        k * float(np.radians(gate_deg)),
    )
    if fused is None or fused[1] < max(int(min_agreeing), 1):
        return None
    return float(wrap_angle(path_integration.theta + fused[0]))


# -- a few surfaces: one compiled call (``triangulation_numba``) -------------------------
# For fewer than ``_SMALL`` surfaces numpy's small-array overhead costs more than the work,
# so with numba the default heuristics run in one compiled call: the array path's float
# operations in its order (sums left to right, which is what numpy's pairwise summation
# does below 8 terms), hence the same pose bit for bit (tests/test_triangulation_small.py).
# The kernel takes numpy's direction differences: numpy's vectorised arctan2 differs from
# numba's in the last bit on some CPUs.
_SMALL = 8


@functools.lru_cache(maxsize=16)
def _small_path_covers(params: TriangulationParams) -> bool:
    """The compiled path implements the default heuristics (any gate and consensus)."""
    general = dataclasses.replace(
        params, max_pi_deviation_m=None, max_pi_deviation_deg=None, heading_consensus_deg=1.0
    )
    return general == TriangulationParams()


def _triangulate_compiled(
    kernel: Callable[..., tuple[bool, float, float, float]],
    local: Surfaces,
    current: Surfaces,
    pi: Pose,
    params: TriangulationParams,
    k: int,
    gate_m: float,
    gate_deg: float,
) -> Pose | None:
    """``triangulate``'s array path for a few surfaces in one compiled call."""
    ls, cs = local.segments, current.segments
    ang_l = np.arctan2(ls[:, 3] - ls[:, 1], ls[:, 2] - ls[:, 0]) - np.arctan2(
        cs[:, 3] - cs[:, 1], cs[:, 2] - cs[:, 0]
    )
    found, x, y, heading = kernel(
        ang_l, ls, cs, local.localisable, current.localisable, local.beams, current.beams,
        float(pi.x), float(pi.y), float(pi.theta), k * gate_m, k * math.radians(gate_deg),
        math.radians(params.heading_consensus_deg), bool(params.use_outlier_heuristic),
    )  # fmt: skip
    return Pose(float(x), float(y), float(heading)) if found else None
