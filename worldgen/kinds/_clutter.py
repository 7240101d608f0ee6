"""Furniture-sized clutter: desks and shelves against walls, tables with chairs, crates,
plants and pillars, placed so the robot can still get everywhere.

Placement rule that keeps every room traversable: free-standing groups keep ``passage_m``
(a robot-sized gap) from walls, door zones and every other item; wall items sit flush
against a wall and keep ``passage_m`` from every other item and out of door zones. Items are
sampled in vectorised batches and accepted greedily against the ones already placed.
"""

from __future__ import annotations

import numpy as np
import shapely
from numpy.typing import NDArray

from worldgen.kinds._plan import boxes
from worldgen.params import CommonParams

__all__ = ["furnish_hall", "furnish_rects", "furnish_region", "pillar_grid", "rect_gaps"]

FloatArray = NDArray[np.float64]

CHAIR_M = 0.45
CHAIR_GAP_M = 0.12
_TRIES_PER_ITEM = 4
# free-standing kinds: table with chairs, round table with chairs, crate, plant
_FREE_P = np.array([0.4, 0.2, 0.25, 0.15])
# wall kinds (length range, depth range): desk, shelf, cabinet, sofa
_WALL = np.array(
    [[1.2, 1.6, 0.6, 0.8], [0.8, 2.0, 0.3, 0.45], [0.5, 1.0, 0.4, 0.6], [1.6, 2.2, 0.8, 0.9]]
)
_WALL_P = np.array([0.4, 0.3, 0.2, 0.1])


def rect_gaps(r: FloatArray, others: FloatArray) -> FloatArray:
    """Euclidean gap between rectangle ``r`` (4,) and each of ``others`` (M, 4); 0 if touching."""
    dx = np.maximum(0.0, np.maximum(others[:, 0] - r[2], r[0] - others[:, 2]))
    dy = np.maximum(0.0, np.maximum(others[:, 1] - r[3], r[1] - others[:, 3]))
    return np.hypot(dx, dy)


def _overlaps(r: FloatArray, others: FloatArray) -> NDArray[np.bool_]:
    return (
        (others[:, 0] < r[2])
        & (r[0] < others[:, 2])
        & (others[:, 1] < r[3])
        & (r[1] < others[:, 3])
    )


def _overlaps_any(rects: FloatArray, others: FloatArray) -> NDArray[np.bool_]:
    """For each of ``rects`` (N, 4): does it overlap any of ``others`` (M, 4)?"""
    if len(rects) == 0 or len(others) == 0:
        return np.zeros(len(rects), dtype=bool)
    a, b = rects[:, None, :], others[None, :, :]
    hit = (b[..., 0] < a[..., 2]) & (a[..., 0] < b[..., 2])
    hit &= (b[..., 1] < a[..., 3]) & (a[..., 1] < b[..., 3])
    return np.asarray(hit.any(axis=1))


def _rot_rect(cx: float, cy: float, w: float, d: float, angle: float) -> FloatArray:
    c, s = np.cos(angle), np.sin(angle)
    local = np.array([[-w, -d], [w, -d], [w, d], [-w, d]]) * 0.5
    return local @ np.array([[c, s], [-s, c]]) + [cx, cy]


def _octagon(cx: float, cy: float, r: float) -> FloatArray:
    a = np.arange(8) * (np.pi / 4) + np.pi / 8
    return np.column_stack([cx + r * np.cos(a), cy + r * np.sin(a)])


def _sample_free(rng: np.random.Generator, m: int) -> tuple[NDArray[np.int64], FloatArray]:
    """Kinds and parameters ``(m, 4)`` of free-standing groups, plus half extents."""
    kind = rng.choice(len(_FREE_P), size=m, p=_FREE_P)
    u = rng.random((m, 4))
    prm = np.zeros((m, 4))
    half = np.zeros((m, 2))
    # table: length, depth, turned (0/1), seed; chairs on both long sides
    t = kind == 0
    prm[t, 0] = 0.8 + 1.0 * u[t, 0]
    prm[t, 1] = 0.7 + 0.3 * u[t, 1]
    prm[t, 2] = u[t, 2] < 0.5
    reach = CHAIR_GAP_M + CHAIR_M
    hw, hd = 0.5 * prm[t, 0], 0.5 * prm[t, 1] + reach
    half[t] = np.where(prm[t, 2:3] > 0, np.column_stack([hd, hw]), np.column_stack([hw, hd]))
    # round table: radius; chairs around
    r = kind == 1
    prm[r, 0] = 0.4 + 0.2 * u[r, 0]
    half[r] = (prm[r, 0] + reach)[:, None]
    # crate: side, angle
    c = kind == 2
    prm[c, 0] = 0.4 + 0.6 * u[c, 0]
    prm[c, 1] = 0.5 * np.pi * u[c, 1]
    ext = 0.5 * prm[c, 0] * (np.abs(np.cos(prm[c, 1])) + np.abs(np.sin(prm[c, 1])))
    half[c] = ext[:, None]
    # plant or bin: radius
    p = kind == 3
    prm[p, 0] = 0.15 + 0.15 * u[p, 0]
    half[p] = prm[p, 0][:, None]
    prm[:, 3] = u[:, 3]
    return kind, np.column_stack([prm, half])


def _free_polygons(
    kind: int, prm: FloatArray, cx: float, cy: float, rng: np.random.Generator
) -> list[FloatArray]:
    if kind == 0:
        length, depth, turned = prm[0], prm[1], prm[2] > 0
        angle = 0.5 * np.pi if turned else 0.0
        out = [_rot_rect(cx, cy, length, depth, angle)]
        n_side = max(1, int(length / 0.6))
        along = (np.arange(n_side) - 0.5 * (n_side - 1)) * (length / n_side)
        off = 0.5 * depth + CHAIR_GAP_M + 0.5 * CHAIR_M
        for side in (-1.0, 1.0):
            for a in along:
                if rng.random() < 0.2:
                    continue  # an empty seat
                dx, dy = (side * off, a) if turned else (a, side * off)
                jitter = rng.uniform(-0.25, 0.25)
                out.append(_rot_rect(cx + dx, cy + dy, CHAIR_M, CHAIR_M, jitter))
        return out
    if kind == 1:
        radius = prm[0]
        out = [_octagon(cx, cy, radius)]
        n = int(rng.integers(3, 5))
        start = rng.uniform(0, 2 * np.pi)
        off = radius + CHAIR_GAP_M + 0.5 * CHAIR_M
        for k in range(n):
            a = start + 2 * np.pi * k / n
            out.append(_rot_rect(cx + off * np.cos(a), cy + off * np.sin(a), CHAIR_M, CHAIR_M, a))
        return out
    if kind == 2:
        return [_rot_rect(cx, cy, prm[0], prm[0], prm[1])]
    return [_octagon(cx, cy, prm[0])]


def _accept(cands: FloatArray, placed: FloatArray, gap_m: float, want: int) -> list[int]:
    """Greedy: indices of candidate rectangles kept ``gap_m`` apart from ``placed`` and
    from each other, at most ``want`` of them."""
    kept: list[int] = []
    taken = [placed] if len(placed) else []
    for k in range(len(cands)):
        if len(kept) >= want:
            break
        if taken:
            current = np.vstack(taken)
            if (rect_gaps(cands[k], current) < gap_m).any():
                continue
        kept.append(k)
        taken.append(cands[k : k + 1])
    return kept


def _polygons(coords: list[FloatArray]) -> list[shapely.Polygon]:
    return [shapely.Polygon(c) for c in coords]


def furnish_rects(
    interiors: FloatArray,
    rng: np.random.Generator,
    *,
    per_10m2: float,
    passage_m: float,
    zones: FloatArray,
    wall_share: float = 0.55,
    walls_along_x: NDArray[np.bool_] | None = None,
    max_wall_depth_m: FloatArray | None = None,
) -> list[shapely.Polygon]:
    """Furnish rectangular rooms: wall items flush to walls and free-standing groups.

    ``walls_along_x`` (one per room) puts wall items only on the two walls running along x
    (True) or along y (False), for corridor stretches whose ends are open;
    ``max_wall_depth_m`` (one per room) caps how far wall items reach into the room, e.g.
    to keep a corridor's centre line clear."""
    rooms = np.asarray(interiors, float).reshape(-1, 4)
    zones = np.asarray(zones, float).reshape(-1, 4)
    area = (rooms[:, 2] - rooms[:, 0]) * (rooms[:, 3] - rooms[:, 1])
    counts = rng.poisson(per_10m2 * area / 10.0)
    coords: list[FloatArray] = []
    depth_cap = np.full(len(rooms), np.inf) if max_wall_depth_m is None else max_wall_depth_m
    along = [None] * len(rooms) if walls_along_x is None else [bool(v) for v in walls_along_x]
    for room, n, cap, along_x in zip(rooms, counts, depth_cap, along, strict=True):
        if n == 0:
            continue
        m = _TRIES_PER_ITEM * int(n)
        near = zones[_overlaps(room, zones)] if len(zones) else zones
        cands, makers = _room_candidates(room, m, rng, passage_m, wall_share, along_x, float(cap))
        idx = np.flatnonzero(~_overlaps_any(cands, near))
        kept = _accept(cands[idx], np.zeros((0, 4)), passage_m, int(n))
        for k in idx[kept]:
            coords.extend(makers[k](rng))
    return _polygons(coords)


def _room_candidates(
    room: FloatArray,
    m: int,
    rng: np.random.Generator,
    passage_m: float,
    wall_share: float,
    along_x: bool | None,
    depth_cap: float,
) -> tuple[FloatArray, list]:
    x0, y0, x1, y1 = room
    kinds, prm = _sample_free(rng, m)
    is_wall = rng.random(m) < wall_share
    wall_kind = rng.choice(len(_WALL), size=m, p=_WALL_P)
    side = rng.integers(0, 4, m)
    if along_x is not None:
        # sides 0/2 are the walls along x, 1/3 the walls along y
        side = 2 * (side % 2) + (0 if along_x else 1)
    u = rng.random((m, 3))
    cands = np.full((m, 4), np.nan)
    makers: list = [None] * m
    for k in range(m):
        if is_wall[k]:
            lo_l, hi_l, lo_d, hi_d = _WALL[wall_kind[k]]
            length = lo_l + (hi_l - lo_l) * u[k, 0]
            depth = lo_d + (hi_d - lo_d) * u[k, 1]
            horizontal = side[k] in (0, 2)
            span = (x1 - x0) if horizontal else (y1 - y0)
            room_depth = (y1 - y0) if horizontal else (x1 - x0)
            if length > span or depth > min(room_depth - passage_m, depth_cap):
                continue
            a = (x0 if horizontal else y0) + (span - length) * u[k, 2]
            rect = {
                0: (a, y0, a + length, y0 + depth),
                2: (a, y1 - depth, a + length, y1),
                1: (x1 - depth, a, x1, a + length),
                3: (x0, a, x0 + depth, a + length),
            }[int(side[k])]
            cands[k] = rect
            makers[k] = lambda _rng, r=rect: [
                _rot_rect(0.5 * (r[0] + r[2]), 0.5 * (r[1] + r[3]), r[2] - r[0], r[3] - r[1], 0.0)
            ]
        else:
            hx, hy = prm[k, 4], prm[k, 5]
            lo_x, hi_x = x0 + passage_m + hx, x1 - passage_m - hx
            lo_y, hi_y = y0 + passage_m + hy, y1 - passage_m - hy
            if lo_x > hi_x or lo_y > hi_y:
                continue
            cx, cy = lo_x + (hi_x - lo_x) * u[k, 0], lo_y + (hi_y - lo_y) * u[k, 1]
            cands[k] = (cx - hx, cy - hy, cx + hx, cy + hy)
            makers[k] = lambda r, kk=int(kinds[k]), pp=prm[k], x=cx, y=cy: _free_polygons(
                kk, pp, x, y, r
            )
    good = ~np.isnan(cands[:, 0])
    return cands[good], [mk for mk, g in zip(makers, good, strict=True) if g]


def furnish_region(
    region: shapely.Polygon,
    rng: np.random.Generator,
    *,
    per_10m2: float,
    passage_m: float,
    avoid: FloatArray,
    placed: FloatArray | None = None,
) -> list[shapely.Polygon]:
    """Scatter free-standing groups in an arbitrary polygon, ``passage_m`` from its boundary,
    from the ``avoid`` rectangles and from the already ``placed`` item rectangles."""
    n = int(rng.poisson(per_10m2 * region.area / 10.0))
    if n == 0:
        return []
    m = _TRIES_PER_ITEM * n
    kinds, prm = _sample_free(rng, m)
    x0, y0, x1, y1 = region.bounds
    centre = rng.uniform([x0, y0], [x1, y1], size=(m, 2))
    half = prm[:, 4:6]
    cands = np.hstack([centre - half, centre + half])
    inner = shapely.buffer(region, -passage_m, join_style="mitre")
    shapely.prepare(inner)
    ok = shapely.contains(inner, boxes(cands))
    avoid = np.asarray(avoid, float).reshape(-1, 4)
    ok &= ~_overlaps_any(cands, avoid)
    idx = np.flatnonzero(ok)
    before = np.zeros((0, 4)) if placed is None else np.asarray(placed, float).reshape(-1, 4)
    kept = idx[_accept(cands[idx], before, passage_m, n)]
    coords: list[FloatArray] = []
    for k in kept:
        coords.extend(_free_polygons(int(kinds[k]), prm[k], centre[k, 0], centre[k, 1], rng))
    return _polygons(coords)


def pillar_grid(
    region: shapely.Polygon,
    rng: np.random.Generator,
    *,
    spacing_m: float,
    size_m: float,
    passage_m: float,
) -> tuple[list[shapely.Polygon], FloatArray]:
    """Structural columns on a regular grid, kept ``passage_m`` inside ``region``.

    Returns the pillar polygons and their bounding rectangles."""
    if spacing_m <= 0.0:
        return [], np.zeros((0, 4))
    x0, y0, x1, y1 = region.bounds
    off = rng.uniform(0.0, spacing_m, 2)
    xs = np.arange(x0 + off[0], x1, spacing_m)
    ys = np.arange(y0 + off[1], y1, spacing_m)
    gx, gy = np.meshgrid(xs, ys)
    h = 0.5 * size_m
    rects = np.column_stack([gx.ravel() - h, gy.ravel() - h, gx.ravel() + h, gy.ravel() + h])
    inner = shapely.buffer(region, -passage_m, join_style="mitre")
    shapely.prepare(inner)
    rects = rects[shapely.contains(inner, boxes(rects))]
    round_pillars = rng.random() < 0.4
    polys = [
        shapely.Polygon(_octagon(0.5 * (r[0] + r[2]), 0.5 * (r[1] + r[3]), h))
        if round_pillars
        else shapely.box(*r)
        for r in rects
    ]
    return polys, rects


def furnish_hall(
    hall: shapely.Polygon,
    rng: np.random.Generator,
    p: CommonParams,
    *,
    pillar_spacing_m: float,
    pillar_size_m: float,
    avoid: FloatArray | None = None,
) -> tuple[list[shapely.Polygon], list[shapely.Polygon]]:
    """A hall's pillars (``pillar_grid``), then its free-standing furniture
    (``furnish_region`` at ``p``'s clutter density), clear of the pillars and of the
    ``avoid`` rectangles; returns (pillars, furniture)."""
    pillars, pillar_rects = pillar_grid(
        hall, rng, spacing_m=pillar_spacing_m, size_m=pillar_size_m, passage_m=p.passage_m
    )
    furniture = furnish_region(
        hall,
        rng,
        per_10m2=p.clutter_per_10m2,
        passage_m=p.passage_m,
        avoid=np.zeros((0, 4)) if avoid is None else avoid,
        placed=pillar_rects,
    )
    return pillars, furniture
