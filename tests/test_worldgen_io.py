"""World JSON files: exact round trips, canonical bytes, and clear errors for bad files."""

from __future__ import annotations

import dataclasses
import json
import os
import re
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from albot2d.errors import InputError
from albot2d.geometry import Pose, polygon_ring_segments
from tests.strategies import examples
from worldgen.io import load, save, world_from_json, world_to_json
from worldgen.strategies import worlds as generated_worlds
from worldgen.world import DynamicObstacle, Roadmap, World

REPO = Path(__file__).resolve().parents[1]

any_float = st.floats(allow_nan=False, allow_infinity=False)
unit = st.floats(min_value=0.0, max_value=1.0)


def sample_world() -> World:
    """A small hand-built world exercising every field (also used from a subprocess)."""
    outer = shapely.box(0.0, 0.0, 20.0, 10.0)
    pillar = shapely.box(4.0, 4.0, 5.0, 5.0)
    table = shapely.Polygon([(6, 6), (8, 6), (8, 7), (7, 7), (7, 8), (6, 8)])
    walls = np.vstack(
        [polygon_ring_segments(outer.exterior.coords), [[10, 0, 10, 4], [10, 6, 10, 10]]]
    )
    nodes = np.array([[1, 1], [3, 2], [9, 5], [12, 5], [15, 8], [3, 8]], dtype=float) + 0.1
    return World(
        walls=walls,
        clutter=(pillar, table),
        free_space=outer.difference(pillar).difference(table),
        bounds=(0.0, 0.0, 20.0, 10.0),
        start=Pose(1.1, 1.1, 0.5),
        roadmap=Roadmap(nodes, np.array([[0, 1], [1, 2], [2, 3], [3, 4], [1, 5]])),
        kind="sample",
        seed=7,
        params={"width_m": 20.0, "n": 3, "name": "x", "sizes": [1.5, 2.5], "flag": True},
        features={
            "doorways": np.array([[10.0, 4.0, 10.0, 6.0]]),
            "room_ids": np.arange(3, dtype=np.int32),
            "rooms": [shapely.box(0, 0, 10, 10), shapely.box(10, 0, 20, 10)],
            "gate": Pose(10.0, 5.0, 0.0),
            "nothing": None,
        },
        dynamic_obstacles=(
            DynamicObstacle(
                "box",
                [[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]],
                Pose(2.0, 6.0, 0.3),
                mass_kg=7.0,
            ),
            DynamicObstacle(
                "person",
                [[-0.2, -0.2], [0.2, -0.2], [0.2, 0.2], [-0.2, 0.2]],
                Pose(13.0, 3.0, 0.0),
                path=[[13, 3], [17, 3]],
                speed_m_s=1.2,
            ),
        ),
        robot_radius_m=0.3,
    )


# ------------------------------------------------------------------ equality helpers


def _same_array(a: np.ndarray, b: np.ndarray) -> bool:
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def _same_polygon(a: Any, b: Any) -> bool:
    rings_a = [a.exterior, *a.interiors]
    rings_b = [b.exterior, *b.interiors]
    return len(rings_a) == len(rings_b) and all(
        _same_array(np.asarray(ra.coords), np.asarray(rb.coords))
        for ra, rb in zip(rings_a, rings_b, strict=True)
    )


def _same_value(a: Any, b: Any) -> bool:
    if isinstance(a, np.ndarray):
        return isinstance(b, np.ndarray) and _same_array(a, b)
    if isinstance(a, shapely.Polygon):
        return isinstance(b, shapely.Polygon) and _same_polygon(a, b)
    if isinstance(a, Pose):
        return isinstance(b, Pose) and _same_array(a.as_array(), b.as_array())
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(_same_value(a[k], b[k]) for k in a)
    if isinstance(a, list | tuple):
        return len(a) == len(b) and all(_same_value(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, float):
        return type(b) is float and np.float64(a).tobytes() == np.float64(b).tobytes()
    return type(a) is type(b) and a == b


def assert_same_world(a: World, b: World) -> None:
    assert _same_array(a.walls, b.walls)
    assert len(a.clutter) == len(b.clutter)
    assert all(_same_polygon(p, q) for p, q in zip(a.clutter, b.clutter, strict=True))
    assert _same_polygon(a.free_space, b.free_space)
    assert _same_value(a.bounds, b.bounds)
    assert _same_array(a.start.as_array(), b.start.as_array())
    assert _same_array(a.roadmap.nodes, b.roadmap.nodes)
    assert _same_array(a.roadmap.edges, b.roadmap.edges)
    assert (a.kind, a.seed, a.robot_radius_m) == (b.kind, b.seed, b.robot_radius_m)
    assert _same_value(dict(a.params), dict(b.params))
    assert _same_value(dict(a.features), dict(b.features))
    assert len(a.dynamic_obstacles) == len(b.dynamic_obstacles)
    for p, q in zip(a.dynamic_obstacles, b.dynamic_obstacles, strict=True):
        assert (p.kind, p.speed_m_s, p.mass_kg, p.pose) == (q.kind, q.speed_m_s, q.mass_kg, q.pose)
        assert _same_array(p.shape, q.shape) and _same_array(p.path, q.path)


# ------------------------------------------------------------------ strategies

json_keys = st.text(min_size=1, max_size=8).filter(lambda k: k != "__type__")
json_values = st.recursive(
    st.none() | st.booleans() | st.integers() | any_float | st.text(max_size=8),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(json_keys, inner, max_size=3),
    max_leaves=10,
)
feature_arrays = st.sampled_from(["float64", "float32", "int64", "int32", "uint8", "bool"]).flatmap(
    lambda dtype: hnp.arrays(
        dtype,
        hnp.array_shapes(min_dims=1, max_dims=3, min_side=0, max_side=4),
        elements={"allow_nan": False, "allow_infinity": False} if "float" in dtype else None,
    )
)


@st.composite
def worlds(draw: st.DrawFn) -> World:
    """Worlds with arbitrary finite float64 arrays (any magnitude, -0.0, subnormals)."""
    x0, y0 = draw(st.floats(-1e6, 1e6)), draw(st.floats(-1e6, 1e6))
    w, h = draw(st.floats(1e-2, 1e6)), draw(st.floats(1e-2, 1e6))
    outer = shapely.box(x0, y0, x0 + w, y0 + h)
    clutter = ()
    if draw(st.booleans()):  # a pillar in the right half, clear of the start
        fx0, fx1 = sorted(draw(st.lists(unit, min_size=2, max_size=2, unique=True)))
        fy0, fy1 = sorted(draw(st.lists(unit, min_size=2, max_size=2, unique=True)))
        pillar = shapely.box(
            x0 + w * (0.6 + 0.3 * fx0),
            y0 + h * (0.1 + 0.8 * fy0),
            x0 + w * (0.6 + 0.3 * fx1),
            y0 + h * (0.1 + 0.8 * fy1),
        )
        if pillar.area > 0 and pillar.is_valid:
            clutter = (pillar,)
    free = outer.difference(clutter[0]) if clutter else outer
    sx = min(x0 + 0.4 * w * draw(unit), x0 + w)
    sy = min(y0 + h * draw(unit), y0 + h)
    n_nodes = draw(st.integers(0, 6))
    pairs = st.tuples(st.integers(0, max(n_nodes - 1, 0)), st.integers(0, max(n_nodes - 1, 0)))
    edges = [(i, j) for i, j in draw(st.lists(pairs, max_size=6)) if i < j] if n_nodes else []
    obstacles = tuple(
        DynamicObstacle(
            draw(st.sampled_from(["box", "person"])),
            [[-0.5, -0.25], [0.5, -0.25], [0.5, 0.25], [-0.5, 0.25]],
            Pose(draw(any_float), draw(any_float), draw(any_float)),
            path=draw(hnp.arrays(np.float64, (draw(st.integers(0, 3)), 2), elements=any_float)),
            speed_m_s=draw(st.floats(0.0, 5.0)),
            mass_kg=draw(st.floats(0.1, 500.0)),
        )
        for _ in range(draw(st.integers(0, 2)))
    )
    return World(
        walls=draw(hnp.arrays(np.float64, (draw(st.integers(0, 12)), 4), elements=any_float)),
        clutter=clutter,
        free_space=free,
        bounds=(x0, y0, x0 + w, y0 + h),
        start=Pose(sx, sy, draw(any_float)),
        roadmap=Roadmap(
            draw(hnp.arrays(np.float64, (n_nodes, 2), elements=any_float)),
            np.array(edges, dtype=np.int64).reshape(-1, 2),
        ),
        kind=draw(st.text(min_size=1, max_size=12)),
        seed=draw(st.none() | st.integers(0, 2**64)),
        params=draw(st.dictionaries(json_keys, json_values, max_size=4)),
        features={
            **draw(st.dictionaries(json_keys, feature_arrays, max_size=3)),
            "poses": [Pose(draw(any_float), draw(any_float), draw(any_float))],
            "polygon": outer,
        },
        dynamic_obstacles=obstacles,
        robot_radius_m=draw(st.floats(1e-3, 10.0)),
    )


# ------------------------------------------------------------------ round trips


@given(worlds())
def test_json_round_trip_is_exact(world: World) -> None:
    text = world_to_json(world)
    again = world_from_json(text, validate=False)
    assert_same_world(world, again)
    assert world_to_json(again) == text


def test_save_load_file_round_trip(tmp_path: Path) -> None:
    world = sample_world()
    path = tmp_path / "world.json"
    save(world, path)
    loaded = load(path)
    assert_same_world(world, loaded)
    assert loaded.features["room_ids"].dtype == np.int32
    assert path.read_text() == world_to_json(loaded)
    assert [p.name for p in tmp_path.iterdir()] == ["world.json"]  # no temp files left


def _hand_and_generated_json() -> str:
    from worldgen.generate import generate

    generated = generate("rooms", seed=3, width_m=16.0, height_m=14.0, dynamic_obstacles=2)
    return world_to_json(sample_world()) + world_to_json(generated)


def test_bytes_identical_across_processes() -> None:
    code = (
        "import sys; from tests.test_worldgen_io import _hand_and_generated_json as f;"
        "sys.stdout.write(f())"
    )
    outputs = {
        subprocess.run(
            [sys.executable, "-c", code],
            cwd=REPO,
            capture_output=True,
            text=True,
            check=True,
            env={**os.environ, "PYTHONHASHSEED": hashseed},
        ).stdout
        for hashseed in ("1", "2")
    }
    assert outputs == {_hand_and_generated_json()}


def test_file_starts_with_format_and_version() -> None:
    lines = world_to_json(sample_world()).splitlines()
    assert lines[1:3] == ['"format":"albot2d-world",', '"version":1,']


# ------------------------------------------------------------------ bad files


def _doc() -> dict[str, Any]:
    return json.loads(world_to_json(sample_world()))


def _set(path: str, value: Any) -> Any:
    """A mutation of the sample document: set the dotted/indexed ``path`` to ``value``."""

    def mutate(doc: dict[str, Any]) -> None:
        keys = [int(k) if k.isdigit() else k for k in re.split(r"[.\[\]]+", path) if k]
        target = doc
        for key in keys[:-1]:
            target = target[key]
        if value is _DELETE:
            del target[keys[-1]]
        else:
            target[keys[-1]] = value

    return mutate


_DELETE = object()
BOW_TIE = {"exterior": [[0, 0], [10, 10], [10, 0], [0, 10]], "holes": []}

BAD_DOCS = [
    (_set("walls[3]", [1.0, 2.0, 3.0]), "walls[3] has 3 numbers, expected 4 [x1, y1, x2, y2]"),
    (_set("walls[1][2]", float("nan")), "walls[1] has a non-finite number"),
    (_set("walls[0][0]", "1.0"), "walls[0] must hold numbers, got '1.0'"),
    (_set("walls[0][0]", True), "walls[0] must hold numbers, got True"),
    (_set("walls", {"a": 1}), "walls must be a list of [x1, y1, x2, y2] rows, got an object"),
    (_set("version", 2), "version is 2; this albot2d reads version 1"),
    (_set("version", "1"), "version is '1'"),
    (_set("format", "other"), "format is 'other', expected 'albot2d-world'"),
    (_set("format", _DELETE), "not an albot2d world file"),
    (_set("walls", _DELETE), "the world is missing walls"),
    (_set("wallz", []), "the world has unknown key(s) wallz"),
    (
        _set("free_space", [BOW_TIE]),
        "free_space must be one polygon (exterior + holes), got a list",
    ),
    (_set("free_space", BOW_TIE), "free_space is not one valid polygon: Self-intersection"),
    (_set("free_space.exterior", [[0, 0], [1, 1]]), "free_space.exterior needs at least 3"),
    (_set("clutter[1].holes", 5), "clutter[1].holes must be a list of rings, got 5"),
    (_set("roadmap.edges[2]", [0, 9]), "roadmap.edges[2] node index 9 out of range (roadmap has 6"),
    (_set("roadmap.edges[0]", [1, 1]), "roadmap.edges[0] joins node 1 to itself"),
    (_set("roadmap.edges[0]", [0, 1.0]), "roadmap.edges[0] must hold integer node indices"),
    (_set("start", [1.0, 2.0]), "start has 2 numbers, expected 3 [x, y, theta]"),
    (_set("start", [15.0, -3.0, 0.0]), "start (15.0, -3.0) is outside free_space"),
    (_set("start[2]", float("inf")), "start[2] must be finite, got inf"),
    (_set("bounds", [0, 0, -1, 10]), "need xmin < xmax and ymin < ymax"),
    (_set("robot_radius_m", -0.1), "robot_radius_m must be > 0, got -0.1"),
    (_set("seed", -3), "seed must be a non-negative integer or null, got -3"),
    (_set("kind", ""), "kind must be a non-empty string"),
    (_set("dynamic_obstacles[0].kind", "cat"), "dynamic_obstacles[0].kind must be one of"),
    (_set("dynamic_obstacles[1].mass_kg", 0), "dynamic_obstacles[1].mass_kg must be > 0, got 0.0"),
    (_set("dynamic_obstacles[1].speed_m_s", _DELETE), "dynamic_obstacles[1] is missing speed_m_s"),
    (_set("params.width_m", float("nan")), "params.width_m must be finite, got nan"),
    (_set("params", [1]), "params must be an object, got a list"),
    (_set("features.doorways.shape", [2, 4]), "features.doorways.data has 4 items, shape [2, 4]"),
    (_set("features.doorways.dtype", "object"), "features.doorways.dtype must be one of"),
    (_set("features.room_ids.data[0]", 1.5), "features.room_ids.data[0] is 1.5, not a int32"),
    (_set("features.gate.__type__", "Frob"), "features.gate has unknown __type__ 'Frob'"),
]


@pytest.mark.parametrize(("mutate", "message"), BAD_DOCS)
def test_bad_document_names_file_field_and_value(mutate: Any, message: str, tmp_path: Path):
    doc = _doc()
    mutate(doc)
    path = tmp_path / "world.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(InputError) as info:
        load(path)
    assert str(info.value).startswith(f"{path}: ")
    assert message in str(info.value)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (
            '{"format": "albot2d-world",\n  "version": 1,,}',
            "not valid JSON: Expecting property name enclosed in double quotes at line 2 column 16",
        ),
        ("", "not valid JSON: Expecting value at line 1 column 1"),
        ("[1, 2]", "expected a JSON object, got a list"),
        ('{"format": 1, "format": 2}', "duplicate key 'format'"),
    ],
)
def test_bad_json_text(text: str, message: str) -> None:
    with pytest.raises(InputError, match=re.escape(f"w.json: {message}")):
        world_from_json(text, source="w.json")


def test_non_utf8_file(tmp_path: Path) -> None:
    path = tmp_path / "world.json"
    path.write_bytes(b'{"format": "\xff"}')
    with pytest.raises(InputError, match="not UTF-8 text"):
        load(path)


def test_missing_file_is_an_os_error(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError):
        load(tmp_path / "nope.json")


def test_saving_a_non_finite_world_writes_nothing(tmp_path: Path) -> None:
    world = sample_world()
    walls = world.walls.copy()
    walls[2, 1] = np.nan
    bad = dataclasses.replace(world, walls=walls)
    with pytest.raises(InputError, match=re.escape("walls[2, 1] is nan")):
        save(bad, tmp_path / "world.json")
    assert list(tmp_path.iterdir()) == []


@settings(max_examples=examples(10))
@given(generated_worlds(max_size_m=30.0, dynamic=True))
def test_generated_worlds_round_trip_exactly(world: World) -> None:
    text = world_to_json(world)
    again = world_from_json(text, source="generated.json")
    assert_same_world(world, again)
    assert world_to_json(again) == text
