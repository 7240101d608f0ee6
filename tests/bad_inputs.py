"""Valid inputs to break: a small world document, a CARMEN log and its relations, as text.

The bad-input corpus (``tests/test_bad_*.py``) and the reader fuzzing
(``tests/test_reader_fuzz.py``) start from these and change one thing. Each builder returns
a fresh copy, so a case may mutate what it gets.
"""

from __future__ import annotations

import copy
import functools
import json
from typing import Any

import numpy as np
import shapely

__all__ = [
    "N_BEAMS",
    "box",
    "carmen_lines",
    "carmen_text",
    "crossing_edge",
    "episode_record",
    "flaser_line",
    "nested",
    "person",
    "relations_text",
    "world_doc",
    "world_text",
]

N_BEAMS = 181  # 1° apart over 180°: fine enough for the mappers' breakpoint rule
_FRAMES = 40
_STEP_M = 0.1
_STEP_S = 0.5
_PARAMS = (
    "PARAM laser_front_laser_fov 180.0",
    "PARAM laser_front_laser_resolution 1.0",
    "PARAM robot_front_laser_max 30.0",
)


@functools.cache
def _world_json() -> str:
    from worldgen.generate import generate
    from worldgen.io import world_to_json

    return world_to_json(generate("rooms", seed=1, width_m=12.0, height_m=12.0))


def world_doc() -> dict[str, Any]:
    """A valid world file's document (a generated 12 m rooms world), a fresh copy."""
    return copy.deepcopy(json.loads(_world_json()))


def world_text(doc: dict[str, Any] | None = None) -> str:
    """``doc`` (default: the valid world) as world-file JSON text."""
    return json.dumps(world_doc() if doc is None else doc)


def person(doc: dict[str, Any], **changes: Any) -> dict[str, Any]:
    """A valid walking person on the first roadmap edge of ``doc``, with ``changes``."""
    nodes, (i, j) = doc["roadmap"]["nodes"], doc["roadmap"]["edges"][0]
    ob = {
        "kind": "person",
        "shape": [[-0.2, -0.2], [0.2, -0.2], [0.2, 0.2], [-0.2, 0.2]],
        "pose": [nodes[i][0], nodes[i][1], 0.0],
        "path": [nodes[i], nodes[j]],
        "speed_m_s": 1.0,
        "mass_kg": 70.0,
    }
    return ob | changes


def box(doc: dict[str, Any], side_m: float = 0.4) -> dict[str, Any]:
    """A valid box standing still in ``doc``: in free space, clear of the walls, the start
    and the roadmap by more than the robot radius (as the generator places them)."""
    free = shapely.Polygon(doc["free_space"]["exterior"], doc["free_space"]["holes"])
    nodes = np.asarray(doc["roadmap"]["nodes"])
    roadmap = shapely.MultiLineString([nodes[[i, j]].tolist() for i, j in doc["roadmap"]["edges"]])
    start = shapely.Point(doc["start"][:2])
    need = side_m + doc["robot_radius_m"] + 0.05
    x0, y0, x1, y1 = free.bounds
    for x in np.arange(x0 + need, x1, 0.1):
        for y in np.arange(y0 + need, y1, 0.1):
            spot = shapely.Point(x, y)
            clear = min(free.exterior.distance(spot), roadmap.distance(spot))
            if free.contains(spot) and clear > need and start.distance(spot) > need + 1.0:
                half = side_m / 2
                return {
                    "kind": "box",
                    "shape": [[-half, -half], [half, -half], [half, half], [-half, half]],
                    "pose": [float(x), float(y), 0.3],
                    "path": [],
                    "speed_m_s": 0.0,
                    "mass_kg": 10.0,
                }
    raise AssertionError("no free spot for a box")


def crossing_edge(doc: dict[str, Any]) -> list[int]:
    """Two roadmap nodes of ``doc`` whose straight line crosses a wall."""
    walls = shapely.MultiLineString(np.asarray(doc["walls"]).reshape(-1, 2, 2).tolist())
    nodes = doc["roadmap"]["nodes"]
    for i in range(len(nodes)):
        for j in range(i + 1, len(nodes)):
            if shapely.LineString([nodes[i], nodes[j]]).intersects(walls):
                return [i, j]
    raise AssertionError("no roadmap node pair crosses a wall")


def flaser_line(
    k: int, *, ranges: list[str] | None = None, x: str | None = None, stamp: str | None = None
) -> str:
    """Frame ``k`` of the valid log: the robot ``k`` steps along x, 2 m from everything."""
    beams = ranges if ranges is not None else ["2.0"] * N_BEAMS
    px = x if x is not None else repr(k * _STEP_M)
    t = stamp if stamp is not None else repr(k * _STEP_S)
    pose = f"{px} 0.0 0.0"
    return f"FLASER {len(beams)} {' '.join(beams)} {pose} {pose} {t} albot2d {t}"


def carmen_lines() -> list[str]:
    """The valid log's lines: laser PARAMs, then one FLASER line per frame."""
    return [*_PARAMS, *(flaser_line(k) for k in range(_FRAMES))]


def carmen_text(lines: list[str] | None = None) -> str:
    return "\n".join(carmen_lines() if lines is None else lines) + "\n"


def relations_text(rows: list[str] | None = None) -> str:
    """Relations between consecutive frames of the valid log (the true motion, no noise)."""
    if rows is None:
        rows = [
            f"{k * _STEP_S!r} {(k + 1) * _STEP_S!r} {_STEP_M!r} 0 0 0 0 0"
            for k in range(_FRAMES - 1)
        ]
    return "\n".join(rows) + "\n"


def nested(depth: int) -> str:
    """JSON text of ``depth`` nested lists."""
    return "[" * depth + "]" * depth


# Every metric an episode of Albot1 records (scored, then measured by the checks).
_OK_METRICS = {
    "frames": 10, "travelled_m": 20.0, "collided_frames": 0, "local_maps": 4,
    "triangulations": 3, "path_integrations": 0, "global_map_surfaces": 12,
    "homing_stops": 0, "homing_bearing_error_max_deg": None,
    "homing_distance_error_max_m": None, "rpe_trans_m": 0.1, "rpe_rot_deg": 0.5,
    "odometry_rpe_trans_m": 0.2, "odometry_rpe_rot_deg": 0.9, "end_trans_m": 0.3,
    "end_rot_deg": 1.0, "odometry_end_trans_m": 0.6, "odometry_end_rot_deg": 2.0,
    "map_accuracy_m": 0.05, "map_accuracy_p95_m": 0.2, "map_completeness": 0.8,
    "local_map_position_error_max_m": 0.04, "local_map_heading_error_max_deg": 0.7,
    "heading_error_max_deg": 1.5, "heading_error_mean_deg": 0.6,
    "odometry_heading_error_max_deg": 3.0, "odometry_heading_error_mean_deg": 1.2,
}  # fmt: skip


def episode_record(index: int, *, seed: int = 0, status: str = "ok") -> dict[str, Any]:
    """A whole episodes.jsonl record of episode ``index`` of a campaign with ``seed``, as
    albot2d writes it, with ``status`` and the fields it needs."""
    record: dict[str, Any] = {
        "episode": index,
        "seed": {"entropy": seed, "spawn_key": [index]},
        "run_seed": 1234 + index,
        "world": {"kind": "rooms", "params": {"width_m": 14.0, "height_m": 14.0}},
        "tour": {"kind": "loop", "min_length_m": 15.0, "length_m": 20.0},
        "profile": "dataset3",
        "noise": "typical",
        "laser_noise": "sick_lms200",
        "mapper": "albot1",
        "status": status,
        "checked": ["route_connected"],
        "violations": {},
        "error": None,
        "metrics": dict(_OK_METRICS),
        "digest": "0" * 64,
        "timings": {"total_s": 1.0, "ms_per_view": 100.0},
    }
    if status == "violation":
        record["violations"] = {"route_connected": ["the route map is not connected"]}
    elif status == "crash":
        record |= {"error": {"type": "RuntimeError", "message": "boom", "traceback": ""},
                   "metrics": {}, "digest": None}  # fmt: skip
    return record
