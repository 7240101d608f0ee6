"""The ``fig6`` kind: the paper's test environment (Yeap et al., Fig. 6) as a seeded plan.

A loop of corridors (a rectangular ring with one cross corridor near its left end) lined
with rooms, and an open area off the top corridor. Every seed draws a different building
of the same shape: ring size, cross-corridor offset, corridor width, room depths and
widths, the hall's extent, doors and furniture.

Named waypoints (``features["waypoints"]``, centre-line points, ``[x, y]``): ``S`` on the
left corridor, ``E1`` its bottom-left corner, ``E2``/``E3`` the bottom-right and top-right
corners, ``E4`` the middle of the top corridor (in the open area), ``E5`` the top end of the
cross corridor, ``E6`` its bottom end, ``E7`` the top-left corner, ``E8`` = ``E5``'s place
reached from the left, and ``X`` = ``S``. ``features["routes"]`` lists each route as the
waypoint names it drives through in straight centre-line legs:

- ``fig6``: S → E1 → E2 → E3 → E4 → E5 → E6 → E1 → E7 → E8 → E6 → (E1) → X, the paper's
  ~136 m route (E1 is passed on the way from E6 back to X; S and X are the same place);
- ``fig8_anticlockwise`` / ``fig8_clockwise``: once round the outer ring from S and back
  to S, in the two directions of the paper's Fig. 8 (Table 1's two journeys);
- ``fig16``: S → E1 → … → E7 (the paper's Fig. 16 route);
- ``fig15``: S → RD → R → RD → E1 or E7: down (or up) the left corridor to ``RD``, in
  front of the door of a room off it, through the door to ``R`` inside the room, turn
  round and out again, then on along the corridor to the next corner (the paper's Fig. 15:
  Albot₁ leaving a room). The room is the one whose door on the left corridor is nearest
  to 4 m from S; ``R`` is the deepest point up to the room's middle on the door's axis
  that the robot reaches clear of walls and furniture.

The letters are placed so the legs follow the paper's description (the Fig. 6 drawing
itself is not in the text): E1 is passed again after the first lap, passing S on the way
up the left corridor (the revisit of Fig. 10), the top corridor runs through the open
area (Fig. 14's second trace), and S → E5 is about 100 m of odometer distance.
"""

from __future__ import annotations

import itertools

import numpy as np
import shapely

from worldgen.kinds import WorldKind
from worldgen.kinds._clutter import furnish_hall, furnish_rects
from worldgen.kinds._plan import JAMB_M, Layout, boxes, partition_1d, shrink
from worldgen.params import Fig6Params

__all__ = ["FIG6_ROUTES", "layout_fig6"]

FIG6_ROUTES: dict[str, tuple[str, ...]] = {
    "fig6": ("S", "E1", "E2", "E3", "E4", "E5", "E6", "E1", "E7", "E8", "E6", "E1", "X"),
    "fig8_anticlockwise": ("S", "E1", "E2", "E3", "E4", "E5", "E7", "X"),
    "fig8_clockwise": ("S", "E7", "E5", "E4", "E3", "E2", "E1", "X"),
    "fig16": ("S", "E1", "E2", "E3", "E4", "E5", "E6", "E1", "E7"),
    "fig15": ("S", "RD", "R", "RD"),  # + the corner ahead (E1 or E7), per building
}
_HALL_PILLAR_SPACING_M = 5.0
_HALL_PILLAR_SIZE_M = 0.4
_HALL_ROUTE_CLEAR_M = 1.6  # pillars and furniture keep this far from the route's line


def _band(lo: float, hi: float, rng: np.random.Generator, p: Fig6Params) -> np.ndarray:
    return partition_1d(lo, hi, rng, p.room_width_min_m, p.room_width_max_m)


def _door(
    room: np.ndarray,
    side: str,
    span: tuple[float, float],
    width: float,
    ht: float,
    rng: np.random.Generator,
) -> np.ndarray | None:
    """A door rectangle through ``room``'s wall on ``side`` (``bottom``/``top``/``left``/
    ``right``) within the corridor's extent ``span`` along that wall; None if it cannot fit."""
    x0, y0, x1, y1 = room
    along = (x0, x1) if side in ("bottom", "top") else (y0, y1)
    lo, hi = max(along[0], span[0]) + ht + JAMB_M, min(along[1], span[1]) - ht - JAMB_M
    if hi - lo < width:
        return None
    a = rng.uniform(lo, hi - width)
    if side == "bottom":
        return np.array([a, y0 - ht, a + width, y0 + ht])
    if side == "top":
        return np.array([a, y1 - ht, a + width, y1 + ht])
    if side == "left":
        return np.array([x0 - ht, a, x0 + ht, a + width])
    return np.array([x1 - ht, a, x1 + ht, a + width])


def _zone(door: np.ndarray, depth: float) -> np.ndarray:
    """Keep-out rectangle for furniture in front of and behind a door."""
    x0, y0, x1, y1 = door
    if x1 - x0 < y1 - y0:  # door through a vertical wall
        return np.array([x0 - depth, y0, x1 + depth, y1])
    return np.array([x0, y0 - depth, x1, y1 + depth])


def layout_fig6(rect: np.ndarray, p: Fig6Params, rng: np.random.Generator) -> Layout:
    ht = 0.5 * p.wall_thickness_m
    X0, Y0, X1, Y1 = np.asarray(rect, float) + np.array([ht, ht, -ht, -ht])
    cw = rng.uniform(p.corridor_width_min_m, p.corridor_width_max_m)
    cell = cw + p.wall_thickness_m
    dl, db, dr = rng.uniform(p.room_depth_min_m, p.room_depth_max_m, 3)
    dt = rng.uniform(p.hall_depth_min_m, p.hall_depth_max_m)
    xa, xd, ya, yd = X0 + dl, X1 - dr, Y0 + db, Y1 - dt  # outer edges of the ring's cells
    off = rng.uniform(p.cross_offset_min_m, p.cross_offset_max_m)
    xm = xa + off  # left edge of the cross corridor's cell
    left, right = [xa, ya, xa + cell, yd], [xd - cell, ya, xd, yd]
    bottom, top = [xa, ya, xd, ya + cell], [xa, yd - cell, xd, yd]
    cross = [xm, ya, xm + cell, yd]
    corridors = np.array([left, right, bottom, top, cross])

    # centre-line coordinates of the ring and the cross corridor
    cxl, cxr, cyb, cyt = xa + cell / 2, xd - cell / 2, ya + cell / 2, yd - cell / 2
    cxm = xm + cell / 2
    sy = cyb + rng.uniform(0.4, 0.6) * (cyt - cyb)
    points = {
        "S": (cxl, sy), "E1": (cxl, cyb), "E2": (cxr, cyb), "E3": (cxr, cyt),
        "E4": (0.5 * (cxm + cxr), cyt), "E5": (cxm, cyt), "E6": (cxm, cyb),
        "E7": (cxl, cyt), "E8": (cxm, cyt), "X": (cxl, sy),
    }  # fmt: skip

    # the open area: the band above the top corridor from past the cross corridor to the
    # right end, with no wall between it and the corridor
    hall_x0 = xm + cell + rng.uniform(1.0, 3.0)
    hall_x1 = xd - rng.uniform(0.0, 2.0)
    hall = np.array([hall_x0, yd - cell, hall_x1, Y1])

    door_w = lambda: rng.uniform(p.door_width_min_m, p.door_width_max_m)  # noqa: E731
    rooms: list[np.ndarray] = []
    doors: list[np.ndarray] = []

    def add_rooms(cells: list[np.ndarray], side: str, span: tuple[float, float]) -> None:
        for r in cells:
            d = _door(r, side, span, door_w(), ht, rng)
            if d is not None:  # a room no corridor reaches stays solid
                rooms.append(r)
                doors.append(d)

    ys = _band(Y0, Y1, rng, p)
    add_rooms([np.array([X0, a, xa, b]) for a, b in itertools.pairwise(ys)], "right", (ya, yd))
    ys = _band(Y0, yd, rng, p)
    add_rooms([np.array([xd, a, X1, b]) for a, b in itertools.pairwise(ys)], "left", (ya, yd))
    xs = _band(xa, xd, rng, p)
    add_rooms([np.array([a, Y0, b, ya]) for a, b in itertools.pairwise(xs)], "top", (xa, xd))
    # rooms above the top corridor, left of the hall
    xs = _band(xa, hall_x0, rng, p)
    add_rooms([np.array([a, yd, b, Y1]) for a, b in itertools.pairwise(xs)], "bottom", (xa, xd))
    # inner blocks: one column between the left and cross corridors, two rows right of it
    ys = _band(ya + cell, yd - cell, rng, p)
    inner_left = [np.array([xa + cell, a, xm, b]) for a, b in itertools.pairwise(ys)]
    for r in inner_left:
        side = "right" if rng.random() < 0.5 else "left"
        d = _door(r, side, (ya, yd), door_w(), ht, rng)
        if d is not None:
            rooms.append(r)
            doors.append(d)
    mid = ya + cell + rng.uniform(0.4, 0.6) * (yd - ya - 2 * cell)
    xs = _band(xm + cell, xd - cell, rng, p)
    add_rooms(
        [np.array([a, ya + cell, b, mid]) for a, b in itertools.pairwise(xs)], "bottom", (xa, xd)
    )
    xs = _band(xm + cell, xd - cell, rng, p)
    add_rooms(
        [np.array([a, mid, b, yd - cell]) for a, b in itertools.pairwise(xs)], "top", (xa, xd)
    )

    room_cells = np.array(rooms).reshape(-1, 4)
    door_rects = np.array(doors).reshape(-1, 4)
    room_in = shrink(room_cells, ht)
    corr_in = shrink(corridors, ht)
    hall_in = shrink(hall[None, :], ht)[0]
    zones = np.array([_zone(d, p.passage_m + 0.3) for d in door_rects]).reshape(-1, 4)
    clutter = furnish_rects(
        room_in, rng, per_10m2=p.clutter_per_10m2, passage_m=p.passage_m, zones=zones
    )
    # the hall's furniture keeps clear of the top corridor's line (the route)
    hall_poly = shapely.box(hall_in[0], cyt + _HALL_ROUTE_CLEAR_M, hall_in[2], hall_in[3])
    pillars, furniture = furnish_hall(
        hall_poly,
        rng,
        p,
        pillar_spacing_m=_HALL_PILLAR_SPACING_M,
        pillar_size_m=_HALL_PILLAR_SIZE_M,
    )
    clutter += pillars + furniture

    floor = [*boxes(room_in), *boxes(corr_in), shapely.box(*hall_in), *boxes(door_rects)]
    links = np.array([
        [cxl, cyb, cxm, cyb], [cxm, cyb, cxr, cyb], [cxr, cyb, cxr, cyt],
        [cxr, cyt, points["E4"][0], cyt], [points["E4"][0], cyt, cxm, cyt],
        [cxm, cyt, cxl, cyt], [cxl, cyt, cxl, sy], [cxl, sy, cxl, cyb], [cxm, cyb, cxm, cyt],
    ])  # fmt: skip
    ring = [[cxl, cyb], [cxr, cyb], [cxr, cyt], [cxl, cyt], [cxl, cyb]]
    room_points = _room_visit(room_cells, door_rects, floor, clutter, points, cell, xa, p)
    routes = {k: list(v) for k, v in FIG6_ROUTES.items()}
    if room_points is None:  # no door on the left corridor (never seen): no fig15 route
        del routes["fig15"]
    else:
        points |= room_points
        ahead = "E1" if room_points["RD"][1] < sy else "E7"
        routes["fig15"].append(ahead)
    layout = Layout(floor=floor, clutter=clutter, doorways=[], links=[links])
    layout.features.update(
        rooms=len(room_cells),
        wall_thickness_m=p.wall_thickness_m,
        corridor_width_m=float(cw),
        corridor_ring=ring,
        ring_length_m=float(2.0 * ((cxr - cxl) + (cyt - cyb))),
        cross_corridor=[[cxm, cyb], [cxm, cyt]],
        open_areas=[hall_in.tolist()],
        waypoints={k: [float(v[0]), float(v[1])] for k, v in points.items()},
        routes=routes,
    )
    return layout


_ROOM_DOOR_FROM_S_M = 4.0  # the fig15 route's room: its door nearest this far from S
_ROOM_DEPTH_STEP_M = 0.1


def _room_visit(
    rooms: np.ndarray,
    doors: np.ndarray,
    floor: list[shapely.Geometry],
    clutter: list[shapely.Polygon],
    points: dict[str, tuple[float, float]],
    cell: float,
    xa: float,
    p: Fig6Params,
) -> dict[str, tuple[float, float]] | None:
    """``RD`` (the left corridor's centre line in front of a room's door) and ``R`` (inside
    that room on the door's axis) for the fig15 route; None when no door opens on the
    left corridor. Uses no randomness, so the building is the same with or without it."""
    cxl, sy = points["S"]
    yb, yt = points["E1"][1], points["E7"][1]
    margin = cell  # keep off the corners: the corridor must run on past the door
    choices = []
    for room, d in zip(rooms, doors, strict=True):
        cx, cy = 0.5 * (d[0] + d[2]), 0.5 * (d[1] + d[3])
        vertical_wall = d[2] - d[0] < d[3] - d[1]
        if not vertical_wall or not yb + margin < cy < yt - margin:
            continue
        if abs(cx - xa) < p.wall_thickness_m:
            inward = -1.0  # a room left of the left corridor
        elif abs(cx - (xa + cell)) < p.wall_thickness_m:
            inward = 1.0  # a room between the left and the cross corridor
        else:
            continue
        middle = abs(0.5 * (room[0] + room[2]) - cx)
        choices.append(
            (abs(abs(cy - sy) - _ROOM_DOOR_FROM_S_M), float(cx), float(cy), inward, float(middle))
        )
    if not choices:
        return None
    free = shapely.difference(shapely.union_all(floor), shapely.union_all(clutter))
    clear = free.buffer(-(p.robot_radius_m + p.clearance_margin_m))
    for _, cx, cy, inward, depth in sorted(choices):
        rd = (float(cxl), cy)
        while depth > 0.5:
            r = (cx + inward * depth, cy)
            if clear.covers(shapely.LineString([rd, r])):
                return {"RD": rd, "R": (float(r[0]), cy)}
            depth -= _ROOM_DEPTH_STEP_M
    return None


KIND = WorldKind(
    name="fig6",
    params=Fig6Params,
    layout=layout_fig6,
    summary="the paper's Fig. 6 building: a corridor ring with a cross corridor, rooms and a hall",
)
