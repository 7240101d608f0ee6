"""World files: versioned, canonical JSON (``save``/``load``, text variants).

A file is one JSON object ``{"format": "albot2d-world", "version": 1, ...}`` holding every
``World`` field. Floats are written with ``repr`` (shortest round-trip form), so
``load(save(w))`` reproduces every float64 bit for bit. Output is canonical (format and
version first, then sorted keys; fixed separators; one top-level field per line; no
timestamps): identical worlds give identical bytes in any process. Loading checks every
field (``worldgen.world_reader``) and raises ``InputError`` naming the file, the field and
the value. Numpy arrays, shapely geometries and poses inside ``params``/``features`` are
stored as tagged objects (``{"__type__": "ndarray", ...}``); tuples come back as lists.
A file larger than ``MAX_WORLD_FILE_BYTES`` or nested deeper than ``MAX_JSON_DEPTH`` is
refused before its fields are read.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import shapely

from albot2d.atomic import atomic_write_text
from albot2d.errors import InputError
from albot2d.geometry import Pose
from albot2d.inputfiles import read_limited
from albot2d.limits import MAX_WORLD_FILE_BYTES
from albot2d.validation import MAX_JSON_DEPTH, parse_json
from worldgen.world import DynamicObstacle, World
from worldgen.world_reader import (
    ARRAY_DTYPES,
    FORMAT_NAME,
    FORMAT_VERSION,
    TYPE_TAG,
    WorldReader,
)

__all__ = [
    "FORMAT_NAME",
    "FORMAT_VERSION",
    "MAX_JSON_DEPTH",
    "MAX_WORLD_FILE_BYTES",
    "load",
    "save",
    "world_from_json",
    "world_to_json",
]


# ---------------------------------------------------------------- writing


def save(world: World, path: str | os.PathLike[str]) -> None:
    """Write ``world`` to ``path`` as canonical JSON, atomically (no partial file on failure)."""
    atomic_write_text(path, world_to_json(world))


def world_to_json(world: World) -> str:
    """The canonical JSON text of ``world`` (see the module docstring)."""
    doc = _world_to_document(world)
    keys = ["format", "version", *sorted(doc.keys() - {"format", "version"})]
    lines = [f"{json.dumps(key)}:{_dumps(doc[key], key)}" for key in keys]
    return "{\n" + ",\n".join(lines) + "\n}\n"


def _dumps(value: Any, field: str) -> str:
    try:
        return json.dumps(value, sort_keys=True, separators=(",", ":"), allow_nan=False)
    except ValueError as exc:
        raise InputError(f"cannot save world: {field} holds a non-finite number ({exc})") from exc


def _finite_list(arr: np.ndarray, field: str) -> list:
    bad = ~np.isfinite(arr)
    if bad.any():
        index = tuple(int(i) for i in np.argwhere(bad)[0])
        raise InputError(f"cannot save world: {field}{list(index)} is {arr[index].item()!r}")
    return arr.tolist()


def _ring_to_json(coords: Any, field: str) -> list:
    arr = np.asarray(coords, dtype=np.float64).reshape(-1, 2)
    if len(arr) > 1 and np.array_equal(arr[0], arr[-1]):
        arr = arr[:-1]  # shapely repeats the first vertex; the reader closes rings itself
    return _finite_list(arr, field)


def _polygon_to_json(poly: Any, field: str) -> dict[str, Any]:
    if not isinstance(poly, shapely.Polygon) or poly.is_empty:
        kind = "an empty Polygon" if isinstance(poly, shapely.Polygon) else type(poly).__name__
        raise InputError(f"cannot save world: {field} must be one non-empty Polygon, got {kind}")
    return {
        "exterior": _ring_to_json(poly.exterior.coords, f"{field}.exterior"),
        "holes": [
            _ring_to_json(ring.coords, f"{field}.holes[{i}]")
            for i, ring in enumerate(poly.interiors)
        ],
    }


def _world_to_document(world: World) -> dict[str, Any]:
    seed = world.seed
    if isinstance(seed, np.integer):
        seed = int(seed)
    return {
        "format": FORMAT_NAME,
        "version": FORMAT_VERSION,
        "kind": str(world.kind),
        "seed": seed,
        "robot_radius_m": float(world.robot_radius_m),
        "bounds": [float(b) for b in world.bounds],
        "start": _finite_list(world.start.as_array(), "start"),
        "walls": _finite_list(world.walls, "walls"),
        "clutter": [_polygon_to_json(p, f"clutter[{i}]") for i, p in enumerate(world.clutter)],
        "free_space": _polygon_to_json(world.free_space, "free_space"),
        "roadmap": {
            "nodes": _finite_list(world.roadmap.nodes, "roadmap.nodes"),
            "edges": world.roadmap.edges.tolist(),
        },
        "dynamic_obstacles": [
            _obstacle_to_json(ob, f"dynamic_obstacles[{i}]")
            for i, ob in enumerate(world.dynamic_obstacles)
        ],
        "params": _encode_value(dict(world.params), "params"),
        "features": _encode_value(dict(world.features), "features"),
    }


def _obstacle_to_json(ob: DynamicObstacle, field: str) -> dict[str, Any]:
    return {
        "kind": ob.kind,
        "shape": _finite_list(ob.shape, f"{field}.shape"),
        "pose": _finite_list(ob.pose.as_array(), f"{field}.pose"),
        "path": _finite_list(ob.path, f"{field}.path"),
        "speed_m_s": float(ob.speed_m_s),
        "mass_kg": float(ob.mass_kg),
    }


def _encode_value(value: Any, field: str) -> Any:
    """Plain JSON for params/features; arrays, geometries and poses become tagged objects."""
    if value is None or isinstance(value, bool | str):
        return value
    if isinstance(value, np.bool_):
        return bool(value)
    if isinstance(value, int | np.integer):
        return int(value)
    if isinstance(value, float | np.floating):
        if not math.isfinite(value):
            raise InputError(f"cannot save world: {field} is {float(value)!r}")
        return float(value)
    if isinstance(value, np.ndarray):
        if value.dtype.name not in ARRAY_DTYPES:
            raise InputError(f"cannot save world: {field} is an array of dtype {value.dtype}")
        return {
            TYPE_TAG: "ndarray",
            "dtype": value.dtype.name,
            "shape": list(value.shape),
            "data": _finite_list(value.reshape(-1), field),
        }
    if isinstance(value, Pose):
        return {TYPE_TAG: "Pose", "xytheta": _finite_list(value.as_array(), field)}
    if isinstance(value, shapely.Polygon):
        return {TYPE_TAG: "Polygon", **_polygon_to_json(value, field)}
    if isinstance(value, shapely.MultiPolygon):
        parts = [_polygon_to_json(p, f"{field}.polygons[{i}]") for i, p in enumerate(value.geoms)]
        return {TYPE_TAG: "MultiPolygon", "polygons": parts}
    if isinstance(value, shapely.LineString | shapely.Point):
        coords = _finite_list(np.asarray(value.coords, dtype=np.float64), field)
        return {TYPE_TAG: value.geom_type, "coords": coords}
    if isinstance(value, Mapping):
        out = {}
        for key, item in value.items():
            if not isinstance(key, str) or key == TYPE_TAG:
                raise InputError(f"cannot save world: {field} has key {key!r} (need str keys)")
            out[key] = _encode_value(item, f"{field}.{key}")
        return out
    if isinstance(value, list | tuple):
        return [_encode_value(item, f"{field}[{i}]") for i, item in enumerate(value)]
    raise InputError(f"cannot save world: {field} has unsupported type {type(value).__name__}")


# ---------------------------------------------------------------- reading


def load(path: str | os.PathLike[str]) -> World:
    """Read a world file written by ``save``; bad files raise ``InputError`` naming the problem."""
    p = Path(path)
    data = read_limited(p, MAX_WORLD_FILE_BYTES, "world file", "MAX_WORLD_FILE_BYTES")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise InputError(f"{p}: not UTF-8 text (byte {exc.start})") from exc
    return world_from_json(text, source=str(p))


class _DuplicateKeyError(Exception):
    pass


def _no_duplicate_keys(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            raise _DuplicateKeyError(key)
        out[key] = value
    return out


def world_from_json(text: str, *, source: str = "<string>", validate: bool = True) -> World:
    """Parse and check world JSON text; ``source`` names the file in error messages.

    ``validate=False`` skips the coordinate limits and the drivability checks (see
    ``worldgen.world_reader``); every command reads worlds with ``validate=True``.
    """
    if len(text) > MAX_WORLD_FILE_BYTES:
        raise InputError(
            f"{source}: {len(text)} characters, more than the limit of {MAX_WORLD_FILE_BYTES} "
            "(MAX_WORLD_FILE_BYTES)"
        )
    try:
        doc = parse_json(text, source, object_pairs_hook=_no_duplicate_keys)
    except _DuplicateKeyError as exc:
        raise InputError(f"{source}: duplicate key {exc.args[0]!r} in a JSON object") from exc
    return WorldReader(source, validate=validate).world(doc)
