"""Properties every generated world has, over random kinds, seeds, sizes and parameters."""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import shapely
from hypothesis import given

from worldgen import generate, kind_names
from worldgen.strategies import worlds
from worldgen.world import World

CLEARANCE_TOL = 1e-9

KINDS = kind_names()


def node_clearance(world: World) -> float:
    return world.robot_radius_m + float(world.params["clearance_margin_m"])


@given(worlds(max_size_m=35.0, dynamic=True))
def test_generated_world_invariants(world):
    fs = world.free_space
    assert fs.geom_type == "Polygon" and fs.is_valid and fs.area > 0
    # walls: finite, positive length, on the free-space side of the bounds
    w = world.walls
    assert w.dtype == np.float64 and w.ndim == 2 and w.shape[1] == 4 and len(w) >= 4
    assert np.isfinite(w).all()
    assert (np.hypot(w[:, 2] - w[:, 0], w[:, 3] - w[:, 1]) > 0).all()
    x0, y0, x1, y1 = world.bounds
    assert (w[:, [0, 2]] >= x0 - 1e-9).all() and (w[:, [0, 2]] <= x1 + 1e-9).all()
    assert (w[:, [1, 3]] >= y0 - 1e-9).all() and (w[:, [1, 3]] <= y1 + 1e-9).all()
    # clutter is furniture-sized and was subtracted from free space
    for c in world.clutter:
        assert c.is_valid and 0.0 < c.area < 12.0
        assert not fs.contains(c.representative_point())
    # start pose and every roadmap node keep robot radius + margin from every obstacle
    boundary = fs.boundary
    need = node_clearance(world) - CLEARANCE_TOL
    start = shapely.Point(world.start.x, world.start.y)
    assert fs.contains(start) and boundary.distance(start) >= need
    nodes = shapely.points(world.roadmap.nodes)
    assert shapely.contains(fs, nodes).all()
    assert shapely.distance(nodes, boundary).min() >= need
    # every roadmap edge is collision-free for the robot's disc
    e = world.roadmap.edges
    assert len(e) > 0 and (e[:, 0] < e[:, 1]).all()
    lines = shapely.linestrings(world.roadmap.nodes[e])
    assert shapely.covers(fs, lines).all()
    assert shapely.distance(lines, boundary).min() >= world.robot_radius_m - CLEARANCE_TOL
    # one connected roadmap
    import networkx as nx

    assert nx.is_connected(world.roadmap.graph)
    # features survive JSON
    json.dumps(world.features)
    assert world.features["loops"] == len(e) - len(world.roadmap.nodes) + 1


@given(worlds(max_size_m=30.0, dynamic=True))
def test_dynamic_obstacles(world):
    requested = int(world.params["dynamic_obstacles"])
    assert len(world.dynamic_obstacles) <= requested
    persons = [o for o in world.dynamic_obstacles if o.kind == "person"]
    assert len(persons) <= (requested + 1) // 2
    for o in world.dynamic_obstacles:
        assert world.free_space.contains(shapely.Point(o.pose.x, o.pose.y))
        if o.kind == "person":
            assert len(o.path) >= 2 and o.speed_m_s > 0
            legs = shapely.linestrings(np.stack([o.path[:-1], o.path[1:]], axis=1))
            assert shapely.covers(world.free_space, legs).all()
        else:
            box = shapely.Polygon(o.shape + np.array([o.pose.x, o.pose.y]))
            road = shapely.MultiLineString(list(world.roadmap.nodes[world.roadmap.edges]))
            assert box.distance(road) > world.robot_radius_m


def test_dynamic_obstacle_counts_in_a_default_office():
    world = generate("office", seed=4, dynamic_obstacles=5)
    kinds = [o.kind for o in world.dynamic_obstacles]
    assert kinds == ["person", "box", "person", "box", "person"]
    assert world.features["dynamic_obstacles"] == 5


def test_same_seed_same_world_and_different_seed_differs():
    for kind in KINDS:
        a, b = generate(kind, seed=7), generate(kind, seed=7)
        assert a.walls.tobytes() == b.walls.tobytes()
        assert a.roadmap.nodes.tobytes() == b.roadmap.nodes.tobytes()
        assert a.roadmap.edges.tobytes() == b.roadmap.edges.tobytes()
        assert a.start == b.start
        assert [c.wkb for c in a.clutter] == [c.wkb for c in b.clutter]
        assert json.dumps(a.features) == json.dumps(b.features)
        c = generate(kind, seed=8)
        assert a.walls.tobytes() != c.walls.tobytes()


def world_digest(kind):
    """SHA-256 over every array, geometry and feature of the kind's seed-11 world."""
    w = generate(
        kind,
        seed=11,
        width_m=30.0 if kind != "mixed" else 40.0,
        height_m=32.0,
        dynamic_obstacles=2,
    )
    h = hashlib.sha256()
    for arr in (w.walls, w.roadmap.nodes, w.roadmap.edges):
        h.update(arr.tobytes())
    for c in w.clutter:
        h.update(c.wkb)
    h.update(repr(w.start).encode())
    h.update(json.dumps(w.features, sort_keys=True).encode())
    for o in w.dynamic_obstacles:
        h.update(o.path.tobytes() + o.shape.tobytes() + repr(o.pose).encode())
    return h.hexdigest()


DIGEST_SCRIPT = """
import sys
from tests.test_worldgen_generate import world_digest
for kind in sys.argv[1:]:
    print(kind, world_digest(kind))
"""


def test_determinism_across_processes():
    result = subprocess.run(
        [sys.executable, "-c", DIGEST_SCRIPT, *KINDS],
        capture_output=True,
        text=True,
        check=True,
        env={**os.environ, "PYTHONHASHSEED": "123"},
        cwd=Path(__file__).resolve().parents[1],
    )
    theirs = dict(line.split() for line in result.stdout.strip().splitlines())
    assert theirs == {kind: world_digest(kind) for kind in KINDS}


@pytest.mark.parametrize("kind", KINDS)
def test_default_sizes(kind):
    world = generate(kind, seed=0)
    expected = {"office": (60.0, 40.0), "mixed": (60.0, 40.0), "fig6": (42.0, 30.0)}.get(
        kind, (40.0, 40.0)
    )
    assert (world.width_m, world.height_m) == expected
    assert world.kind == kind and world.seed == 0
    assert world.params["width_m"] == expected[0]
