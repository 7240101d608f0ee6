"""Whether a world can be driven at all: the semantic checks a world file must pass.

The reader (``worldgen.world_reader``) checks each field's type and range; this module
checks the world as a whole, with named limits, so that no world albot2d accepts is
impossible or unbounded work:

- at least one wall of positive length; counts of walls, clutter, roadmap nodes and
  moving obstacles within named maxima;
- ``robot_radius_m`` at most :data:`MAX_ROBOT_RADIUS_M`;
- the start disc (robot radius) inside ``bounds`` and free space, clear of every wall and
  clutter outline; so free space fits the robot;
- a roadmap with at least one edge, every node a safe place for the disc, every edge
  disc-safe (no wall or clutter outline closer than the robot radius), and the start on
  the roadmap or joined to one of its nearest nodes by a disc-safe straight line;
- total wall length at most :data:`MAX_TOTAL_WALL_LENGTH_M` (the raycast grid and every
  beam's work grow with it);
- every moving obstacle's outline (at its start pose) clear of the start disc, and those
  that stand still (no speed or no path) clear of the roadmap by the robot radius, as
  walls must be;
- moving obstacles: a valid outline of at least :data:`MIN_OBSTACLE_AREA_M2`, speed at most
  :data:`MAX_OBSTACLE_SPEED_M_S`, mass at most :data:`MAX_OBSTACLE_MASS_KG`, inside bounds,
  and a walking person's path at least :data:`MIN_PERSON_PATH_M` long (a shorter one would
  make the person turn around thousands of times per physics step).

Disc checks allow :data:`_TOLERANCE_M` of rounding. :func:`world_problem` returns the
first problem as text (the reader adds the file name); :func:`check_world` raises it.
"""

from __future__ import annotations

import math

import numpy as np
import shapely

from albot2d import limits as _limits
from albot2d.errors import InputError
from worldgen.params import MAX_DYNAMIC_OBSTACLES, MAX_ROBOT_RADIUS_M
from worldgen.world import MAX_OBSTACLE_SPEED_M_S, DynamicObstacle, World

__all__ = [
    "MAX_CLUTTER_ITEMS",
    "MAX_DYNAMIC_OBSTACLES",
    "MAX_OBSTACLE_MASS_KG",
    "MAX_OBSTACLE_SPEED_M_S",
    "MAX_PATH_POINTS",
    "MAX_ROADMAP_NODES",
    "MAX_ROBOT_RADIUS_M",
    "MAX_TOTAL_WALL_LENGTH_M",
    "MAX_WALLS",
    "MIN_OBSTACLE_AREA_M2",
    "MIN_PERSON_PATH_M",
    "check_world",
    "world_problem",
]

MAX_WALLS = _limits.MAX_WALLS
MAX_CLUTTER_ITEMS = _limits.MAX_CLUTTER_ITEMS
MAX_ROADMAP_NODES = _limits.MAX_ROADMAP_NODES
MAX_PATH_POINTS = _limits.MAX_PATH_POINTS
MAX_TOTAL_WALL_LENGTH_M = _limits.MAX_TOTAL_WALL_LENGTH_M
MIN_OBSTACLE_AREA_M2 = 1e-4  # a 1 cm square
MAX_OBSTACLE_MASS_KG = 10_000.0
MIN_PERSON_PATH_M = 0.1
_TOLERANCE_M = 1e-9
_START_LINKS = 3  # as ``worldgen.assemble`` links a given start


def check_world(world: World) -> None:
    """Raise ``InputError`` naming the first reason ``world`` cannot be driven."""
    problem = world_problem(world)
    if problem is not None:
        raise InputError(problem)


def world_problem(world: World) -> str | None:
    """The first reason ``world`` cannot be driven (see the module docstring), or None."""
    for check in (_counts, _walls, _start, _roadmap, _obstacles, _static_obstacles):
        problem = check(world)
        if problem is not None:
            return problem
    return None


def _counts(world: World) -> str | None:
    for what, count, limit in (
        ("walls", len(world.walls), MAX_WALLS),
        ("clutter", len(world.clutter), MAX_CLUTTER_ITEMS),
        ("roadmap.nodes", len(world.roadmap.nodes), MAX_ROADMAP_NODES),
        ("dynamic_obstacles", len(world.dynamic_obstacles), MAX_DYNAMIC_OBSTACLES),
    ):
        if count > limit:
            return f"{what} has {count} items, more than the limit of {limit}"
    w = world.walls
    total = float(np.hypot(w[:, 2] - w[:, 0], w[:, 3] - w[:, 1]).sum()) if len(w) else 0.0
    if total > MAX_TOTAL_WALL_LENGTH_M:
        return (f"walls are {total:.0f} m long in all, more than the limit of "
                f"{MAX_TOTAL_WALL_LENGTH_M:.0f} m (MAX_TOTAL_WALL_LENGTH_M)")  # fmt: skip
    if world.robot_radius_m > MAX_ROBOT_RADIUS_M:
        return f"robot_radius_m is {world.robot_radius_m!r}, more than {MAX_ROBOT_RADIUS_M} m"
    return None


def _walls(world: World) -> str | None:
    w = world.walls
    if not (np.hypot(w[:, 2] - w[:, 0], w[:, 3] - w[:, 1]) > 0.0).any():
        return f"walls: needs at least one wall of positive length, got {len(w)} walls"
    xmin, ymin, xmax, ymax = world.bounds
    slack = _TOLERANCE_M + 1e-9 * max(xmax - xmin, ymax - ymin)
    xs, ys = w[:, [0, 2]], w[:, [1, 3]]
    outside = ((xs < xmin - slack) | (xs > xmax + slack) | (ys < ymin - slack)
               | (ys > ymax + slack)).any(axis=1)  # fmt: skip
    if outside.any():
        i = int(np.flatnonzero(outside)[0])
        return f"walls[{i}] {w[i].tolist()} lies outside bounds {list(world.bounds)}"
    fx0, fy0, fx1, fy1 = world.free_space.bounds
    if fx0 < xmin - slack or fy0 < ymin - slack or fx1 > xmax + slack or fy1 > ymax + slack:
        return f"free_space {[fx0, fy0, fx1, fy1]} reaches outside bounds {list(world.bounds)}"
    return None


def _obstacle_tree(world: World) -> shapely.STRtree:
    segs = world.obstacle_segments
    return shapely.STRtree(shapely.linestrings(segs.reshape(-1, 2, 2)))


def _clear(tree: shapely.STRtree, geoms: np.ndarray, radius_m: float) -> np.ndarray:
    """For each geometry, whether no wall or clutter outline is within ``radius_m``."""
    ok = np.ones(len(geoms), dtype=bool)
    hits = tree.query(geoms, predicate="dwithin", distance=max(radius_m - _TOLERANCE_M, 0.0))
    ok[hits[0]] = False
    return ok


def _in_free_space(world: World, xy: np.ndarray, radius_m: float) -> np.ndarray:
    """Whether each point's disc lies inside the free-space polygon."""
    free = world.free_space
    inside = shapely.covers(free, shapely.points(xy))
    boundary = shapely.boundary(free)
    distance = shapely.distance(boundary, shapely.points(xy))
    return inside & (distance >= radius_m - _TOLERANCE_M)


def _start(world: World) -> str | None:
    s, r = world.start, world.robot_radius_m
    xmin, ymin, xmax, ymax = world.bounds
    where = f"start ({s.x!r}, {s.y!r})"
    if not (xmin <= s.x <= xmax and ymin <= s.y <= ymax):
        return f"{where} is outside bounds {list(world.bounds)}"
    xy = np.array([[s.x, s.y]])
    if not _in_free_space(world, xy, r)[0]:
        return f"{where}: the robot's disc (radius {r} m) is not inside free_space"
    if not _clear(_obstacle_tree(world), shapely.points(xy), r)[0]:
        return f"{where}: the robot's disc (radius {r} m) overlaps a wall or clutter"
    return None


def _roadmap(world: World) -> str | None:
    nodes, edges, r = world.roadmap.nodes, world.roadmap.edges, world.robot_radius_m
    if len(edges) == 0:
        return "roadmap has no edges: the robot has nowhere to go"
    tree = _obstacle_tree(world)
    ok = _in_free_space(world, nodes, r) & _clear(tree, shapely.points(nodes), r)
    if not ok.all():
        i = int(np.flatnonzero(~ok)[0])
        return (f"roadmap.nodes[{i}] {nodes[i].tolist()}: the robot's disc (radius {r} m) "
                "is not clear of walls and clutter inside free_space")  # fmt: skip
    lines = shapely.linestrings(np.stack([nodes[edges[:, 0]], nodes[edges[:, 1]]], axis=1))
    ok = _clear(tree, lines, r)
    if not ok.all():
        k = int(np.flatnonzero(~ok)[0])
        return (f"roadmap.edges[{k}] {edges[k].tolist()} passes closer than the robot radius "
                f"({r} m) to a wall or clutter")  # fmt: skip
    start = np.array([world.start.x, world.start.y])
    d = np.hypot(*(nodes - start).T)
    if d.min() <= _TOLERANCE_M:
        return None
    near = np.argsort(d, kind="stable")[:_START_LINKS]
    links = shapely.linestrings([[start, nodes[k]] for k in near])
    if not _clear(tree, links, r).any():
        return (f"start ({world.start.x!r}, {world.start.y!r}) is not on the roadmap and no "
                "nearby roadmap node can be reached from it: the robot is boxed in")  # fmt: skip
    return None


def _obstacles(world: World) -> str | None:
    xmin, ymin, xmax, ymax = world.bounds
    for i, ob in enumerate(world.dynamic_obstacles):
        field = f"dynamic_obstacles[{i}]"
        outline = shapely.Polygon(ob.shape)
        if not outline.is_valid:
            return f"{field}.shape is not a valid polygon: {shapely.is_valid_reason(outline)}"
        if outline.area < MIN_OBSTACLE_AREA_M2:
            return (f"{field}.shape has area {outline.area!r} m², less than "
                    f"{MIN_OBSTACLE_AREA_M2:g} m²")  # fmt: skip
        if not (xmin <= ob.pose.x <= xmax and ymin <= ob.pose.y <= ymax):
            return f"{field}.pose ({ob.pose.x!r}, {ob.pose.y!r}) is outside bounds"
        if ob.speed_m_s > MAX_OBSTACLE_SPEED_M_S:
            return (f"{field}.speed_m_s is {ob.speed_m_s!r}, more than the limit of "
                    f"{MAX_OBSTACLE_SPEED_M_S} m/s")  # fmt: skip
        if ob.mass_kg > MAX_OBSTACLE_MASS_KG:
            return f"{field}.mass_kg is {ob.mass_kg!r}, more than {MAX_OBSTACLE_MASS_KG:g} kg"
        if len(ob.path) > MAX_PATH_POINTS:
            return f"{field}.path has {len(ob.path)} points, more than {MAX_PATH_POINTS}"
        if ob.kind == "person" and ob.speed_m_s > 0.0 and len(ob.path) >= 2:
            length = float(np.hypot(*np.diff(ob.path, axis=0).T).sum())
            if 0.0 < length < MIN_PERSON_PATH_M or not math.isfinite(length):
                return (f"{field}.path is {length!r} m long; a walking person needs at least "
                        f"{MIN_PERSON_PATH_M} m (or speed_m_s 0)")  # fmt: skip
    return None


def _outline(ob: DynamicObstacle) -> shapely.Polygon:
    """An obstacle's outline placed at its start pose."""
    c, s = math.cos(ob.pose.theta), math.sin(ob.pose.theta)
    xy = ob.shape @ np.array([[c, s], [-s, c]]) + [ob.pose.x, ob.pose.y]
    return shapely.Polygon(xy)


def _static_obstacles(world: World) -> str | None:
    """Obstacles against the start disc (every one) and the roadmap (those that stand
    still), as walls are: a box on the start pose would hold the robot inside it, one on
    the roadmap would block the tour."""
    if not world.dynamic_obstacles:
        return None
    r = world.robot_radius_m
    start = shapely.Point(world.start.x, world.start.y)
    nodes, edges = world.roadmap.nodes, world.roadmap.edges
    lines = shapely.linestrings(np.stack([nodes[edges[:, 0]], nodes[edges[:, 1]]], axis=1))
    tree = shapely.STRtree(lines)
    for i, ob in enumerate(world.dynamic_obstacles):
        field = f"dynamic_obstacles[{i}]"
        outline = _outline(ob)
        if outline.distance(start) < r - _TOLERANCE_M:
            return (f"{field} ({ob.kind} at {ob.pose.x!r}, {ob.pose.y!r}) overlaps the robot's "
                    f"start disc (radius {r} m)")  # fmt: skip
        moves = ob.speed_m_s > 0.0 and len(ob.path) >= 2
        if moves:
            continue
        hits = tree.query(outline, predicate="dwithin", distance=max(r - _TOLERANCE_M, 0.0))
        if len(hits):
            k = int(np.min(hits))
            return (f"{field} ({ob.kind} at {ob.pose.x!r}, {ob.pose.y!r}, standing still) is "
                    f"closer than the robot radius ({r} m) to roadmap.edges[{k}] "
                    f"{edges[k].tolist()}: it blocks the roadmap")  # fmt: skip
    return None
