"""A pymunk physics space for a World: ``build_space``.

Walls become static segments (radius 0) and clutter static polygons, all on the space's
static body. Dynamic obstacles become bodies of their own: movable ``box``es are DYNAMIC
bodies with mass (the robot can push them), walking ``person``s KINEMATIC bodies (the
simulator sets their velocity along ``DynamicObstacle.path``). Every shape carries one of
the ``collision_type`` constants below; obstacle bodies also carry ``albot2d_kind``
(``"box"``/``"person"``) and ``albot2d_index`` (index into ``world.dynamic_obstacles``).
The space is top-down 2D, so gravity is zero.

pymunk polygons are convex, so non-convex outlines are split into triangles first.
"""

from __future__ import annotations

import numpy as np
import pymunk
import shapely
from numpy.typing import NDArray

from worldgen.world import DynamicObstacle, World

__all__ = [
    "COLLISION_BOX",
    "COLLISION_CLUTTER",
    "COLLISION_PERSON",
    "COLLISION_WALL",
    "build_space",
    "convex_parts",
    "obstacle_bodies",
]

COLLISION_WALL = 1
COLLISION_CLUTTER = 2
COLLISION_BOX = 3
COLLISION_PERSON = 4

# A polygon whose area is within this fraction of its hull's is treated as convex: one
# pymunk Poly instead of many triangles (float noise never makes a true box "non-convex").
_CONVEX_AREA_TOLERANCE = 1e-9


def convex_parts(polygon: shapely.Polygon) -> list[NDArray[np.float64]]:
    """Convex pieces of ``polygon`` as ``(K, 2)`` vertex arrays (the polygon itself if convex)."""
    if polygon.is_empty or polygon.area <= 0.0:
        return []
    hull_area = polygon.convex_hull.area
    if not polygon.interiors and hull_area - polygon.area <= _CONVEX_AREA_TOLERANCE * hull_area:
        return [np.asarray(polygon.exterior.coords, dtype=np.float64)[:-1]]
    triangles = shapely.get_parts(shapely.constrained_delaunay_triangles(polygon))
    return [
        np.asarray(tri.exterior.coords, dtype=np.float64)[:-1]
        for tri in triangles
        if tri.area > 0.0
    ]


def _add_obstacle(space: pymunk.Space, index: int, ob: DynamicObstacle) -> pymunk.Body:
    outline = shapely.Polygon(ob.shape)
    if not outline.is_valid:
        outline = shapely.make_valid(outline).convex_hull
    parts = convex_parts(outline)
    if not parts:
        raise ValueError(f"dynamic_obstacles[{index}] has a zero-area shape: {ob.shape.tolist()}")
    if ob.kind == "box":
        # Shape masses set the body's mass and moment (pymunk sums them over its shapes).
        body = pymunk.Body(body_type=pymunk.Body.DYNAMIC)
        collision_type = COLLISION_BOX
    else:
        body = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        collision_type = COLLISION_PERSON
    body.position = (ob.pose.x, ob.pose.y)
    body.angle = ob.pose.theta
    body.albot2d_kind = ob.kind
    body.albot2d_index = index
    shapes = []
    for part in parts:
        shape = pymunk.Poly(body, part.tolist(), radius=0.0)
        if ob.kind == "box":
            shape.mass = ob.mass_kg * shapely.Polygon(part).area / outline.area
        shape.collision_type = collision_type
        shapes.append(shape)
    space.add(body, *shapes)
    return body


def build_space(world: World, *, include_dynamic: bool = True) -> pymunk.Space:
    """A zero-gravity pymunk Space holding the world's walls, clutter and (optionally)
    its dynamic obstacles; see the module docstring for how shapes are marked."""
    space = pymunk.Space()
    space.gravity = (0.0, 0.0)
    static = space.static_body
    shapes: list[pymunk.Shape] = []
    for x1, y1, x2, y2 in world.walls.tolist():
        if x1 == x2 and y1 == y2:
            continue  # a zero-length wall has no surface to collide with
        seg = pymunk.Segment(static, (x1, y1), (x2, y2), 0.0)
        seg.collision_type = COLLISION_WALL
        shapes.append(seg)
    for polygon in world.clutter:
        for part in convex_parts(polygon):
            poly = pymunk.Poly(static, part.tolist(), radius=0.0)
            poly.collision_type = COLLISION_CLUTTER
            shapes.append(poly)
    space.add(*shapes)
    if include_dynamic:
        for index, ob in enumerate(world.dynamic_obstacles):
            _add_obstacle(space, index, ob)
    return space


def obstacle_bodies(space: pymunk.Space) -> dict[int, pymunk.Body]:
    """The dynamic-obstacle bodies of a space from ``build_space``, by obstacle index."""
    return {body.albot2d_index: body for body in space.bodies if hasattr(body, "albot2d_index")}
