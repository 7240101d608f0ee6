"""make_world and build_roadmap on hand-made polygons (the path HouseExpo import takes)."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from hypothesis import example, given
from hypothesis import strategies as st

from albot2d.errors import InputError
from albot2d.geometry import Pose
from worldgen.assemble import make_world
from worldgen.roadmap import build_roadmap, count_loops
from worldgen.roadmap_links import roadmap_from_links

RADIUS = 0.25
MARGIN = 0.10


def ring_with_room() -> shapely.Polygon:
    """A 20x12 m corridor ring around a solid block, with a room off the top corridor."""
    outer = shapely.box(0, 0, 20, 12)
    block = shapely.box(3, 3, 17, 9)
    room = shapely.box(8, 12.1, 12, 16)
    door = shapely.box(9.5, 12.0, 10.5, 12.1)
    return shapely.union_all([outer.difference(block), room, door])


def assert_roadmap_safe(world, radius=RADIUS, margin=MARGIN):
    boundary = world.free_space.boundary
    nodes = shapely.points(world.roadmap.nodes)
    assert shapely.contains(world.free_space, nodes).all()
    assert shapely.distance(nodes, boundary).min() >= radius + margin - 1e-9
    legs = world.roadmap.nodes[world.roadmap.edges].reshape(-1, 4)
    if len(legs) == 0:
        return
    lines = shapely.linestrings(legs.reshape(-1, 2, 2))
    assert shapely.covers(world.free_space, lines).all()
    assert shapely.distance(lines, boundary).min() >= radius - 1e-9


def test_make_world_on_ring_with_room_and_clutter():
    clutter = [shapely.box(18.2, 5, 18.8, 5.6), shapely.Point(1.5, 6).buffer(0.3)]
    world = make_world(ring_with_room(), clutter=clutter, seed=3)
    assert world.free_space.geom_type == "Polygon"
    assert len(world.clutter) == 2
    # clutter is subtracted: its centre is not free
    assert not world.free_space.contains(shapely.Point(18.5, 5.3))
    # walls are the structural boundary: exterior ring + the block's ring, no clutter outlines
    assert world.walls.dtype == np.float64 and world.walls.shape[1] == 4
    lengths = np.hypot(world.walls[:, 2] - world.walls[:, 0], world.walls[:, 3] - world.walls[:, 1])
    assert (lengths > 0).all()
    assert np.isclose(
        lengths.sum(), 2 * (20 + 12) + 2 * (14 + 6) + 2 * (4 + 3.9) - 2 * 1 + 2 * 0.1, atol=1e-6
    )
    assert len(world.obstacle_segments) == len(world.walls) + len(world.clutter_segments)
    assert world.bounds == (0.0, 0.0, 20.0, 16.0)
    assert world.features["loops"] >= 1
    assert_roadmap_safe(world)
    # the roadmap reaches into the room through the 1 m door
    assert (world.roadmap.nodes[:, 1] > 12.5).any()
    # start is a roadmap node, heading along one of its edges
    start = np.array([world.start.x, world.start.y])
    i = np.flatnonzero((world.roadmap.nodes == start).all(axis=1))
    assert len(i) == 1
    nbrs = [j for e in world.roadmap.edges for j in e if i[0] in e and j != i[0]]
    headings = [np.arctan2(*(world.roadmap.nodes[j] - start)[::-1]) for j in nbrs]
    assert np.isclose(headings, world.start.theta).any()


def test_make_world_is_deterministic_without_rng():
    a = make_world(ring_with_room())
    b = make_world(ring_with_room())
    assert a.walls.tobytes() == b.walls.tobytes()
    assert a.roadmap.nodes.tobytes() == b.roadmap.nodes.tobytes()
    assert a.roadmap.edges.tobytes() == b.roadmap.edges.tobytes()
    assert a.start == b.start


def test_given_start_is_linked_into_the_roadmap():
    start = Pose(10.0, 14.0, 1.0)
    world = make_world(ring_with_room(), start=start)
    assert world.start == start
    assert ((world.roadmap.nodes == [10.0, 14.0]).all(axis=1)).any()
    with pytest.raises(InputError, match="clearance"):
        make_world(ring_with_room(), start=Pose(0.1, 0.1, 0.0))


def test_disconnected_free_space():
    two = shapely.union_all([shapely.box(0, 0, 10, 10), shapely.box(20, 0, 25, 5)])
    world = make_world(two)
    assert world.free_space.area == pytest.approx(100.0)
    with pytest.raises(InputError, match="2 disconnected parts"):
        make_world(two, keep_largest=False)


def test_invalid_and_too_small_polygons():
    bowtie = shapely.Polygon([(0, 0), (10, 10), (10, 0), (0, 10)])  # self-intersecting
    world = make_world(bowtie)
    assert world.free_space.is_valid
    with pytest.raises(InputError, match="clearance"):
        make_world(shapely.box(0, 0, 0.5, 5))
    with pytest.raises(InputError, match="no polygon"):
        make_world(shapely.Polygon())


def test_annulus_roadmap_is_a_cycle():
    ring = shapely.Point(0, 0).buffer(10).difference(shapely.Point(0, 0).buffer(7))
    roadmap = build_roadmap(ring, clearance_m=0.35, robot_radius_m=0.25)
    assert count_loops(roadmap) == 1


@example(w=2.0, h=3.0, holes=[(0.5, 0.0, 2.5)])  # leaves room for one node, no edges
@given(
    w=st.floats(2.0, 30.0),
    h=st.floats(2.0, 30.0),
    holes=st.lists(st.tuples(st.floats(0, 1), st.floats(0, 1), st.floats(0.1, 3)), max_size=6),
)
def test_roadmap_safe_on_random_rectangles_with_pillars(w, h, holes):
    pillars = [
        shapely.Point(round(fx * w, 3), round(fy * h, 3)).buffer(r, quad_segs=2)
        for fx, fy, r in holes
    ]
    try:
        world = make_world(shapely.box(0, 0, w, h), clutter=pillars)
    except InputError as err:
        assert "clearance" in str(err) or "no polygon" in str(err)
        return
    assert world.free_space.geom_type == "Polygon"
    assert_roadmap_safe(world)


def test_planned_links_keep_only_what_is_safe():
    # a U: two 2 m wide arms joined at the bottom, a wall between the arms
    u = shapely.box(0, 0, 6, 8).difference(shapely.box(2, 2, 4, 8))
    links = np.array(
        [
            [1, 1, 1, 7],  # up the left arm: safe, split into <= 3 m pieces
            [1, 1, 5, 1],  # along the bottom: safe
            [5, 1, 5, 7],  # up the right arm: safe
            [1, 7, 5, 7],  # straight through the wall between the arms: dropped
            [1, 4, 1.2, 4],  # a short spur inside the left arm: kept
            [5, 4, 5.8, 4],  # ends 0.2 m from the outer wall: node unsafe, dropped
        ],
        dtype=float,
    )
    roadmap = roadmap_from_links(u, links, clearance_m=0.35, robot_radius_m=0.25)
    nodes = roadmap.nodes
    assert not (nodes[:, 0] > 5.5).any()
    seg = nodes[roadmap.edges]
    crosses = (seg[:, 0, 1] > 2) & (seg[:, 1, 1] > 2) & (seg[:, 0, 0] < 2) & (seg[:, 1, 0] > 4)
    assert not crosses.any()
    length = np.hypot(*(seg[:, 1] - seg[:, 0]).T)
    assert length.max() <= 3.0 + 1e-9
    assert np.isclose(length.sum(), 6 + 4 + 6 + 0.2)
    world = make_world(u, links=links)
    assert_roadmap_safe(world)
