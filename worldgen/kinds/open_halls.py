"""The ``open`` kind: large halls with irregular outlines, pillars and scattered furniture.

The hall is a union of overlapping rectangles (an orthogonal, non-corridor-like outline)
with some convex corners cut at 45 degrees; a few partition walls split it into sub-halls
without cutting it apart for the robot. Pillars stand on a structural grid and furniture
groups (tables with chairs, crates, plants) are scattered with robot-sized gaps.
"""

from __future__ import annotations

import numpy as np
import shapely

from worldgen.kinds import WorldKind
from worldgen.kinds._clutter import furnish_hall
from worldgen.kinds._plan import Layout, boxes
from worldgen.params import OpenParams
from worldgen.roadmap import BUFFER_SLACK_M

__all__ = ["irregular_hall", "layout_open", "open_features"]

_PART_MIN, _PART_MAX = 0.25, 0.6  # extra rectangles, as fractions of the hall's extent
_ANCHOR_INSET_M = 1.5  # new rectangles overlap old ones at least this deep
_PARTITION_TRIES = 8
_MAX_FILL = 0.9  # a hall fills at most this much of its bounding box
_NOTCH_MIN, _NOTCH_MAX = 0.2, 0.4  # corner notches, as fractions of the bounding box
_NOTCH_TRIES = 6


def _hall_parts(inner: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    x0, y0, x1, y1 = inner
    w, h = x1 - x0, y1 - y0
    size = rng.uniform(0.45, 0.75, 2) * [w, h]
    lo = rng.uniform([x0, y0], [x1, y1] - size)
    parts = [np.array([*lo, *(lo + size)])]
    for _ in range(n - 1):
        base = parts[int(rng.integers(len(parts)))]
        inset = np.minimum(_ANCHOR_INSET_M, 0.3 * (base[2:] - base[:2]))
        anchor = rng.uniform(base[:2] + inset, base[2:] - inset)
        size = rng.uniform(_PART_MIN, _PART_MAX, 2) * [w, h]
        lo = anchor - rng.uniform(0.2, 0.8, 2) * size
        new = np.concatenate([np.maximum(lo, [x0, y0]), np.minimum(lo + size, [x1, y1])])
        parts.append(new)
    return np.array(parts)


def _chamfers(
    hall: shapely.Polygon, fraction: float, rng: np.random.Generator, force: bool
) -> shapely.Geometry:
    """Cut convex corners of the outline at 45 degrees (at least one when ``force``)."""
    ring = np.asarray(shapely.orient_polygons(hall).exterior.coords)[:-1]
    prev, nxt = np.roll(ring, 1, axis=0), np.roll(ring, -1, axis=0)
    e1, e2 = ring - prev, nxt - ring
    l1, l2 = np.hypot(*e1.T), np.hypot(*e2.T)
    convex = (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]) > 0
    leg_max = np.minimum(4.0, 0.4 * np.minimum(l1, l2))
    cut = convex & (rng.random(len(ring)) < fraction) & (leg_max > 1.0)
    if force and not cut.any() and (convex & (leg_max > 1.0)).any():
        cut[np.flatnonzero(convex & (leg_max > 1.0))[0]] = True
    legs = rng.uniform(1.0, np.maximum(leg_max, 1.0))
    tris = []
    for k in np.flatnonzero(cut):
        u1, u2 = e1[k] / l1[k], e2[k] / l2[k]
        tris.append(shapely.Polygon([ring[k], ring[k] - u1 * legs[k], ring[k] + u2 * legs[k]]))
    if not tris:
        return hall
    return shapely.difference(hall, shapely.union_all(tris))


def _partitions(
    hall: shapely.Geometry, count: int, p: OpenParams, rng: np.random.Generator
) -> tuple[shapely.Geometry, int]:
    """Subtract partition walls that never cut the hall apart for the robot."""
    clearance = p.robot_radius_m + p.clearance_margin_m + BUFFER_SLACK_M
    x0, y0, x1, y1 = hall.bounds
    placed = 0
    for _ in range(count * _PARTITION_TRIES):
        if placed == count:
            break
        axis = int(rng.integers(2))
        extent = (x1 - x0, y1 - y0)[axis]
        length = rng.uniform(0.25, 0.6) * extent
        cx, cy = rng.uniform([x0, y0], [x1, y1])
        ht, hl = 0.5 * p.wall_thickness_m, 0.5 * length
        wall = (
            shapely.box(cx - hl, cy - ht, cx + hl, cy + ht)
            if axis == 0
            else shapely.box(cx - ht, cy - hl, cx + ht, cy + hl)
        )
        cut = shapely.difference(hall, wall)
        if cut.geom_type != "Polygon" or cut.area > hall.area - 0.5 * length * p.wall_thickness_m:
            continue  # split the hall, or barely touched it
        if shapely.buffer(cut, -clearance).geom_type != "Polygon":
            continue  # the robot could no longer get everywhere
        hall = cut
        placed += 1
    return hall, placed


def _notch(hall: shapely.Polygon, p: OpenParams, rng: np.random.Generator) -> shapely.Polygon:
    """Cut a rectangle out of one corner of the hall's bounding box (if that keeps the
    hall in one piece for the robot)."""
    x0, y0, x1, y1 = hall.bounds
    w, h = rng.uniform(_NOTCH_MIN, _NOTCH_MAX, 2) * [x1 - x0, y1 - y0]
    cx, cy = (x0, y0 + h) if rng.random() < 0.5 else (x1 - w, y1)
    if rng.random() < 0.5:
        cy = y1 if cy == y0 + h else y0 + h
    cut = shapely.difference(hall, shapely.box(cx, cy - h, cx + w, cy))
    clearance = p.robot_radius_m + p.clearance_margin_m + BUFFER_SLACK_M
    if cut.geom_type != "Polygon" or shapely.buffer(cut, -clearance).geom_type != "Polygon":
        return hall
    return cut


def irregular_hall(rect: np.ndarray, p: OpenParams, rng: np.random.Generator) -> shapely.Polygon:
    """The hall outline inside ``rect`` (outer wall ``wall_thickness_m`` thick).

    Unless ``hall_parts`` is 1, corners are notched until the hall fills at most
    ``_MAX_FILL`` of its bounding box, so it never degenerates into a plain rectangle."""
    t = p.wall_thickness_m
    inner = np.asarray(rect, float) + np.array([t, t, -t, -t])
    hall = shapely.union_all(boxes(_hall_parts(inner, p.hall_parts, rng)))
    hall = shapely.normalize(shapely.simplify(hall, 0.0))
    for _ in range(_NOTCH_TRIES if p.hall_parts > 1 else 0):
        if hall.area / shapely.envelope(hall).area <= _MAX_FILL:
            break
        hall = _notch(hall, p, rng)
    square = hall.area / shapely.envelope(hall).area > 0.97
    return _chamfers(hall, p.chamfer_fraction, rng, force=square and p.chamfer_fraction > 0)


def open_features(hall: shapely.Geometry, pillars: int, partitions: int) -> dict:
    return {
        "hall_area_m2": float(hall.area),
        "hall_fill_ratio": float(hall.area / shapely.envelope(hall).area),
        "boundary_vertices": len(shapely.get_coordinates(shapely.boundary(hall))),
        "pillars": pillars,
        "partition_walls": partitions,
    }


def layout_open(rect: np.ndarray, p: OpenParams, rng: np.random.Generator) -> Layout:
    hall = irregular_hall(rect, p, rng)
    hall, partitions = _partitions(hall, p.partition_walls, p, rng)
    pillars, furniture = furnish_hall(
        hall, rng, p, pillar_spacing_m=p.pillar_spacing_m, pillar_size_m=p.pillar_size_m
    )
    layout = Layout(floor=[hall], clutter=[*pillars, *furniture], links=None)
    layout.features.update(open_features(hall, len(pillars), partitions))
    return layout


KIND = WorldKind(
    name="open",
    params=OpenParams,
    layout=layout_open,
    summary="large halls with irregular outlines, pillars and furniture",
)
