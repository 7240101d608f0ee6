"""HouseExpo floor plans as Worlds: ``from_houseexpo``.

A HouseExpo json (Li et al., IROS 2020) holds one house: ``verts``, the single outer
polygon of free space in metres (implicitly closed; interior walls are notches in it),
plus ``id``, ``room_num``, ``bbox`` and ``room_category`` (category → room bounding boxes).
The walls are the polygon's edges, unsimplified. Every field is checked and errors name
the file, the field and the value.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np
import shapely

from albot2d.errors import InputError
from albot2d.inputfiles import read_json_file
from albot2d.limits import MAX_HOUSEEXPO_VERTICES
from albot2d.seeding import make_rng
from albot2d.validation import COORDINATE_LIMIT_M
from worldgen.assemble import make_world
from worldgen.params import MAX_WORLD_SIZE_M
from worldgen.roadmap import RoadmapParams
from worldgen.world import World

__all__ = ["HOUSEEXPO_KIND", "from_houseexpo", "read_houseexpo"]

HOUSEEXPO_KIND = "houseexpo"


def _fail(source: str, message: str) -> InputError:
    return InputError(f"{source}: {message}")


def _is_number(x: Any) -> bool:
    """A finite number within the coordinate limit (ints of any size are compared exactly)."""
    return type(x) in (int, float) and abs(x) <= COORDINATE_LIMIT_M


def _numbers(value: Any, source: str, field: str, count: int) -> list[float]:
    if not isinstance(value, list) or len(value) != count or not all(map(_is_number, value)):
        raise _fail(
            source,
            f"{field} must be {count} finite numbers, got {value!r:.80} "
            f"(each within ±{COORDINATE_LIMIT_M:g})",
        )
    return [float(v) for v in value]


def _check_verts(value: Any, source: str) -> np.ndarray:
    if not isinstance(value, list):
        raise _fail(source, f"verts must be a list of [x, y] points, got {value!r:.60}")
    if len(value) > MAX_HOUSEEXPO_VERTICES:
        raise _fail(
            source,
            f"verts has {len(value)} points, more than the limit of {MAX_HOUSEEXPO_VERTICES} "
            "(MAX_HOUSEEXPO_VERTICES)",
        )
    points = [_numbers(p, source, f"verts[{i}]", 2) for i, p in enumerate(value)]
    arr = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    if len(np.unique(arr, axis=0)) < 3:
        raise _fail(source, f"verts needs at least 3 distinct points, got {len(arr)}")
    extent = float(np.ptp(arr, axis=0).max())
    if extent > MAX_WORLD_SIZE_M:
        raise _fail(
            source, f"verts span {extent:g} m, more than the world size cap of {MAX_WORLD_SIZE_M} m"
        )
    return arr


def _check_rooms(value: Any, source: str) -> tuple[list[str], np.ndarray]:
    if not isinstance(value, dict):
        raise _fail(source, f"room_category must be an object, got {value!r:.60}")
    categories, boxes = [], []
    for category in sorted(value):
        rooms = value[category]
        if not isinstance(rooms, list):
            raise _fail(source, f"room_category.{category} must be a list of boxes, got {rooms!r}")
        for i, box in enumerate(rooms):
            x1, y1, x2, y2 = _numbers(box, source, f"room_category.{category}[{i}]", 4)
            if x1 > x2 or y1 > y2:
                raise _fail(
                    source, f"room_category.{category}[{i}] {box} needs x1 <= x2 and y1 <= y2"
                )
            categories.append(category)
            boxes.append([x1, y1, x2, y2])
    return categories, np.asarray(boxes, dtype=np.float64).reshape(-1, 4)


def read_houseexpo(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Parse and check a HouseExpo json; returns ``verts`` ``(N, 2)``, ``id``, ``room_num``,
    ``bbox`` ``(4,)``, ``room_categories`` (list) and ``room_bboxes`` ``(K, 4)``."""
    source = str(Path(path))
    doc = read_json_file(path, "HouseExpo plan")
    if not isinstance(doc, dict):
        raise _fail(source, "expected a HouseExpo JSON object with a verts field")
    missing = [key for key in ("verts", "id") if key not in doc]
    if missing:
        raise _fail(source, f"missing HouseExpo field(s) {', '.join(missing)}")
    house_id = doc["id"]
    if not isinstance(house_id, str) or not house_id:
        raise _fail(source, f"id must be a non-empty string, got {house_id!r}")
    verts = _check_verts(doc["verts"], source)
    categories, boxes = _check_rooms(doc.get("room_category", {}), source)
    room_num = doc.get("room_num", len(categories))
    if type(room_num) is not int or room_num < 0:
        raise _fail(source, f"room_num must be a non-negative integer, got {room_num!r}")
    bbox = np.concatenate([verts.min(axis=0), verts.max(axis=0)])
    if "bbox" in doc:
        box = doc["bbox"]
        if not isinstance(box, dict) or not {"min", "max"} <= box.keys():
            raise _fail(source, f'bbox must be {{"min": [x, y], "max": [x, y]}}, got {box!r}')
        bbox = np.asarray(
            _numbers(box["min"], source, "bbox.min", 2)
            + _numbers(box["max"], source, "bbox.max", 2)
        )
    return {
        "verts": verts,
        "id": house_id,
        "room_num": room_num,
        "bbox": bbox,
        "room_categories": categories,
        "room_bboxes": boxes,
    }


def from_houseexpo(
    path: str | os.PathLike[str],
    *,
    robot_radius_m: float = 0.25,
    clearance_margin_m: float = 0.10,
    seed: int | None = None,
    roadmap_params: RoadmapParams | None = None,
) -> World:
    """A World from a HouseExpo plan: free space = the plan polygon, walls = its edges.

    ``seed`` (optional) picks a random start on the roadmap; without it the start is
    deterministic. ``params`` records the source file name and the house id; ``features``
    holds ``room_categories``, ``room_bboxes`` ``(K, 4)``, ``room_num`` and ``bbox``.
    """
    plan = read_houseexpo(path)
    polygon = shapely.Polygon(plan["verts"])
    source = Path(path).name
    try:
        return make_world(
            polygon,
            kind=HOUSEEXPO_KIND,
            seed=seed,
            rng=None if seed is None else make_rng(seed),
            params={"source": source, "id": plan["id"]},
            features={
                "room_categories": plan["room_categories"],
                "room_bboxes": plan["room_bboxes"],
                "room_num": plan["room_num"],
                "bbox": plan["bbox"],
                "polygon_valid": bool(polygon.is_valid),
            },
            robot_radius_m=robot_radius_m,
            clearance_margin_m=clearance_margin_m,
            roadmap_params=roadmap_params,
        )
    except InputError as exc:
        raise _fail(str(path), str(exc)) from exc
