"""Bad world files, HouseExpo plans and reports.

Part of the bad-input corpus: every case starts from a valid input (``tests/bad_inputs.py``)
and breaks one thing; the real CLI must exit 2 with one stderr line naming the place and the
value, no traceback and no output (``tests/bad_input_checks.py``).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from tests import bad_inputs as bi
from tests.bad_input_checks import (
    nothing_written,
    obstacle,
    refused,
    set_field,
)
from worldgen.io import world_from_json

ROOT = Path(__file__).resolve().parents[1]

# ------------------------------------------------------------------ world files


def _scale_walls(doc: dict[str, Any]) -> None:
    doc["walls"] = [[v * 1e15 for v in wall] for wall in doc["walls"]]


def _crossing_edge(doc: dict[str, Any]) -> None:
    doc["roadmap"]["edges"].append(bi.crossing_edge(doc))


def _tiny_free_space(doc: dict[str, Any]) -> None:
    x, y, _ = doc["start"]
    doc["free_space"] = {
        "exterior": [
            [x - 0.2, y - 0.2],
            [x + 0.2, y - 0.2],
            [x + 0.2, y + 0.2],
            [x - 0.2, y + 0.2],
        ],
        "holes": [],
    }


def _boxed_in(doc: dict[str, Any]) -> None:
    x, y, _ = doc["start"]
    d = 0.4
    corners = [(x - d, y - d), (x + d, y - d), (x + d, y + d), (x - d, y + d)]
    doc["walls"] += [[*corners[k], *corners[(k + 1) % 4]] for k in range(4)]


def _start_on_wall(doc: dict[str, Any]) -> None:
    x1, y1, x2, y2 = doc["walls"][0]
    doc["start"] = [(x1 + x2) / 2, (y1 + y2) / 2, 0.0]


def _near_wall_start(doc: dict[str, Any]) -> None:
    doc["robot_radius_m"] = 4.0  # the start's clearance in a 12 m world of rooms is less


# (id, mutation of the valid document, texts the error line must hold)
WORLD_CASES: list[tuple[str, Callable[[dict[str, Any]], None], tuple[str, ...]]] = [
    ("wall-1e308", set_field("walls.0.0", 1e308), ("walls[0]", "1e+308", "limit")),
    ("wall-huge-int", set_field("walls.0.0", 10**400), ("walls[0]", "401 digits")),
    ("wall-string", set_field("walls.0.1", "nan"), ("walls[0]", "'nan'")),
    ("wall-3-numbers", set_field("walls.0", [1.0, 2.0, 3.0]), ("walls[0]", "3 numbers")),
    ("no-walls", set_field("walls", []), ("walls", "positive length", "0 walls")),
    ("zero-length-walls", set_field("walls", [[1.0, 1.0, 1.0, 1.0]]), ("walls", "positive length")),
    ("walls-scaled-1e15", _scale_walls, ("walls[", "limit")),
    ("walls-not-a-list", set_field("walls", {"a": 1}), ("walls", "an object")),
    ("start-in-wall", _start_on_wall, ("start (",)),
    ("start-outside-bounds", set_field("start", [-50.0, 5.0, 0.0]), ("start (-50.0, 5.0)",)),
    ("start-x-1e308", set_field("start.0", 1e308), ("start[0]", "1e+308")),
    ("start-theta-nan", set_field("start.2", float("nan")), ("start[2]", "finite", "nan")),
    ("start-two-numbers", set_field("start", [1.0, 2.0]), ("start", "2 numbers")),
    ("start-disc-overlaps-wall", _near_wall_start, ("start (", "radius 4.0 m")),
    ("boxed-in", _boxed_in, ("roadmap",)),
    ("free-space-too-small", _tiny_free_space, ("free_space",)),
    ("robot-radius-zero", set_field("robot_radius_m", 0.0), ("robot_radius_m", "> 0", "0.0")),
    ("robot-radius-6m", set_field("robot_radius_m", 6.0), ("robot_radius_m", "6.0", "5.0 m")),
    (
        "robot-radius-1e9",
        set_field("robot_radius_m", 1e9),
        ("robot_radius_m", "1000000000.0", "limit"),
    ),
    ("robot-radius-inf", set_field("robot_radius_m", float("inf")), ("robot_radius_m", "inf")),
    ("bounds-inverted", set_field("bounds", [0.0, 0.0, -1.0, -1.0]), ("bounds", "xmin < xmax")),
    ("bounds-too-small", set_field("bounds", [0.0, 0.0, 1.0, 1.0]), ("outside bounds",)),
    ("bounds-1e308", set_field("bounds.2", 1e308), ("bounds[2]", "1e+308")),
    ("roadmap-no-edges", set_field("roadmap.edges", []), ("roadmap has no edges",)),
    ("roadmap-edge-out-of-range", set_field("roadmap.edges.0", [0, 10**6]), ("roadmap.edges[0]",)),
    ("roadmap-self-loop", set_field("roadmap.edges.0", [1, 1]), ("roadmap.edges[0]", "itself")),
    ("roadmap-edge-through-wall", _crossing_edge, ("roadmap.edges[", "robot radius")),
    ("roadmap-node-outside", set_field("roadmap.nodes.0", [-5.0, -5.0]), ("roadmap.nodes[0]",)),
    (
        "roadmap-node-1e308",
        set_field("roadmap.nodes.0", [1e308, 0.0]),
        ("roadmap.nodes[0]", "limit"),
    ),
    ("roadmap-edge-float", set_field("roadmap.edges.0", [0.5, 1]), ("roadmap.edges[0]", "integer")),
    (
        "clutter-bowtie",
        set_field("clutter.0.exterior", [[0, 0], [1, 1], [1, 0], [0, 1]]),
        ("clutter[0]", "not one valid polygon"),
    ),
    ("clutter-not-a-list", set_field("clutter", {}), ("clutter", "must be a list")),
    (
        "free-space-2-points",
        set_field("free_space.exterior", [[0, 0], [1, 1]]),
        ("free_space.exterior", "3 distinct points"),
    ),
    (
        "obstacle-zero-area",
        obstacle(shape=[[0, 0], [1, 0], [2, 0]]),
        ("dynamic_obstacles[0].shape",),
    ),
    (
        "obstacle-tiny-area",
        obstacle(shape=[[0, 0], [1e-3, 0], [1e-3, 1e-3], [0, 1e-3]]),
        ("dynamic_obstacles[0].shape", "area"),
    ),
    (
        "person-enormous-speed",
        obstacle(speed_m_s=1e12),
        ("dynamic_obstacles[0].speed_m_s", "1000000000000.0", "5.0] m/s"),
    ),
    (
        "person-1-micrometre-path",
        lambda d: obstacle(
            path=[d["start"][:2], [d["start"][0] + 1e-6, d["start"][1]]], pose=d["start"]
        )(d),
        ("dynamic_obstacles[0].path", "0.1 m"),
    ),
    ("obstacle-mass-zero", obstacle(mass_kg=0.0), ("dynamic_obstacles[0].mass_kg", "> 0")),
    ("obstacle-mass-huge", obstacle(mass_kg=1e30), ("dynamic_obstacles[0].mass_kg", "1e+30")),
    ("obstacle-negative-speed", obstacle(speed_m_s=-1.0), ("dynamic_obstacles[0].speed_m_s",)),
    ("obstacle-kind-ghost", obstacle(kind="ghost"), ("dynamic_obstacles[0].kind", "'ghost'")),
    (
        "obstacle-pose-outside",
        obstacle(pose=[500.0, 500.0, 0.0]),
        ("dynamic_obstacles[0].pose", "outside bounds"),
    ),
    (
        "obstacle-path-1e308",
        obstacle(path=[[0.0, 0.0], [1e308, 0.0]]),
        ("dynamic_obstacles[0].path[1]", "limit"),
    ),
    (
        "too-many-obstacles",
        lambda d: d.__setitem__("dynamic_obstacles", [bi.person(d)] * 201),
        ("dynamic_obstacles", "201", "200"),
    ),
    ("kind-empty", set_field("kind", ""), ("kind", "non-empty")),
    ("seed-negative", set_field("seed", -1), ("seed", "-1")),
    ("params-nan", set_field("params.width_m", float("nan")), ("params.width_m", "nan")),
    ("features-inf", set_field("features.loops", float("-inf")), ("features.loops", "-inf")),
    ("format-wrong", set_field("format", "other"), ("format", "'other'")),
    ("version-2", set_field("version", 2), ("version is 2",)),
    ("unknown-key", set_field("colour", "red"), ("unknown key", "colour")),
    ("missing-key", lambda d: d.pop("roadmap"), ("missing", "roadmap")),
]


@pytest.fixture
def world_path(tmp_path: Path) -> Callable[[str | bytes], Path]:
    def write(content: str | bytes) -> Path:
        path = tmp_path / "w.json"
        if isinstance(content, bytes):
            path.write_bytes(content)
        else:
            path.write_text(content)
        return path

    return write


def _refuse_world(capsys: Any, path: Path, tmp_path: Path, *expected: str) -> None:
    out = tmp_path / "out"
    refused(capsys, ["simulate", "--world", str(path), "--out", str(out)], str(path), *expected)
    nothing_written(out)


def test_the_valid_world_with_moving_obstacles_is_accepted() -> None:
    doc = bi.world_doc()
    doc["dynamic_obstacles"] = [bi.person(doc), bi.box(doc)]
    world = world_from_json(bi.world_text(doc))
    assert len(world.dynamic_obstacles) == 2 and len(world.walls) > 0


@pytest.mark.parametrize(
    ("mutate", "expected"), [c[1:] for c in WORLD_CASES], ids=[c[0] for c in WORLD_CASES]
)
def test_bad_world_file(mutate, expected, world_path, tmp_path, capsys) -> None:
    doc = bi.world_doc()
    mutate(doc)
    _refuse_world(capsys, world_path(bi.world_text(doc)), tmp_path, *expected)


RAW_WORLD_CASES = [
    ("deep-json", bi.nested(100_000), ("nested deeper than 64",)),
    (
        "deep-json-in-params",
        bi.world_text()[:-1] + ',"extra":' + bi.nested(70) + "}",
        ("nested deeper than 64",),
    ),
    ("integer-5000-digits", '{"format": ' + "9" * 5000 + "}", ("not valid JSON",)),
    ("not-json", "walls: none", ("not valid JSON", "line 1 column 1")),
    ("a-list", "[1, 2]", ("expected a JSON object", "a list")),
    ("duplicate-key", '{"format": "albot2d-world", "format": "x"}', ("duplicate key 'format'",)),
    ("empty-file", "", ("not valid JSON",)),
    ("not-utf8", b'{"format": "\xff"}', ("not UTF-8", "byte 12")),
]


@pytest.mark.parametrize(
    ("content", "expected"), [c[1:] for c in RAW_WORLD_CASES], ids=[c[0] for c in RAW_WORLD_CASES]
)
def test_bad_world_text(content, expected, world_path, tmp_path, capsys) -> None:
    _refuse_world(capsys, world_path(content), tmp_path, *expected)


# ------------------------------------------------------------------ plans and reports

OTHER_CASES = [
    (
        "houseexpo-1e300",
        "he.json",
        '{"id": "h", "verts": [[0, 0], [1e300, 0], [0, 5]]}',
        ("verts[1]", "1e+300"),
    ),
    (
        "houseexpo-huge-int",
        "he.json",
        '{"id": "h", "verts": [[0, 0], [' + "9" * 400 + ", 0]]}",
        ("verts[1]", "999999"),
    ),
    (
        "houseexpo-800m",
        "he.json",
        '{"id": "h", "verts": [[0, 0], [800, 0], [0, 5]]}',
        ("verts span 800 m", "500"),
    ),
    ("houseexpo-deep", "he.json", bi.nested(100_000), ("nested deeper than 64",)),
    ("report-deep", "report.json", bi.nested(100_000), ("nested deeper than 64",)),
    ("report-not-json", "report.json", "{", ("not valid JSON",)),
]


@pytest.mark.parametrize(
    ("name", "content", "expected"), [c[1:] for c in OTHER_CASES], ids=[c[0] for c in OTHER_CASES]
)
def test_bad_plan_or_report(name, content, expected, tmp_path, capsys) -> None:
    path = tmp_path / name
    path.write_text(content)
    if name == "he.json":
        out = tmp_path / "w.json"
        argv = ["world", "--from-houseexpo", str(path), "--out", str(out)]
    else:
        out = tmp_path / "out"
        argv = ["run", "--reproduce", str(path), "--out", str(out)]
    refused(capsys, argv, str(path), *expected)
    nothing_written(out)
