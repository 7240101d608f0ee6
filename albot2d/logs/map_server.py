"""Occupancy grids as ROS ``map_server`` maps: ``NAME.pgm`` + ``NAME.yaml``.

The format ``map_server`` / nav2's ``map_server`` load and ``map_saver`` writes: a YAML
file naming the image, its ``resolution`` (m per pixel), ``origin`` (the map-frame pose
``[x, y, yaw]`` of the image's lower-left pixel), ``negate``, ``occupied_thresh``,
``free_thresh`` and ``mode``; and a greyscale image whose top row is the grid's highest
row. ``map_server_files`` writes trinary maps as ``map_saver`` does: occupied 0 (black),
free 254 (white), unknown 205 (grey), with map_saver's thresholds (0.65, 0.196), so a
pixel's occupancy ``p = (255 − value) / 255`` reads back as 100 (p > 0.65), 0 (p < 0.196)
or −1 (205: p = 0.19608).

``read_map_server`` loads any ``map_server`` map (trinary, scale or raw; any image format
Pillow reads; needs the ``[maps]`` extra: PyYAML and Pillow) into an ``OccupancyGrid``.
"""

from __future__ import annotations

import math
import os
import re
from pathlib import Path
from typing import Any

import numpy as np

from albot2d.errors import InputError
from albot2d.geometry.grid import FREE, OCCUPIED, UNKNOWN, OccupancyGrid

__all__ = [
    "FREE_PIXEL",
    "FREE_THRESH",
    "OCCUPIED_PIXEL",
    "OCCUPIED_THRESH",
    "UNKNOWN_PIXEL",
    "map_server_files",
    "map_yaml_text",
    "pgm_bytes",
    "read_map_server",
]

OCCUPIED_PIXEL = 0
FREE_PIXEL = 254
UNKNOWN_PIXEL = 205
OCCUPIED_THRESH = 0.65
FREE_THRESH = 0.196
MISSING_EXTRA = "reading map_server maps needs the optional extra: pip install 'albot2d[maps]'"
_SAFE_NAME = re.compile(r"^[A-Za-z0-9_.-]+$")


def pgm_bytes(grid: OccupancyGrid) -> bytes:
    """The grid as a binary (P5) 8-bit PGM image, top row = the grid's highest row."""
    pixels = np.full(grid.cells.shape, UNKNOWN_PIXEL, dtype=np.uint8)
    pixels[grid.cells == FREE] = FREE_PIXEL
    pixels[grid.cells == OCCUPIED] = OCCUPIED_PIXEL
    header = f"P5\n# albot2d occupancy grid, {grid.resolution_m:g} m/pixel\n"
    header += f"{grid.width} {grid.height}\n255\n"
    return header.encode("ascii") + np.ascontiguousarray(pixels[::-1]).tobytes()


def map_yaml_text(grid: OccupancyGrid, image: str) -> str:
    """The map's YAML file naming ``image`` (a file name beside it)."""
    origin = ", ".join(repr(float(v)) for v in (grid.origin_x_m, grid.origin_y_m,
                                                 grid.origin_yaw_rad))  # fmt: skip
    return (
        f"image: {image}\n"
        "mode: trinary\n"
        f"resolution: {grid.resolution_m!r}\n"
        f"origin: [{origin}]\n"
        "negate: 0\n"
        f"occupied_thresh: {OCCUPIED_THRESH}\n"
        f"free_thresh: {FREE_THRESH}\n"
    )


def map_server_files(grid: OccupancyGrid, name: str) -> dict[str, bytes]:
    """``{"NAME.pgm": ..., "NAME.yaml": ...}`` (``name``: a plain file stem)."""
    if not _SAFE_NAME.match(name):
        raise ValueError(f"map name {name!r}: use letters, digits, '_', '-' and '.' only")
    image = f"{name}.pgm"
    return {image: pgm_bytes(grid), f"{name}.yaml": map_yaml_text(grid, image).encode("utf-8")}


def _field(doc: dict[str, Any], key: str, where: Path) -> Any:
    if key not in doc:
        raise InputError(f"{where}: map YAML has no {key!r}")
    return doc[key]


def _number(value: Any, key: str, where: Path) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError):
        number = math.nan
    if not math.isfinite(number) or isinstance(value, bool):
        raise InputError(f"{where}: {key} must be a number, got {value!r}")
    return number


def read_map_server(path: str | os.PathLike[str]) -> OccupancyGrid:
    """Load a ``map_server`` map (its YAML file) as an ``OccupancyGrid``: pixels are
    interpreted as ``map_server`` does for the YAML's ``mode`` (trinary by default)."""
    try:
        import yaml
        from PIL import Image
    except ImportError as exc:
        raise InputError(MISSING_EXTRA) from exc
    where = Path(path)
    try:
        doc = yaml.safe_load(where.read_text(encoding="utf-8"))
    except OSError as exc:
        raise InputError(f"{where}: cannot read the map YAML ({exc.strerror})") from None
    except (yaml.YAMLError, UnicodeDecodeError) as exc:
        raise InputError(f"{where}: not a YAML file ({str(exc).splitlines()[0]})") from None
    if not isinstance(doc, dict):
        raise InputError(f"{where}: a map YAML is a mapping of keys, got {type(doc).__name__}")
    resolution = _number(_field(doc, "resolution", where), "resolution", where)
    origin = _field(doc, "origin", where)
    if not isinstance(origin, list) or len(origin) != 3:
        raise InputError(f"{where}: origin must be [x, y, yaw], got {origin!r}")
    ox, oy, oyaw = (_number(v, "origin", where) for v in origin)
    occupied = _number(doc.get("occupied_thresh", OCCUPIED_THRESH), "occupied_thresh", where)
    free = _number(doc.get("free_thresh", FREE_THRESH), "free_thresh", where)
    negate = bool(doc.get("negate", 0))
    mode = str(doc.get("mode", "trinary"))
    if mode not in ("trinary", "scale", "raw"):
        raise InputError(f"{where}: mode must be trinary, scale or raw, got {mode!r}")
    image_path = where.parent / str(_field(doc, "image", where))
    try:
        with Image.open(image_path) as image:
            has_alpha = image.mode in ("RGBA", "LA") or "transparency" in image.info
            rgba = np.asarray(image.convert("RGBA"), dtype=np.float64)
    except OSError as exc:
        raise InputError(f"{where}: cannot read its image {image_path} ({exc})") from None
    value = rgba[:, :, :3].mean(axis=2)  # map_server averages the colour channels
    if mode == "raw":  # the pixel value itself, as the message's int8 holds it (255 → −1)
        raw = np.ascontiguousarray(value.round().astype(np.uint8)[::-1]).view(np.int8)
        return OccupancyGrid(raw, resolution, ox, oy, oyaw)
    else:
        p = value / 255.0 if negate else (255.0 - value) / 255.0
        cells = np.full(p.shape, UNKNOWN, dtype=np.int16)
        cells[p > occupied] = OCCUPIED
        cells[p < free] = FREE
        if mode == "scale":
            between = (p >= free) & (p <= occupied)
            cells[between] = np.round(99.0 * (p[between] - free) / (occupied - free))
            if has_alpha:
                cells[rgba[:, :, 3] < 255] = UNKNOWN
    return OccupancyGrid(cells[::-1].astype(np.int8), resolution, ox, oy, oyaw)
