"""The ``office`` kind, after the paper's Fig. 6: a corridor ring lined with rooms, cross
corridors through the core, rooms on both sides and an open area off the corridors.

Cell layout (wall centre lines): a band of rooms along each outer wall, the ring corridor
inside it, and the core split by cross corridors into blocks of one or two rows of rooms.
``open_areas`` blocks become halls with wide openings, pillars and furniture. Each room
gets a door onto a corridor when it touches one, otherwise onto a connected neighbour.
"""

from __future__ import annotations

import itertools

import numpy as np
import shapely

from worldgen.kinds import WorldKind
from worldgen.kinds._clutter import furnish_hall, furnish_rects
from worldgen.kinds._doors import door_links, hall_links
from worldgen.kinds._plan import (
    JAMB_M,
    Adjacency,
    Layout,
    adjacency,
    boxes,
    cell_centrelines,
    centreline_links,
    door_approaches,
    door_rects,
    foot_on_segments,
    partition_1d,
    shrink,
)
from worldgen.params import OfficeParams

__all__ = ["layout_office"]

_OPENING_MIN_M = 2.5
_OPENING_MAX_M = 8.0
_SECOND_OPENING_P = 0.3
_HALL_PILLAR_SPACING_M = 6.0
_HALL_PILLAR_SIZE_M = 0.4


def _rows(block: np.ndarray, p: OfficeParams, rng: np.random.Generator) -> list[np.ndarray]:
    """Rooms of one block: one or two rows along its long side."""
    x0, y0, x1, y1 = block
    long_x = (x1 - x0) >= (y1 - y0)
    depth = (y1 - y0) if long_x else (x1 - x0)
    if depth >= 2.0 * p.room_depth_min_m:
        split = depth * rng.uniform(0.4, 0.6)
        bands = [(0.0, split), (split, depth)]
    else:
        bands = [(0.0, depth)]
    rooms = []
    for d0, d1 in bands:
        if long_x:
            cuts = partition_1d(x0, x1, rng, p.room_width_min_m, p.room_width_max_m)
            rooms += [[a, y0 + d0, b, y0 + d1] for a, b in itertools.pairwise(cuts)]
        else:
            cuts = partition_1d(y0, y1, rng, p.room_width_min_m, p.room_width_max_m)
            rooms += [[x0 + d0, a, x0 + d1, b] for a, b in itertools.pairwise(cuts)]
    return [np.array(r) for r in rooms]


def _band_rooms(
    band: np.ndarray, along_x: bool, p: OfficeParams, rng: np.random.Generator
) -> list[np.ndarray]:
    x0, y0, x1, y1 = band
    if along_x:
        cuts = partition_1d(x0, x1, rng, p.room_width_min_m, p.room_width_max_m)
        return [np.array([a, y0, b, y1]) for a, b in itertools.pairwise(cuts)]
    cuts = partition_1d(y0, y1, rng, p.room_width_min_m, p.room_width_max_m)
    return [np.array([x0, a, x1, b]) for a, b in itertools.pairwise(cuts)]


def _cross_lines(
    lo: float, hi: float, n: int, cell_w: float, rng: np.random.Generator
) -> list[float]:
    """Lower edges of ``n`` cross-corridor cells spread over ``[lo, hi]``, jittered."""
    if n <= 0:
        return []
    span = hi - lo - n * cell_w
    piece = span / (n + 1)
    starts = lo + piece * np.arange(1, n + 1) + cell_w * np.arange(n)
    return list(starts + rng.uniform(-0.15, 0.15, n) * piece)


def _one_per_room(adj: Adjacency, rng: np.random.Generator) -> np.ndarray:
    """Mask choosing one random adjacency row per room ``i``."""
    mask = np.zeros(len(adj), dtype=bool)
    if len(adj):
        order = rng.permutation(len(adj))
        _, first = np.unique(adj.i[order], return_index=True)
        mask[order[first]] = True
    return mask


def _first_per_room(adj: Adjacency, rng: np.random.Generator) -> Adjacency:
    """One random adjacency row per room ``i``."""
    return adj.take(_one_per_room(adj, rng))


def _connect_rooms(
    rooms: np.ndarray, corridors: np.ndarray, p: OfficeParams, rng: np.random.Generator
) -> tuple[Adjacency, Adjacency]:
    """Door adjacencies (room to corridor, room to room): a corridor door for each room
    touching a corridor, then doors to already-connected neighbours for the rest, then a
    few extra room-to-room doors."""
    min_overlap = p.door_width_max_m + p.wall_thickness_m + 2.0 * JAMB_M
    to_corridor = _first_per_room(adjacency(rooms, corridors, min_overlap_m=min_overlap), rng)
    connected = np.zeros(len(rooms), dtype=bool)
    connected[to_corridor.i] = True
    between = adjacency(rooms, min_overlap_m=min_overlap)
    used = np.zeros(len(between), dtype=bool)
    links = []
    while True:
        rows = np.flatnonzero(connected[between.i] ^ connected[between.j])
        if len(rows) == 0:
            break
        frontier = between.take(rows)
        # orient every row as (new room, connected room), pick one per new room
        new = np.where(connected[frontier.i], frontier.j, frontier.i)
        old = np.where(connected[frontier.i], frontier.i, frontier.j)
        sign = np.where(connected[frontier.i], -frontier.sign, frontier.sign)
        oriented = Adjacency(
            new, old, frontier.axis, frontier.coord, frontier.lo, frontier.hi, sign
        )
        chosen = _one_per_room(oriented, rng)
        pick = oriented.take(chosen)
        used[rows[chosen]] = True
        links.append(pick)
        connected[pick.i] = True
    extra = between.take(~used & (rng.random(len(between)) < p.extra_door_fraction))
    return to_corridor, Adjacency.concat([*links, extra])


def layout_office(rect: np.ndarray, p: OfficeParams, rng: np.random.Generator) -> Layout:
    ht = 0.5 * p.wall_thickness_m
    X0, Y0, X1, Y1 = np.asarray(rect, float) + np.array([ht, ht, -ht, -ht])
    cw = rng.uniform(p.corridor_width_min_m, p.corridor_width_max_m)
    cell_w = cw + p.wall_thickness_m
    dl, dr, db, dt = rng.uniform(p.room_depth_min_m, p.room_depth_max_m, 4)
    xa, xd = X0 + dl, X1 - dr
    ya, yd = Y0 + db, Y1 - dt
    xb, xc, yb, yc = xa + cell_w, xd - cell_w, ya + cell_w, yd - cell_w

    corridors = [[xa, ya, xb, yd], [xc, ya, xd, yd], [xa, ya, xd, yb], [xa, yc, xd, yd]]
    rooms = _band_rooms(np.array([X0, Y0, xa, Y1]), False, p, rng)
    rooms += _band_rooms(np.array([xd, Y0, X1, Y1]), False, p, rng)
    rooms += _band_rooms(np.array([xa, Y0, xd, ya]), True, p, rng)
    rooms += _band_rooms(np.array([xa, yd, xd, Y1]), True, p, rng)

    strip = 2.0 * 0.5 * (p.room_depth_min_m + p.room_depth_max_m)
    n_h = max(0, round((yc - yb + cell_w) / (strip + cell_w)) - 1)
    n_v = max(0, int(np.ceil((xc - xb) / p.block_length_max_m)) - 1)
    ys = _cross_lines(yb, yc, n_h, cell_w, rng)
    xs = _cross_lines(xb, xc, n_v, cell_w, rng)
    corridors += [[xa, y, xd, y + cell_w] for y in ys]
    corridors += [[x, ya, x + cell_w, yd] for x in xs]
    x_edges = [xb, *[v for x in xs for v in (x, x + cell_w)], xc]
    y_edges = [yb, *[v for y in ys for v in (y, y + cell_w)], yc]
    blocks = np.array(
        [
            [x_edges[i], y_edges[j], x_edges[i + 1], y_edges[j + 1]]
            for j in range(0, len(y_edges), 2)
            for i in range(0, len(x_edges), 2)
        ]
    )
    hall_ids = rng.choice(len(blocks), size=min(p.open_areas, len(blocks)), replace=False)
    halls = blocks[np.sort(hall_ids)].reshape(-1, 4)
    for k, block in enumerate(blocks):
        if k not in hall_ids:
            rooms += _rows(block, p, rng)
    room_cells = np.array(rooms)
    corridor_cells = np.array(corridors)

    door_kw = {
        "wall_thickness_m": p.wall_thickness_m,
        "zone_depth_m": p.passage_m + 0.3,
    }
    to_corridor, between = _connect_rooms(room_cells, corridor_cells, p, rng)
    adj = Adjacency.concat([to_corridor, between])
    j_is_room = np.arange(len(adj)) >= len(to_corridor)
    doors, segs, zones = door_rects(
        adj, rng, width_min_m=p.door_width_min_m, width_max_m=p.door_width_max_m, **door_kw
    )
    hall_min = _OPENING_MIN_M + p.wall_thickness_m + 2.0 * JAMB_M
    hall_adj = adjacency(halls, corridor_cells, min_overlap_m=hall_min)
    # every hall opens onto one corridor, some onto a second
    keep = _one_per_room(hall_adj, rng) | (rng.random(len(hall_adj)) < _SECOND_OPENING_P)
    hall_adj = hall_adj.take(keep)
    o_rect, o_seg, o_zone = door_rects(
        hall_adj, rng, width_min_m=_OPENING_MIN_M, width_max_m=_OPENING_MAX_M, **door_kw
    )

    room_in = shrink(room_cells, ht)
    hall_in = shrink(halls, ht)
    dl = door_links(
        room_in, doors, adj, j_is_room, offset_m=p.approach_m, lane_half_width_m=p.lane_half_width_m
    )
    hall_pts, hall_corr = door_approaches(o_rect, hall_adj, p.approach_m)
    centres = cell_centrelines(corridor_cells)
    corr_pts = np.vstack([dl.outer_points, hall_corr])
    corr_idx = np.concatenate([dl.outer_cells, hall_adj.j])
    feet = foot_on_segments(corr_pts, centres, corr_idx)
    links = [
        dl.links,
        np.hstack([corr_pts, feet]),
        np.hstack([hall_pts, hall_corr]),
        centreline_links(centres, feet),
    ]
    clutter = furnish_rects(
        room_in,
        rng,
        per_10m2=p.clutter_per_10m2,
        passage_m=p.passage_m,
        zones=np.vstack([zones, o_zone, dl.lanes]),
    )
    for k, hall in enumerate(hall_in):
        poly = shapely.box(*hall)
        pillars, furniture = furnish_hall(
            poly,
            rng,
            p,
            pillar_spacing_m=_HALL_PILLAR_SPACING_M,
            pillar_size_m=_HALL_PILLAR_SIZE_M,
            avoid=o_zone,
        )
        clutter += pillars + furniture
        links.append(_hall_links(poly, pillars + furniture, hall_pts[hall_adj.i == k], p))

    floor = [*boxes(room_in), *boxes(shrink(corridor_cells, ht)), *boxes(hall_in)]
    floor += [*boxes(doors), *boxes(o_rect)]
    ring = np.array([[xa, ya], [xd, ya], [xd, yd], [xa, yd], [xa, ya]]) + 0.5 * cell_w * np.array(
        [[1, 1], [-1, 1], [-1, -1], [1, -1], [1, 1]]
    )
    layout = Layout(floor=floor, clutter=clutter, doorways=[segs], links=links)
    layout.features.update(
        rooms=len(room_cells),
        wall_thickness_m=p.wall_thickness_m,
        corridor_width_m=[float(cw), float(cw)],
        corridor_ring=ring.tolist(),
        ring_length_m=float(np.hypot(*np.diff(ring, axis=0).T).sum()),
        cross_corridors=len(xs) + len(ys),
        open_areas=hall_in.tolist(),
        openings=o_seg.tolist(),
    )
    return layout


def _hall_links(
    hall: shapely.Polygon, clutter: list, entries: np.ndarray, p: OfficeParams
) -> np.ndarray:
    return hall_links(
        hall, clutter, entries, clearance_m=p.node_clearance_m, robot_radius_m=p.robot_radius_m
    )


KIND = WorldKind(
    name="office",
    params=OfficeParams,
    layout=layout_office,
    summary="a corridor ring lined with rooms, cross corridors and an open area (Fig. 6)",
    reports_doorways=True,
)
