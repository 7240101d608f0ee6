"""Localising a view in the current local map from tracked surfaces (Albot1's triangulation).

Each tracked surface seen both in the local map and in the view affords one pose of the
view in the local map: heading from the difference of the surface's directions, position
from an endpoint that is a real corner (unoccluded) in both observations. The paper's two
heuristics pick one affordance:

1. drop affordances farther from the mean position than the "standard deviation" (here the
   RMS distance of the positions to their mean; at least the one nearest the mean survives);
2. of the rest, take the one nearest the path-integration estimate.

The paper localises by a point and does not say where the heading comes from. By default
(``heading="inlier_mean"``) the heading is the mean of the headings afforded by the
surfaces that survive heuristic 1 and agree with the chosen one within
``heading_consensus_deg``: each is one line fit's direction, so averaging them cuts the
noise of a single fit, while a mis-tracked surface (whose heading disagrees) is left out.
The chosen surface's position is then recomputed with that heading.
``heading="selected"`` keeps the chosen affordance's own heading.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, NamedTuple

import numpy as np
from numpy.typing import NDArray

from albot2d.geometry import Pose, segment_angles, wrap_angle
from albot2d.perception.surfaces import Surfaces

__all__ = ["Affordances", "TriangulationParams", "pose_affordances", "triangulate"]


@dataclass(frozen=True, slots=True)
class TriangulationParams:
    """Options of the triangulation heuristics.

    - ``use_outlier_heuristic``: heuristic 1 (drop affordances beyond one standard
      deviation from the mean); the spec reports that dropping it measurably hurts.
    - ``prefer_nearer_endpoint``: when both endpoints are usable, take the one nearer the
      robot (range errors grow with distance).
    """

    use_outlier_heuristic: bool = True
    prefer_nearer_endpoint: bool = True
    heading: Literal["inlier_mean", "selected"] = "inlier_mean"
    heading_consensus_deg: float = 1.0

    def __post_init__(self) -> None:
        from albot2d.validation import check_non_negative

        check_non_negative(self, "heading_consensus_deg")
        if self.heading not in ("inlier_mean", "selected"):
            from albot2d.errors import InputError

            raise InputError(
                f"TriangulationParams.heading must be inlier_mean or selected, got {self.heading!r}"
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


def triangulate(
    local: Surfaces,
    current: Surfaces,
    path_integration: Pose,
    params: TriangulationParams = TriangulationParams(),
) -> Pose | None:
    """The view's pose in the local map, or ``None`` when no surface affords one."""
    aff = pose_affordances(local, current, path_integration.theta, params)
    poses = aff.poses
    if len(poses) == 0:
        return None
    keep = np.ones(len(poses), bool)
    if params.use_outlier_heuristic and len(poses) > 2:
        mean = poses[:, :2].mean(axis=0)
        d = np.hypot(*(poses[:, :2] - mean).T)
        sigma = float(np.sqrt(np.mean(d**2)))
        keep = d <= sigma
        if not keep.any():
            keep = d == d.min()
    kept = np.flatnonzero(keep)
    d_pi = np.hypot(poses[kept, 0] - path_integration.x, poses[kept, 1] - path_integration.y)
    best = int(kept[np.argmin(d_pi)])
    if params.heading == "selected" or len(kept) == 1:
        return Pose.from_array(poses[best])
    # Mean heading of the inliers, as deviations from the chosen one (no wrap-around).
    dev = np.asarray(wrap_angle(poses[kept, 2] - poses[best, 2]))
    dev = dev[np.abs(dev) <= np.radians(params.heading_consensus_deg)]
    heading = float(wrap_angle(poses[best, 2] + dev.mean()))
    x, y = _position_for(heading, aff.local_points[best], aff.current_points[best])
    return Pose(float(x), float(y), heading)
