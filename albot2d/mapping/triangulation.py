"""Localising a view in the current local map from tracked surfaces (Albot1's triangulation).

Each tracked surface seen both in the local map and in the view affords one pose of the
view in the local map: heading from the difference of the surface's directions, position
from an endpoint that is a real corner (unoccluded) in both observations. The paper's two
heuristics pick one affordance:

1. drop affordances farther from the mean position than the "standard deviation" (here the
   RMS distance of the positions to their mean; at least the one nearest the mean survives);
2. of the rest, take the one nearest the path-integration estimate, with its own heading.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

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


class Affordances(NamedTuple):
    """Per-surface pose affordances: ``poses (K, 3)`` in the local map, ``surface (K,)`` indices."""

    poses: NDArray[np.float64]
    surface: NDArray[np.int64]


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
        return Affordances(np.zeros((0, 3)), np.zeros(0, np.int64))
    dtheta = wrap_angle(segment_angles(local.segments) - segment_angles(current.segments))
    flipped = np.abs(wrap_angle(dtheta - heading_hint_rad)) > np.pi / 2
    dtheta = np.where(flipped, wrap_angle(dtheta + np.pi), dtheta)

    cur_pts = current.segments.reshape(n, 2, 2)
    loc_pts = local.segments.reshape(n, 2, 2)
    loc_occ = local.occluded
    # A flipped match pairs endpoint 0 of one observation with endpoint 1 of the other.
    loc_pts = np.where(flipped[:, None, None], loc_pts[:, ::-1, :], loc_pts)
    loc_occ = np.where(flipped[:, None], loc_occ[:, ::-1], loc_occ)
    usable = ~loc_occ & ~current.occluded  # (n, 2): endpoint is a real corner in both

    dist = np.hypot(cur_pts[..., 0], cur_pts[..., 1])
    if params.prefer_nearer_endpoint:
        score = np.where(usable, dist, np.inf)
    else:
        score = np.where(usable, np.arange(2)[None, :], np.inf)
    best = np.argmin(score, axis=1)
    has = np.isfinite(score[np.arange(n), best])
    idx = np.flatnonzero(has)
    if len(idx) == 0:
        return Affordances(np.zeros((0, 3)), np.zeros(0, np.int64))
    th = dtheta[idx]
    c, s = np.cos(th), np.sin(th)
    pc = cur_pts[idx, best[idx]]
    pl = loc_pts[idx, best[idx]]
    x = pl[:, 0] - (c * pc[:, 0] - s * pc[:, 1])
    y = pl[:, 1] - (s * pc[:, 0] + c * pc[:, 1])
    return Affordances(np.column_stack([x, y, th]), idx.astype(np.int64))


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
    if params.use_outlier_heuristic and len(poses) > 2:
        mean = poses[:, :2].mean(axis=0)
        d = np.hypot(*(poses[:, :2] - mean).T)
        sigma = float(np.sqrt(np.mean(d**2)))
        keep = d <= sigma
        if not keep.any():
            keep = d == d.min()
        poses = poses[keep]
    d_pi = np.hypot(poses[:, 0] - path_integration.x, poses[:, 1] - path_integration.y)
    return Pose.from_array(poses[int(np.argmin(d_pi))])
