"""HouseExpo import: real plans become Worlds whose walls are exactly the plan's edges."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import networkx as nx
import numpy as np
import pytest
import shapely

from albot2d.errors import InputError
from albot2d.seeding import make_rng
from worldgen.houseexpo import from_houseexpo, read_houseexpo
from worldgen.io import world_from_json, world_to_json
from worldgen.tours import make_tour

# The five plans documented in ../shared/data/SOURCES.md section 4.
PLANS = [
    "0a1b29dba355df2ab02630133187bfab",
    "0004d52d1aeeb8ae6de39d6bd993e992",
    "1f99717550c31ae321ca2313edceedcc",
    "3a977bda0c177c31c8c64e8076562d5a",
    "75555d2f4a69546c4c811f85bac572d9",
]

# A small L-shaped two-room house in HouseExpo form, for tests that need no shared data.
L_HOUSE: dict[str, Any] = {
    "id": "l-house",
    "room_num": 2,
    "bbox": {"min": [0.0, 0.0], "max": [8.0, 8.0]},
    "verts": [[0, 0], [8, 0], [8, 3], [3, 3], [3, 8], [0, 8]],
    "room_category": {"Kitchen": [[0, 0, 8, 3]], "Bedroom": [[0, 3, 3, 8]]},
}


def _undirected(segments: np.ndarray) -> set[tuple[float, ...]]:
    """Segments as a set, each with its endpoints in a fixed order (orientation-free)."""
    out = set()
    for x1, y1, x2, y2 in segments.tolist():
        a, b = sorted([(x1, y1), (x2, y2)])
        if a != b:
            out.add((*a, *b))
    return out


def _plan_edges(verts: np.ndarray) -> np.ndarray:
    return np.hstack([verts, np.roll(verts, -1, axis=0)])


def _write(tmp_path: Path, doc: Any, name: str = "plan.json") -> Path:
    path = tmp_path / name
    path.write_text(doc if isinstance(doc, str) else json.dumps(doc))
    return path


@pytest.mark.parametrize("plan_id", PLANS)
def test_real_plans_import(shared_data: Path, plan_id: str) -> None:
    path = shared_data / "floorplans" / f"{plan_id}.json"
    plan = read_houseexpo(path)
    world = from_houseexpo(path)
    assert world.kind == "houseexpo"
    assert world.params == {"source": path.name, "id": plan_id}
    # Walls are the plan polygon's edges, unsimplified (orientation aside).
    assert _undirected(world.walls) == _undirected(_plan_edges(plan["verts"]))
    assert len(world.walls) == len(plan["verts"])
    # Free space is the plan polygon itself: one connected polygon.
    assert isinstance(world.free_space, shapely.Polygon) and world.free_space.is_valid
    assert world.free_space.equals(shapely.Polygon(plan["verts"]))
    assert world.bounds == pytest.approx(tuple(plan["bbox"]))
    # The roadmap is a non-empty connected graph in free space, and holds the start.
    assert len(world.roadmap.nodes) > 1 and len(world.roadmap.edges) > 0
    assert nx.is_connected(world.roadmap.graph)
    assert shapely.contains_xy(world.free_space, *world.roadmap.nodes.T).all()
    assert world.roadmap.nodes[world.roadmap.nearest_node(world.start.position)] == pytest.approx(
        world.start.position
    )
    features = world.features
    assert len(features["room_categories"]) == len(features["room_bboxes"]) > 0
    assert set(features["room_categories"]) == set(json.loads(path.read_text())["room_category"])


def test_real_plan_survives_a_json_round_trip(shared_data: Path) -> None:
    world = from_houseexpo(shared_data / "floorplans" / f"{PLANS[0]}.json")
    text = world_to_json(world)
    again = world_from_json(text)
    assert world_to_json(again) == text
    assert np.array_equal(again.walls, world.walls)


def test_a_tour_can_be_planned_on_a_real_plan(shared_data: Path) -> None:
    pytest.importorskip("worldgen.tours", reason="tour planner not built yet")
    world = from_houseexpo(shared_data / "floorplans" / f"{PLANS[3]}.json")
    tour = make_tour(world, make_rng(0), kind="loop", min_length_m=20.0)
    assert tour.length_m >= 20.0
    assert tour.waypoints[0] == pytest.approx(world.start.position)


def test_synthetic_plan_imports_without_shared_data(tmp_path: Path) -> None:
    world = from_houseexpo(_write(tmp_path, L_HOUSE))
    assert _undirected(world.walls) == _undirected(_plan_edges(np.array(L_HOUSE["verts"], float)))
    assert world.free_space.area == pytest.approx(8 * 3 + 3 * 5)
    assert world.features["room_categories"] == ["Bedroom", "Kitchen"]  # sorted by category
    np.testing.assert_array_equal(world.features["room_bboxes"], [[0, 3, 3, 8], [0, 0, 8, 3]])
    assert nx.is_connected(world.roadmap.graph)
    # The same file always gives the same world; a seed only moves the start.
    assert world_to_json(from_houseexpo(tmp_path / "plan.json")) == world_to_json(world)
    seeded = from_houseexpo(tmp_path / "plan.json", seed=5)
    assert seeded.seed == 5 and np.array_equal(seeded.walls, world.walls)


def _with(**changes: Any) -> dict[str, Any]:
    doc = json.loads(json.dumps(L_HOUSE))
    for key, value in changes.items():
        if value is None:
            del doc[key]
        else:
            doc[key] = value
    return doc


@pytest.mark.parametrize(
    ("doc", "message"),
    [
        (_with(verts=None), "missing HouseExpo field(s) verts"),
        (_with(id=None), "missing HouseExpo field(s) id"),
        (
            _with(verts=[[0, 0], [1, 0], [1, 1, 2]]),
            "verts[2] must be 2 finite numbers, got [1, 1, 2]",
        ),
        (_with(verts=[[0, 0], [1, 0], ["1", 1]]), "verts[2] must be 2 finite numbers"),
        (_with(verts=[[0, 0], [1, 0], [0, 0]]), "verts needs at least 3 distinct points"),
        (_with(verts="square"), "verts must be a list of [x, y] points"),
        (_with(id=7), "id must be a non-empty string, got 7"),
        (_with(room_num=-1), "room_num must be a non-negative integer, got -1"),
        (_with(room_category={"Kitchen": [[0, 0, 1]]}), "room_category.Kitchen[0] must be 4"),
        (_with(room_category={"Kitchen": [[5, 0, 1, 1]]}), "needs x1 <= x2 and y1 <= y2"),
        (_with(bbox={"min": [0, 0]}), "bbox must be"),
        ("[1, 2]", "expected a HouseExpo JSON object"),
        ('{"verts": [[0, 0],\n [1, 0]', "not valid JSON: Expecting ',' delimiter at line 2"),
        (_with(verts=[[0, 0], [1, 0], [0.5, 0.01]]), "no place with clearance"),
    ],
)
def test_bad_plans_name_file_field_and_value(tmp_path: Path, doc: Any, message: str) -> None:
    path = _write(tmp_path, doc)
    with pytest.raises(InputError) as info:
        from_houseexpo(path)
    assert str(info.value).startswith(f"{path}: ")
    assert message in str(info.value)


def test_non_finite_vertex_is_rejected(tmp_path: Path) -> None:
    path = _write(tmp_path, '{"id": "x", "verts": [[0, 0], [1, NaN], [1, 1]]}')
    with pytest.raises(InputError, match=r"verts\[1\] must be 2 finite numbers, got \[1, nan\]"):
        from_houseexpo(path)


def test_missing_plan_file_is_an_os_error(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError):
        from_houseexpo(tmp_path / "nope.json")
