"""Planning and following paths on a ``KnowledgeGrid``: what every grid controller shares.

- ``cost_grid``: the per-cell cost of a knowledge grid for a robot disc: impassable where the
  disc (plus ``wall_margin_m``) would touch an occupied cell, ``comfort_cost`` times dearer
  within ``comfort_margin_m`` more of a wall (so paths keep to the middle of corridors and
  doorways). Unknown cells are impassable for an explorer (it drives only where it has
  looked) or passable for a goal seeker (it plans optimistically through what it has not
  seen, as a person walking to an address does, and replans when the laser shows a wall).
- ``search_seeds``: the cells a search starts from (the robot's own, or when that is
  impassable, hard against a wall, the passable cells it sees within a diameter).
- ``plan_path``: Dijkstra to the nearest goal cell, cut down to its corners, in world
  coordinates.
- ``steer``: the velocity command that follows a path corner to corner (turn on the spot
  towards the next corner when more than ``turn_in_place_rad`` off heading, else drive
  with a proportional heading correction), and whether its last corner was reached.
- ``blocked_ahead``: whether a scan shows something in the strip the disc would sweep in
  the next ``stop_distance_m``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from albot2d.control.grid_search import dilate, nearest_goal_path, segment_clear, simplify_path
from albot2d.control.knowledge import GridSpec, KnowledgeGrid
from albot2d.frames import Scan
from albot2d.geometry import Pose, wrap_angle

__all__ = ["Steer", "blocked_ahead", "cost_grid", "plan_path", "search_seeds", "steer"]

FloatArray = NDArray[np.float64]


def cost_grid(
    knowledge: KnowledgeGrid,
    radius_m: float,
    *,
    wall_margin_m: float,
    comfort_margin_m: float,
    comfort_cost: float,
    unknown_passable: bool,
) -> FloatArray:
    """Per-cell travel cost (``inf``: impassable) for a disc of ``radius_m``."""
    r = knowledge.spec.resolution_m
    occupied = knowledge.occupied
    # An occupied cell's wall may lie anywhere in it: up to half a diagonal nearer.
    hard = dilate(occupied, (radius_m + wall_margin_m) / r + math.sqrt(0.5))
    if not unknown_passable:
        hard |= dilate(knowledge.unknown, radius_m / r)
    soft = dilate(occupied, (radius_m + wall_margin_m + comfort_margin_m) / r)
    cost = np.where(soft, comfort_cost, 1.0)
    cost[hard] = np.inf
    return cost


def search_seeds(
    knowledge: KnowledgeGrid, pose: Pose, radius_m: float, passable: NDArray[np.bool_]
) -> tuple[NDArray[np.int64], FloatArray]:
    """The passable cells a search starts from and their starting costs: the robot's own
    cell, or when that is impassable (hard against a wall), the passable cells within a
    diameter of it that it sees in a straight line (dearer the farther)."""
    spec = knowledge.spec
    iy, ix = spec.cell_of(pose.x, pose.y)
    if passable[iy, ix]:
        return np.array([iy * spec.nx + ix]), np.zeros(1)
    r = spec.resolution_m
    k = math.ceil(2.0 * radius_m / r)
    y0, y1 = max(iy - k, 0), min(iy + k + 1, spec.ny)
    x0, x1 = max(ix - k, 0), min(ix + k + 1, spec.nx)
    yy, xx = np.mgrid[y0:y1, x0:x1]
    d = np.hypot(yy - iy, xx - ix)
    ok = passable[y0:y1, x0:x1] & (d <= k)
    clear = ~knowledge.occupied
    here = np.array([iy, ix], dtype=np.float64)
    sy, sx = yy[ok], xx[ok]
    sight = np.array(
        [
            segment_clear(clear, here, np.array([y, x], dtype=np.float64))
            for y, x in zip(sy, sx, strict=True)
        ],
        dtype=bool,
    )
    sy, sx = sy[sight], sx[sight]
    return (sy * spec.nx + sx).astype(np.int64), d[ok][sight] * 4.0


def plan_path(
    spec: GridSpec,
    cost: FloatArray,
    goals: NDArray[np.bool_],
    seeds: NDArray[np.int64],
    seed_dist: FloatArray,
    pose: Pose,
) -> FloatArray | None:
    """The corners ``(K, 2)`` (world x, y) of the cheapest path from the seeds to the nearest
    goal cell, or None when no goal is reachable. The robot's own cell is dropped; when the
    search started elsewhere (the robot hard against a wall) the path begins at that
    passable cell, so the robot drives clear of the wall first."""
    found = nearest_goal_path(cost, goals, seeds, seed_dist)
    if found is None:
        return None
    cells, _ = found
    corners = simplify_path(cells, np.isfinite(cost))
    r = spec.resolution_m
    xy = np.column_stack(
        [spec.origin_x_m + (corners[:, 1] + 0.5) * r, spec.origin_y_m + (corners[:, 0] + 0.5) * r]
    )
    iy, ix = spec.cell_of(pose.x, pose.y)
    own = int(corners[0, 0]) == iy and int(corners[0, 1]) == ix
    return xy[1:] if own and len(xy) > 1 else xy


class Steer(NamedTuple):
    """One control decision: the command, the corners still to drive, and whether the last
    corner (the goal) is reached (the command is then a stop)."""

    command: tuple[float, float]
    path: FloatArray
    arrived: bool


def steer(
    path: FloatArray,
    pose: Pose,
    *,
    speed_mps: float,
    turn_rate_radps: float,
    corner_tolerance_m: float,
    goal_tolerance_m: float,
    turn_in_place_rad: float,
    heading_gain: float,
) -> Steer:
    """Follow ``path`` (at least one corner) from ``pose``. Corners are driven to, not cut:
    the straight legs between them are what the plan checked."""
    while len(path) > 1 and math.hypot(path[0, 0] - pose.x, path[0, 1] - pose.y) < (
        corner_tolerance_m
    ):
        path = path[1:]
    gx, gy = path[0]
    dist = math.hypot(gx - pose.x, gy - pose.y)
    if len(path) == 1 and dist < goal_tolerance_m:
        return Steer((0.0, 0.0), path, True)
    err = float(wrap_angle(math.atan2(gy - pose.y, gx - pose.x) - pose.theta))
    omega = float(np.clip(heading_gain * err, -turn_rate_radps, turn_rate_radps))
    if abs(err) > turn_in_place_rad:
        return Steer((0.0, omega), path, False)
    v = speed_mps * math.cos(err)
    if len(path) == 1:
        v = min(v, max(0.1, dist))  # slow down into the goal
    return Steer((v, omega), path, False)


def blocked_ahead(scan: Scan, radius_m: float, stop_distance_m: float) -> bool:
    """A return inside the strip the disc would sweep in the next ``stop_distance_m``."""
    pts = scan.points()
    ahead = (pts[:, 0] > 0.0) & (pts[:, 0] < radius_m + stop_distance_m)
    return bool((ahead & (np.abs(pts[:, 1]) < radius_m)).any())
