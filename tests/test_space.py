"""build_space: a real pymunk space whose shapes sit exactly where the world's surfaces are."""

from __future__ import annotations

import math

import numpy as np
import pymunk
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.strategies import examples
from tests.test_worldgen_io import sample_world
from worldgen.space import (
    COLLISION_BOX,
    COLLISION_CLUTTER,
    COLLISION_PERSON,
    COLLISION_WALL,
    build_space,
    convex_parts,
    obstacle_bodies,
)
from worldgen.strategies import worlds as generated_worlds

ALL = pymunk.ShapeFilter()
RAY_LENGTH_M = 100.0


def _shapes(space: pymunk.Space, collision_type: int) -> list[pymunk.Shape]:
    return [s for s in space.shapes if s.collision_type == collision_type]


def _ray_distance(origin: np.ndarray, angle: float, segments: np.ndarray) -> float:
    """Distance to the first segment hit by a ray (plain numpy reference)."""
    d = np.array([math.cos(angle), math.sin(angle)])
    a, b = segments[:, :2], segments[:, 2:]
    e = b - a
    denom = d[0] * e[:, 1] - d[1] * e[:, 0]
    w = a - origin
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        t = (w[:, 0] * e[:, 1] - w[:, 1] * e[:, 0]) / denom
        s = (w[:, 0] * d[1] - w[:, 1] * d[0]) / denom
    hit = (np.abs(denom) > 1e-12) & (t >= 0) & (s >= 0) & (s <= 1)
    return float(t[hit].min()) if hit.any() else math.inf


def test_static_shapes_match_walls_and_clutter() -> None:
    world = sample_world()
    space = build_space(world)
    walls = _shapes(space, COLLISION_WALL)
    assert len(walls) == len(world.walls)
    assert all(s.body is space.static_body and s.radius == 0.0 for s in walls)
    got = sorted((*s.a, *s.b) for s in walls)
    assert got == sorted(map(tuple, world.walls.tolist()))
    clutter = _shapes(space, COLLISION_CLUTTER)
    # The box pillar stays one polygon; the L-shaped table is split into convex pieces.
    assert len(clutter) == 1 + len(convex_parts(world.clutter[1]))
    assert sum(s.area for s in clutter) == pytest.approx(sum(p.area for p in world.clutter))
    assert space.gravity == (0.0, 0.0)


@given(st.floats(-math.pi, math.pi), st.sampled_from([(1.1, 1.1), (9.0, 5.0), (15.0, 2.0)]))
def test_segment_queries_hit_where_the_world_surfaces_are(angle: float, origin: tuple) -> None:
    world = sample_world()
    space = build_space(world, include_dynamic=False)
    o = np.asarray(origin)
    end = o + RAY_LENGTH_M * np.array([math.cos(angle), math.sin(angle)])
    hit = space.segment_query_first(tuple(o), tuple(end), 0.0, ALL)
    expected = _ray_distance(o, angle, world.obstacle_segments)
    assert hit is not None  # the world is closed, so every ray hits something
    assert hit.shape.collision_type in (COLLISION_WALL, COLLISION_CLUTTER)
    assert math.dist(origin, hit.point) == pytest.approx(expected, abs=1e-9)


def test_point_query_finds_walls_and_clutter() -> None:
    world = sample_world()
    space = build_space(world)
    for x1, y1, x2, y2 in world.walls:
        mid = ((x1 + x2) / 2, (y1 + y2) / 2)
        info = space.point_query_nearest(mid, 1e-6, ALL)
        assert info is not None and info.shape.collision_type == COLLISION_WALL
    inside_table = space.point_query((6.3, 7.6), 0.0, ALL)
    assert [q.shape.collision_type for q in inside_table] == [COLLISION_CLUTTER]
    assert space.point_query((3.0, 3.0), 0.0, ALL) == []  # open floor


def test_dynamic_obstacles_are_marked_bodies() -> None:
    world = sample_world()
    space = build_space(world)
    bodies = obstacle_bodies(space)
    assert sorted(bodies) == [0, 1]
    box, person = bodies[0], bodies[1]
    assert box.body_type == pymunk.Body.DYNAMIC and box.albot2d_kind == "box"
    assert box.mass == pytest.approx(world.dynamic_obstacles[0].mass_kg)
    assert tuple(box.position) == (2.0, 6.0) and box.angle == 0.3
    assert [s.collision_type for s in box.shapes] == [COLLISION_BOX]
    assert person.body_type == pymunk.Body.KINEMATIC and person.albot2d_kind == "person"
    assert {s.collision_type for s in person.shapes} == {COLLISION_PERSON}
    assert obstacle_bodies(build_space(world, include_dynamic=False)) == {}
    assert len(build_space(world, include_dynamic=False).shapes) == len(space.shapes) - 2


def test_pushed_box_stops_at_the_wall() -> None:
    world = sample_world()
    space = build_space(world)
    box = obstacle_bodies(space)[0]
    box.velocity = (-3.0, 0.0)  # towards the wall at x = 0
    for _ in range(240):
        space.step(1.0 / 60.0)
    corners = [box.local_to_world(v) for v in next(iter(box.shapes)).get_vertices()]
    assert min(c.x for c in corners) > -0.05  # collision slop only, never through the wall
    assert box.position.x < 1.0  # it did travel to the wall


def test_convex_parts_cover_a_polygon_with_a_hole() -> None:
    ring = shapely.box(0, 0, 4, 4).difference(shapely.box(1, 1, 2, 2))
    parts = convex_parts(ring)
    assert sum(shapely.Polygon(p).area for p in parts) == pytest.approx(ring.area)
    assert shapely.union_all([shapely.Polygon(p) for p in parts]).equals(ring)
    assert convex_parts(shapely.Polygon()) == []


@settings(max_examples=examples(10))
@given(generated_worlds(max_size_m=30.0, dynamic=True), st.floats(-math.pi, math.pi))
def test_generated_worlds_give_matching_spaces(world, angle: float) -> None:
    space = build_space(world)
    assert len(_shapes(space, COLLISION_WALL)) == len(world.walls)
    clutter_area = sum(s.area for s in _shapes(space, COLLISION_CLUTTER))
    assert clutter_area == pytest.approx(sum(p.area for p in world.clutter), rel=1e-9, abs=1e-9)
    assert len(obstacle_bodies(space)) == len(world.dynamic_obstacles)
    static = build_space(world, include_dynamic=False)
    origin = world.start.position
    end = origin + RAY_LENGTH_M * np.array([math.cos(angle), math.sin(angle)])
    hit = static.segment_query_first(tuple(origin), tuple(end), 0.0, ALL)
    expected = _ray_distance(origin, angle, world.obstacle_segments)
    assert hit is not None and math.dist(origin, hit.point) == pytest.approx(expected, abs=1e-9)
