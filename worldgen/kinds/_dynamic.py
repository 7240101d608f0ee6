"""Moving obstacles for any world: movable boxes off the roadmap and people walking along it.

People walk back and forth along a shortest roadmap path between two nodes at least
``_MIN_WALK_M`` apart; boxes sit where they block no roadmap edge, with room around them.
Both start at least ``_START_CLEARANCE_M`` from the robot's start point (a person whose
path begins there starts from the path's other end).
"""

from __future__ import annotations

import networkx as nx
import numpy as np
import shapely

from albot2d.geometry import Pose
from worldgen.world import DynamicObstacle, World

__all__ = ["add_dynamic_obstacles"]

_MIN_WALK_M = 5.0
_PERSON_SHAPE = np.array(
    [[0.12, 0.25], [-0.12, 0.25], [-0.15, 0.0], [-0.12, -0.25], [0.12, -0.25], [0.15, 0.0]]
)
_BOX_TRIES = 64
# Moving obstacles start at least this far from the robot's start point.
_START_CLEARANCE_M = 1.0


def _person(world: World, rng: np.random.Generator) -> DynamicObstacle | None:
    nodes = world.roadmap.nodes
    graph = world.roadmap.graph
    for _ in range(16):
        a, b = (int(v) for v in rng.integers(len(nodes), size=2))
        if np.hypot(*(nodes[a] - nodes[b])) < _MIN_WALK_M:
            continue
        path = nx.shortest_path(graph, a, b, weight="weight")
        pts = nodes[path]
        if np.hypot(*(pts[0] - world.start.position)) < _START_CLEARANCE_M:
            pts = pts[::-1]  # start at the far end, not on the robot
        heading = float(np.arctan2(*(pts[1] - pts[0])[::-1]))
        return DynamicObstacle(
            kind="person",
            shape=_PERSON_SHAPE,
            pose=Pose(float(pts[0, 0]), float(pts[0, 1]), heading),
            path=pts,
            speed_m_s=float(rng.uniform(0.6, 1.4)),
            mass_kg=float(rng.uniform(50.0, 90.0)),
        )
    return None


def _box(
    world: World, rng: np.random.Generator, taken: list[shapely.Geometry]
) -> DynamicObstacle | None:
    side = float(rng.uniform(0.4, 0.8))
    half_diag = side / np.sqrt(2.0)
    x0, y0, x1, y1 = world.free_space.bounds
    pts = rng.uniform([x0, y0], [x1, y1], size=(_BOX_TRIES, 2))
    spots = shapely.points(pts)
    inside = shapely.contains(world.free_space, spots)
    wall_gap = shapely.distance(spots, world.free_space.boundary)
    legs = world.roadmap.nodes[world.roadmap.edges].reshape(-1, 2, 2)
    network = shapely.multilinestrings(shapely.linestrings(legs)) if len(legs) else None
    path_gap = shapely.distance(spots, network) if network is not None else np.inf
    need = half_diag + world.robot_radius_m + 0.05
    start_gap = shapely.distance(spots, shapely.Point(world.start.x, world.start.y))
    ok = inside & (wall_gap > half_diag + 0.05) & (path_gap > need)
    ok &= start_gap > half_diag + _START_CLEARANCE_M
    for g in taken:
        ok &= shapely.distance(spots, g) > 2 * half_diag
    good = np.flatnonzero(ok)
    if len(good) == 0:
        return None
    x, y = pts[good[0]]
    half = 0.5 * side
    shape = np.array([[-half, -half], [half, -half], [half, half], [-half, half]])
    return DynamicObstacle(
        kind="box",
        shape=shape,
        pose=Pose(float(x), float(y), float(rng.uniform(-np.pi, np.pi))),
        mass_kg=float(rng.uniform(5.0, 20.0)),
    )


def add_dynamic_obstacles(
    world: World, count: int, rng: np.random.Generator
) -> tuple[DynamicObstacle, ...]:
    """``count`` moving obstacles: alternately a person and a box (boxes may be skipped when
    no spot off the roadmap is free)."""
    out: list[DynamicObstacle] = []
    taken: list[shapely.Geometry] = []
    if len(world.roadmap.nodes) < 2:
        return ()
    for k in range(count):
        if k % 2 == 0:
            mover = _person(world, rng)
        else:
            mover = _box(world, rng, taken)
            if mover is not None:
                taken.append(shapely.Point(mover.pose.x, mover.pose.y))
        if mover is not None:
            out.append(mover)
    return tuple(out)
