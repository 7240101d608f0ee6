"""The bad-input corpus: malformed or extreme world files, CARMEN logs, relations files and
command-line values, each refused by the real CLI with exit code 2, one stderr line naming
the place (file and field or line, or the option) and the value, no traceback and no output.

Every case starts from a valid input (``tests/bad_inputs.py``; the first tests show the
valid inputs are accepted) and breaks one thing. Cases run through ``albot2d.cli.main``;
a representative few run the installed CLI in a subprocess too.
"""

from __future__ import annotations

import gzip
import json
import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from albot2d.cli import main
from tests import bad_inputs as bi
from worldgen.io import world_from_json

ROOT = Path(__file__).resolve().parents[1]

# ------------------------------------------------------------------ the checks


def _refused(capsys: pytest.CaptureFixture[str], argv: list[str], *expected: str) -> str:
    """Run the CLI; assert exit 2 and one stderr line holding every ``expected`` text."""
    code = main(argv)
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert code == 2, captured.err
    assert len(lines) == 1, captured.err
    assert "Traceback" not in captured.err
    assert lines[0].startswith(f"albot2d {argv[0]}: error: ")
    for text in expected:
        assert text in lines[0], lines[0]
    return lines[0]


def _nothing_written(*paths: Path) -> None:
    for path in paths:
        assert not path.exists(), path
        assert not list(path.parent.glob(f".{path.name}*")), path  # no temporary leftovers


# ------------------------------------------------------------------ world files


def _set(path: str, value: Any) -> Callable[[dict[str, Any]], None]:
    """A mutation setting the field at ``path`` (``walls.0.1``) to ``value``."""

    def mutate(doc: dict[str, Any]) -> None:
        *parents, last = path.split(".")
        target: Any = doc
        for key in parents:
            target = target[int(key)] if isinstance(target, list) else target[key]
        if isinstance(target, list):
            target[int(last)] = value
        else:
            target[last] = value

    return mutate


def _obstacle(**changes: Any) -> Callable[[dict[str, Any]], None]:
    def mutate(doc: dict[str, Any]) -> None:
        doc["dynamic_obstacles"] = [bi.person(doc, **changes)]

    return mutate


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
    ("wall-1e308", _set("walls.0.0", 1e308), ("walls[0]", "1e+308", "limit")),
    ("wall-huge-int", _set("walls.0.0", 10**400), ("walls[0]", "401 digits")),
    ("wall-string", _set("walls.0.1", "nan"), ("walls[0]", "'nan'")),
    ("wall-3-numbers", _set("walls.0", [1.0, 2.0, 3.0]), ("walls[0]", "3 numbers")),
    ("no-walls", _set("walls", []), ("walls", "positive length", "0 walls")),
    ("zero-length-walls", _set("walls", [[1.0, 1.0, 1.0, 1.0]]), ("walls", "positive length")),
    ("walls-scaled-1e15", _scale_walls, ("walls[", "limit")),
    ("walls-not-a-list", _set("walls", {"a": 1}), ("walls", "an object")),
    ("start-in-wall", _start_on_wall, ("start (",)),
    ("start-outside-bounds", _set("start", [-50.0, 5.0, 0.0]), ("start (-50.0, 5.0)",)),
    ("start-x-1e308", _set("start.0", 1e308), ("start[0]", "1e+308")),
    ("start-theta-nan", _set("start.2", float("nan")), ("start[2]", "finite", "nan")),
    ("start-two-numbers", _set("start", [1.0, 2.0]), ("start", "2 numbers")),
    ("start-disc-overlaps-wall", _near_wall_start, ("start (", "radius 4.0 m")),
    ("boxed-in", _boxed_in, ("roadmap",)),
    ("free-space-too-small", _tiny_free_space, ("free_space",)),
    ("robot-radius-zero", _set("robot_radius_m", 0.0), ("robot_radius_m", "> 0", "0.0")),
    ("robot-radius-6m", _set("robot_radius_m", 6.0), ("robot_radius_m", "6.0", "5.0 m")),
    ("robot-radius-1e9", _set("robot_radius_m", 1e9), ("robot_radius_m", "1000000000.0", "limit")),
    ("robot-radius-inf", _set("robot_radius_m", float("inf")), ("robot_radius_m", "inf")),
    ("bounds-inverted", _set("bounds", [0.0, 0.0, -1.0, -1.0]), ("bounds", "xmin < xmax")),
    ("bounds-too-small", _set("bounds", [0.0, 0.0, 1.0, 1.0]), ("outside bounds",)),
    ("bounds-1e308", _set("bounds.2", 1e308), ("bounds[2]", "1e+308")),
    ("roadmap-no-edges", _set("roadmap.edges", []), ("roadmap has no edges",)),
    ("roadmap-edge-out-of-range", _set("roadmap.edges.0", [0, 10**6]), ("roadmap.edges[0]",)),
    ("roadmap-self-loop", _set("roadmap.edges.0", [1, 1]), ("roadmap.edges[0]", "itself")),
    ("roadmap-edge-through-wall", _crossing_edge, ("roadmap.edges[", "robot radius")),
    ("roadmap-node-outside", _set("roadmap.nodes.0", [-5.0, -5.0]), ("roadmap.nodes[0]",)),
    ("roadmap-node-1e308", _set("roadmap.nodes.0", [1e308, 0.0]), ("roadmap.nodes[0]", "limit")),
    ("roadmap-edge-float", _set("roadmap.edges.0", [0.5, 1]), ("roadmap.edges[0]", "integer")),
    (
        "clutter-bowtie",
        _set("clutter.0.exterior", [[0, 0], [1, 1], [1, 0], [0, 1]]),
        ("clutter[0]", "not one valid polygon"),
    ),
    ("clutter-not-a-list", _set("clutter", {}), ("clutter", "must be a list")),
    (
        "free-space-2-points",
        _set("free_space.exterior", [[0, 0], [1, 1]]),
        ("free_space.exterior", "3 distinct points"),
    ),
    (
        "obstacle-zero-area",
        _obstacle(shape=[[0, 0], [1, 0], [2, 0]]),
        ("dynamic_obstacles[0].shape",),
    ),
    (
        "obstacle-tiny-area",
        _obstacle(shape=[[0, 0], [1e-3, 0], [1e-3, 1e-3], [0, 1e-3]]),
        ("dynamic_obstacles[0].shape", "area"),
    ),
    (
        "person-enormous-speed",
        _obstacle(speed_m_s=1e12),
        ("dynamic_obstacles[0].speed_m_s", "1000000000000.0", "5.0] m/s"),
    ),
    (
        "person-1-micrometre-path",
        lambda d: _obstacle(
            path=[d["start"][:2], [d["start"][0] + 1e-6, d["start"][1]]], pose=d["start"]
        )(d),
        ("dynamic_obstacles[0].path", "0.1 m"),
    ),
    ("obstacle-mass-zero", _obstacle(mass_kg=0.0), ("dynamic_obstacles[0].mass_kg", "> 0")),
    ("obstacle-mass-huge", _obstacle(mass_kg=1e30), ("dynamic_obstacles[0].mass_kg", "1e+30")),
    ("obstacle-negative-speed", _obstacle(speed_m_s=-1.0), ("dynamic_obstacles[0].speed_m_s",)),
    ("obstacle-kind-ghost", _obstacle(kind="ghost"), ("dynamic_obstacles[0].kind", "'ghost'")),
    (
        "obstacle-pose-outside",
        _obstacle(pose=[500.0, 500.0, 0.0]),
        ("dynamic_obstacles[0].pose", "outside bounds"),
    ),
    (
        "obstacle-path-1e308",
        _obstacle(path=[[0.0, 0.0], [1e308, 0.0]]),
        ("dynamic_obstacles[0].path[1]", "limit"),
    ),
    (
        "too-many-obstacles",
        lambda d: d.__setitem__("dynamic_obstacles", [bi.person(d)] * 201),
        ("dynamic_obstacles", "201", "200"),
    ),
    ("kind-empty", _set("kind", ""), ("kind", "non-empty")),
    ("seed-negative", _set("seed", -1), ("seed", "-1")),
    ("params-nan", _set("params.width_m", float("nan")), ("params.width_m", "nan")),
    ("features-inf", _set("features.loops", float("-inf")), ("features.loops", "-inf")),
    ("format-wrong", _set("format", "other"), ("format", "'other'")),
    ("version-2", _set("version", 2), ("version is 2",)),
    ("unknown-key", _set("colour", "red"), ("unknown key", "colour")),
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
    _refused(capsys, ["simulate", "--world", str(path), "--out", str(out)], str(path), *expected)
    _nothing_written(out)


def test_the_valid_world_with_moving_obstacles_is_accepted() -> None:
    doc = bi.world_doc()
    doc["dynamic_obstacles"] = [bi.person(doc), bi.person(doc, kind="box", speed_m_s=0.0)]
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


# ------------------------------------------------------------------ CARMEN logs


def _line(k: int, **changes: Any) -> Callable[[list[str]], None]:
    """A mutation replacing FLASER frame ``k`` by one with ``changes``."""

    def mutate(lines: list[str]) -> None:
        lines[3 + k] = bi.flaser_line(k, **changes)

    return mutate


def _replace(old: str, new: str, *, count: int = 1) -> Callable[[list[str]], None]:
    def mutate(lines: list[str]) -> None:
        text = "\n".join(lines).replace(old, new, count)
        lines[:] = text.split("\n")

    return mutate


def _append(line: str) -> Callable[[list[str]], None]:
    return lambda lines: lines.append(line)


def _ranges(index: int, value: str) -> list[str]:
    beams = ["2.0"] * bi.N_BEAMS
    beams[index] = value
    return beams


_ROBOTLASER = (
    "ROBOTLASER1 0 {start} {fov} 0.0174533 30.0 0.01 0 181 "
    + " ".join(["2.0"] * 181)
    + " 0 0 0 0 0 0 0 0 0 0 0 0 100.0 albot2d 100.0"
)


def _coarse_laser(lines: list[str]) -> None:
    """19 beams 20° apart: readable, but too coarse for the mappers' surface extraction."""
    lines[:] = [
        "PARAM laser_front_laser_fov 360.0",
        "PARAM laser_front_laser_resolution 20.0",
        *(bi.flaser_line(k, ranges=["2.0"] * 19) for k in range(10)),
    ]


# (id, mutation of the valid log's lines, texts the error line must hold; ``:N`` = line)
LOG_CASES: list[tuple[str, Callable[[list[str]], None], tuple[str, ...]]] = [
    ("pose-x-1e308", _line(3, x="1e308"), (":7:", "x '1e308'", "limit")),
    ("pose-x-inf", _line(3, x="inf"), (":7:", "x 'inf'", "not finite")),
    ("pose-x-text", _line(3, x="east"), (":7:", "x 'east'", "not a number")),
    ("timestamp-1e300", _line(5, stamp="1e300"), (":9:", "ipc_timestamp '1e300'", "limit")),
    ("timestamp-nan", _line(5, stamp="nan"), (":9:", "ipc_timestamp 'nan'")),
    ("range-text", _line(0, ranges=_ranges(7, "far")), (":4:", "range 7 'far'")),
    (
        "beam-count-huge",
        _replace("FLASER 181", "FLASER 999999999999"),
        (":4:", "999999999999", "65536"),
    ),
    ("beam-count-negative", _replace("FLASER 181", "FLASER -1"), (":4:", "n must be >= 0")),
    ("beam-count-mismatch", _replace("FLASER 181", "FLASER 180"), (":4:", "n=180", "expected 191")),
    (
        "line-cut-short",
        lambda lines: lines.__setitem__(5, lines[5][:40]),
        (":6:", "FLASER", "fields"),
    ),
    (
        "param-fov-1e308",
        _replace("laser_front_laser_fov 180.0", "laser_front_laser_fov 1e308"),
        (":1:", "PARAM laser_front_laser_fov value '1e308'", "(0, 360]"),
    ),
    (
        "param-fov-zero",
        _replace("laser_front_laser_fov 180.0", "laser_front_laser_fov 0"),
        (":1:", "laser_front_laser_fov value '0'"),
    ),
    (
        "param-resolution-negative",
        _replace("laser_front_laser_resolution 1.0", "laser_front_laser_resolution -1"),
        (":2:", "laser_front_laser_resolution value '-1'"),
    ),
    (
        "param-max-range-nan",
        _replace("robot_front_laser_max 30.0", "robot_front_laser_max nan"),
        (":3:", "robot_front_laser_max value 'nan'"),
    ),
    (
        "param-max-range-1e9",
        _replace("robot_front_laser_max 30.0", "robot_front_laser_max 1e9"),
        (":3:", "robot_front_laser_max value '1e9'", "1e+06"),
    ),
    (
        "param-angular-offset-100",
        _append("PARAM robot_frontlaser_angular_offset 100"),
        (":44:", "robot_frontlaser_angular_offset value '100'"),
    ),
    (
        "param-offset-1e308",
        _append("PARAM robot_frontlaser_offset 1e308"),
        (":44:", "robot_frontlaser_offset value '1e308'"),
    ),
    ("param-no-value", _append("PARAM robot_frontlaser_offset"), (":44:", "PARAM", "value")),
    (
        "robotlaser-start-1e308",
        _append(_ROBOTLASER.format(start="1e308", fov="3.14159")),
        (":44:", "start_angle '1e308'"),
    ),
    (
        "robotlaser-fov-100",
        _append(_ROBOTLASER.format(start="-1.5708", fov="100")),
        (":44:", "fov '100'"),
    ),
    ("odom-1e308", _append("ODOM 1e308 0 0 0 0 0 100.0 albot2d 100.0"), (":44:", "ODOM", "x")),
    ("odom-short", _append("ODOM 1 2 3"), (":44:", "ODOM has 4 fields")),
    ("neff-text", _append("NEFF many"), (":44:", "NEFF", "'many'")),
    ("coarse-laser", _coarse_laser, ("beams are 20 deg apart", "less than 10 deg")),
    ("no-laser-lines", lambda lines: lines.__setitem__(slice(3, None), []), ("no laser scans",)),
]


def _refuse_log(capsys: Any, path: Path, tmp_path: Path, *expected: str, strict: bool = False):
    out = tmp_path / "out"
    argv = ["replay", str(path), "--no-figures", "--out", str(out)]
    _refused(capsys, [*argv, "--strict"] if strict else argv, str(path), *expected)
    _nothing_written(out)


def _write_log(tmp_path: Path, lines: list[str]) -> Path:
    path = tmp_path / "log.clf"
    path.write_text(bi.carmen_text(lines))
    (tmp_path / "log.relations").write_text(bi.relations_text())
    return path


def test_the_valid_log_replays_strictly(tmp_path: Path, capsys: Any) -> None:
    path = _write_log(tmp_path, bi.carmen_lines())
    assert (
        main(["replay", str(path), "--no-figures", "--strict", "--out", str(tmp_path / "o")]) == 0
    )
    report = json.loads((tmp_path / "o" / "report.json").read_text())
    assert report["log"]["anomalies"]["frames_kept"] == 40
    assert report["run"]["relations_used"] == 39
    assert "warning" not in capsys.readouterr().err


@pytest.mark.parametrize(
    ("mutate", "expected"), [c[1:] for c in LOG_CASES], ids=[c[0] for c in LOG_CASES]
)
def test_bad_log(mutate, expected, tmp_path, capsys) -> None:
    lines = bi.carmen_lines()
    mutate(lines)
    _refuse_log(capsys, _write_log(tmp_path, lines), tmp_path, *expected)


def test_truncated_gzip_log(tmp_path: Path, capsys: Any) -> None:
    data = gzip.compress(bi.carmen_text().encode())
    path = tmp_path / "log.clf.gz"
    path.write_bytes(data[: len(data) // 2])
    _refuse_log(capsys, path, tmp_path, "corrupt or truncated gzip")


# Anomalies a real log may hold: accepted with a warning, refused with --strict.
ANOMALY_CASES = [
    ("nan-range", _line(2, ranges=_ranges(10, "nan")), "1 non-finite range"),
    ("inf-range", _line(2, ranges=_ranges(10, "inf")), "1 non-finite range"),
    ("negative-range", _line(2, ranges=_ranges(10, "-0.5")), "1 negative range"),
    ("duplicate-timestamp", _line(2, stamp="0.5"), "1 duplicate timestamp"),
    ("shuffled", lambda lines: lines.insert(10, lines.pop(20)), "1 out-of-order timestamp"),
    (
        "reversed",
        lambda lines: lines.__setitem__(slice(3, None), lines[3:][::-1]),
        "39 out-of-order timestamps",
    ),
]


@pytest.mark.parametrize(
    ("mutate", "summary"), [c[1:] for c in ANOMALY_CASES], ids=[c[0] for c in ANOMALY_CASES]
)
def test_log_anomaly_is_refused_with_strict(mutate, summary, tmp_path, capsys) -> None:
    lines = bi.carmen_lines()
    mutate(lines)
    _refuse_log(capsys, _write_log(tmp_path, lines), tmp_path, summary, "strict", strict=True)


# ------------------------------------------------------------------ relations files

RELATION_CASES = [
    ("t1-nan", "nan 0.5 0.1 0 0 0 0 0", ("relation field t1 'nan'", "not a finite number")),
    ("x-1e308", "0 0.5 1e308 0 0 0 0 0", ("relation field x '1e308'", "limit")),
    ("t2-1e300", "0 1e300 0.1 0 0 0 0 0", ("relation field t2 '1e300'", "limit")),
    ("yaw-1e7", "0 0.5 0.1 0 0 0 0 1e7", ("relation field yaw '1e7'", "limit")),
    ("seven-fields", "0 0.5 0.1 0 0 0 0", ("relation has 7 fields", "expected 8")),
    ("text-field", "0 0.5 north 0 0 0 0 0", ("relation field x 'north'",)),
    ("nine-fields", "0 0.5 0.1 0 0 0 0 0 0", ("relation has 9 fields",)),
]


@pytest.mark.parametrize(
    ("row", "expected"), [c[1:] for c in RELATION_CASES], ids=[c[0] for c in RELATION_CASES]
)
def test_bad_relations(row, expected, tmp_path, capsys) -> None:
    log = _write_log(tmp_path, bi.carmen_lines())
    relations = tmp_path / "bad.relations"
    relations.write_text(bi.relations_text(["0 0.5 0.1 0 0 0 0 0", row]))
    out = tmp_path / "out"
    argv = ["replay", str(log), "--relations", str(relations), "--no-figures", "--out", str(out)]
    _refused(capsys, argv, f"{relations}:2:", *expected)
    _nothing_written(out)


def test_missing_relations_file(tmp_path: Path, capsys: Any) -> None:
    log = _write_log(tmp_path, bi.carmen_lines())
    out = tmp_path / "out"
    missing = tmp_path / "none.relations"
    argv = ["replay", str(log), "--relations", str(missing), "--out", str(out)]
    _refused(capsys, argv, str(missing), "No such file")
    _nothing_written(out)


# ------------------------------------------------------------------ command-line values

# (id, argv after the command with OUT for the output, texts the error line must hold)
CLI_CASES = [
    ("world-seed-negative", ["world", "--kind", "rooms", "--seed", "-1"], ("--seed", "'-1'")),
    ("world-seed-float", ["world", "--kind", "rooms", "--seed", "1e3"], ("--seed", "'1e3'")),
    ("world-width-nan", ["world", "--kind", "rooms", "--width", "nan"], ("--width", "'nan'")),
    (
        "world-width-1e5",
        ["world", "--kind", "rooms", "--width", "1e5"],
        ("width_m", "500", "100000.0"),
    ),
    ("world-height-negative", ["world", "--kind", "rooms", "--height", "-3"], ("--height", "-3")),
    (
        "world-100000-obstacles",
        ["world", "--kind", "rooms", "--param", "dynamic_obstacles=100000"],
        ("dynamic_obstacles", "200", "100000"),
    ),
    (
        "world-param-inf",
        ["world", "--kind", "rooms", "--param", "width_m=1e400"],
        ("width_m", "finite", "inf"),
    ),
    (
        "world-param-radius",
        ["world", "--kind", "rooms", "--param", "robot_radius_m=1e300"],
        ("robot_radius_m", "1e+300"),
    ),
    (
        "world-param-clutter",
        ["world", "--kind", "open", "--param", "clutter_per_10m2=1e6"],
        ("clutter_per_10m2", "1000000.0"),
    ),
    (
        "world-param-door",
        ["world", "--kind", "rooms", "--param", "door_width_max_m=1e9"],
        ("door_width_max_m", "1000000000.0", "500"),
    ),
    ("world-param-unknown", ["world", "--kind", "rooms", "--param", "colour=1"], ("colour",)),
    ("world-param-no-value", ["world", "--kind", "rooms", "--param", "x"], ("--param", "'x'")),
    (
        "world-tour-1e300",
        ["world", "--kind", "rooms", "--tour-length", "1e300"],
        ("min_length_m", "1e+300"),
    ),
    ("world-kind-unknown", ["world", "--kind", "castle"], ("'castle'",)),
    ("run-max-frames-0", ["run", "--kind", "rooms", "--max-frames", "0"], ("--max-frames", "'0'")),
    (
        "run-last-k-huge",
        ["run", "--kind", "rooms", "--last-k-views", "1" + "0" * 20],
        ("last_k_views", "1" + "0" * 20),
    ),
    (
        "run-snapshots-huge",
        ["run", "--kind", "rooms", "--snapshots", "1000000000"],
        ("snapshots", "1000000000"),
    ),
    (
        "run-stop-every-nan",
        ["run", "--kind", "rooms", "--stop-every", "nan"],
        ("--stop-every", "'nan'"),
    ),
    (
        "run-min-start-inf",
        ["run", "--kind", "rooms", "--min-start-distance", "inf"],
        ("--min-start-distance", "'inf'"),
    ),
    ("run-width-1e5", ["run", "--kind", "rooms", "--width", "1e5"], ("width_m", "100000.0")),
    ("run-mapper-unknown", ["run", "--kind", "rooms", "--mapper", "oracle"], ("'oracle'",)),
    ("run-profile-unknown", ["run", "--kind", "rooms", "--profile", "fast"], ("'fast'",)),
    ("fuzz-episodes-0", ["fuzz", "--episodes", "0"], ("--episodes", "'0'")),
    ("fuzz-workers-0", ["fuzz", "--episodes", "2", "--workers", "0"], ("--workers", "'0'")),
    (
        "fuzz-world-size-inverted",
        ["fuzz", "--episodes", "2", "--world-size", "30", "10"],
        ("--world-size", "30", "10"),
    ),
    (
        "fuzz-address-not-a-port",
        ["fuzz", "--episodes", "2", "--backend", "dask", "--address", "tcp://127.0.0.1:notaport"],
        ("--address", "notaport"),
    ),
    (
        "fuzz-tour-length-huge",
        ["fuzz", "--episodes", "2", "--tour-length", "1e300", "2e300"],
        ("tour_length_max_m", "2e+300"),
    ),
    (
        "fuzz-world-size-over-cap",
        ["fuzz", "--episodes", "2", "--world-size", "10", "1e5"],
        ("world_size_max_m", "100000.0"),
    ),
    (
        "fuzz-workers-huge",
        ["fuzz", "--episodes", "2", "--workers", "100000"],
        ("--workers", "100000"),
    ),
    (
        "fuzz-address-port-range",
        ["fuzz", "--episodes", "2", "--backend", "dask", "--address", "tcp://127.0.0.1:99999"],
        ("--address", "99999"),
    ),
]


@pytest.mark.parametrize(
    ("argv", "expected"), [c[1:] for c in CLI_CASES], ids=[c[0] for c in CLI_CASES]
)
def test_bad_command_line_value(argv, expected, tmp_path, capsys) -> None:
    out = tmp_path / ("w.json" if argv[0] == "world" else "out")
    _refused(capsys, [*argv, "--out", str(out)], *expected)
    _nothing_written(out)


def test_replay_command_line_values(tmp_path: Path, capsys: Any) -> None:
    log = _write_log(tmp_path, bi.carmen_lines())
    out = tmp_path / "out"
    for option, value in (("--max-frames", "1e3"), ("--stop-every", "-1"), ("--mapper", "truth")):
        _refused(capsys, ["replay", str(log), option, value, "--out", str(out)], value)
        _nothing_written(out)


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
    _refused(capsys, argv, str(path), *expected)
    _nothing_written(out)


# ------------------------------------------------------------------ the installed CLI

SUBPROCESS_CASES = [
    ("world", lambda d: _set("walls.0.0", 1e308)(d), ("walls[0]", "limit")),
    ("world", _obstacle(speed_m_s=1e12), ("speed_m_s", "1000000000000.0")),
    ("log", _line(3, x="1e308"), (":7:", "x '1e308'")),
    (
        "log",
        _replace("laser_front_laser_fov 180.0", "laser_front_laser_fov 1e308"),
        (":1:", "laser_front_laser_fov value '1e308'"),
    ),
]


@pytest.mark.parametrize(("what", "mutate", "expected"), SUBPROCESS_CASES)
def test_installed_cli_refuses_in_one_line(what, mutate, expected, tmp_path) -> None:
    out = tmp_path / "out"
    if what == "world":
        doc = bi.world_doc()
        mutate(doc)
        path = tmp_path / "w.json"
        path.write_text(bi.world_text(doc))
        argv = ["simulate", "--world", str(path), "--out", str(out)]
    else:
        lines = bi.carmen_lines()
        mutate(lines)
        path = _write_log(tmp_path, lines)
        argv = ["replay", str(path), "--out", str(out)]
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.run(
        [sys.executable, "-m", "albot2d", *argv],
        capture_output=True,
        text=True,
        cwd=ROOT,
        env=env,
        timeout=120,
    )
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and len(lines) == 1, proc.stderr
    assert "Traceback" not in proc.stderr and str(path) in lines[0]
    assert all(text in lines[0] for text in expected), lines[0]
    _nothing_written(out)
