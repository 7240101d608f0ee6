"""The ``mixed`` kind: regions of corridors, rooms and open halls joined by a corridor spine.

The spine (one corridor, a T or a cross, for 2/3/4 regions) splits the world into regions;
each region is laid out by another kind's generator and joined to the spine through the
wall by a *bridge*: a doorway for rooms, a wide opening for halls, a corridor stub for a
corridor network, placed where the region's floor comes closest to the spine and reaches
across its full width.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import shapely

from worldgen.kinds import WorldKind
from worldgen.kinds._doors import hall_links
from worldgen.kinds._plan import (
    Layout,
    boxes,
    cell_centrelines,
    centreline_links,
    foot_on_segments,
    shrink,
)
from worldgen.kinds.corridors import layout_corridors
from worldgen.kinds.open_halls import layout_open
from worldgen.kinds.rooms import plan_rooms
from worldgen.params import CorridorsParams, MixedParams, OpenParams, RoomsParams

__all__ = ["layout_mixed"]

_PART_KINDS = ("rooms", "open", "corridors")
_RAY_STEP_M = 0.4
_FLAT_TOL_M = 0.05
_CONTACT_OVERLAP_M = 0.02
_END_CLEARANCE_EXTRA_M = 0.1
_HALL_OPENING_MIN_M = 2.5
_HALL_OPENING_MAX_M = 5.0


def _spine(
    rect: np.ndarray, n: int, cell_w: float, rng: np.random.Generator
) -> tuple[list[np.ndarray], list[tuple[np.ndarray, list[tuple[int, int]]]]]:
    """Spine corridor cells and the regions, each with its (spine index, side) contacts.

    Sides: 0 bottom, 1 right, 2 top, 3 left (the region side that faces the spine)."""
    X0, Y0, X1, Y1 = rect
    wide = (X1 - X0) >= (Y1 - Y0)

    def at(lo: float, hi: float) -> float:
        return lo + (hi - lo - cell_w) * rng.uniform(0.4, 0.6)

    if n == 2:
        if wide:
            x = at(X0, X1)
            spine = [np.array([x, Y0, x + cell_w, Y1])]
            regions = [
                (np.array([X0, Y0, x, Y1]), [(0, 1)]),
                (np.array([x + cell_w, Y0, X1, Y1]), [(0, 3)]),
            ]
        else:
            y = at(Y0, Y1)
            spine = [np.array([X0, y, X1, y + cell_w])]
            regions = [
                (np.array([X0, Y0, X1, y]), [(0, 2)]),
                (np.array([X0, y + cell_w, X1, Y1]), [(0, 0)]),
            ]
        return spine, regions
    y = at(Y0, Y1)
    x = at(X0, X1)
    main = np.array([X0, y, X1, y + cell_w])
    if n == 3:
        branch = np.array([x, y, x + cell_w, Y1])
        regions = [
            (np.array([X0, Y0, X1, y]), [(0, 2)]),
            (np.array([X0, y + cell_w, x, Y1]), [(0, 0), (1, 1)]),
            (np.array([x + cell_w, y + cell_w, X1, Y1]), [(0, 0), (1, 3)]),
        ]
        return [main, branch], regions
    branch = np.array([x, Y0, x + cell_w, Y1])
    regions = [
        (np.array([X0, Y0, x, y]), [(0, 2), (1, 1)]),
        (np.array([x + cell_w, Y0, X1, y]), [(0, 2), (1, 3)]),
        (np.array([X0, y + cell_w, x, Y1]), [(0, 0), (1, 1)]),
        (np.array([x + cell_w, y + cell_w, X1, Y1]), [(0, 0), (1, 3)]),
    ]
    return [main, branch], regions


def _bridge(
    floor: shapely.Geometry,
    region: np.ndarray,
    spine_in: np.ndarray,
    side: int,
    width: float,
    rng: np.random.Generator,
    *,
    inward_m: float,
    clearance_m: float,
) -> np.ndarray | None:
    """A rectangle from the spine's inner wall face to the region's floor, ``width`` wide,
    where the floor is near and flat across the whole width and the point ``inward_m``
    past the bridge's end has ``clearance_m`` (None if there is no such place).
    """
    x0, y0, x1, y1 = region
    vertical = side in (0, 2)  # bridge runs along y
    lo, hi = (
        (max(x0, spine_in[0]), min(x1, spine_in[2]))
        if vertical
        else (max(y0, spine_in[1]), min(y1, spine_in[3]))
    )
    centres = np.arange(lo + 0.5 * width + 0.3, hi - 0.5 * width - 0.3, _RAY_STEP_M)
    if len(centres) == 0:
        return None
    offs = np.linspace(-0.5 * width + 0.02, 0.5 * width - 0.02, max(3, int(width / 0.4) + 1))
    along = (centres[:, None] + offs[None, :]).ravel()
    # start on the spine's wall face, run to the far side of the region
    start, stop, sign = {
        0: (spine_in[3], y1, 1.0),
        2: (spine_in[1], y0, -1.0),
        1: (spine_in[0], x0, -1.0),
        3: (spine_in[2], x1, 1.0),
    }[side]
    a = np.column_stack([along, np.full_like(along, start)])
    b = np.column_stack([along, np.full_like(along, stop)])
    if not vertical:
        a, b = a[:, ::-1], b[:, ::-1]
    rays = shapely.linestrings(np.stack([a, b], axis=1))
    hits = shapely.intersection(rays, floor)
    depth = shapely.distance(shapely.points(a), hits).reshape(len(centres), len(offs))
    depth = np.where(np.isfinite(depth), depth, np.inf)
    far, near = depth.max(axis=1), depth.min(axis=1)
    ok = np.isfinite(far)
    ok[ok] = far[ok] - near[ok] < _FLAT_TOL_M
    if not ok.any():
        return None
    # the bridge's roadmap node just inside the region must be clear of walls
    depth_in = start + sign * (np.where(ok, far, 0.0) + inward_m)
    ends = np.column_stack([centres, depth_in] if vertical else [depth_in, centres])
    spots = shapely.points(ends)
    ok &= shapely.contains(floor, spots)
    ok &= shapely.distance(spots, floor.boundary) > clearance_m
    if not ok.any():
        return None
    best = far[ok].min()
    pick = np.flatnonzero(ok & (far <= best + 1.0))
    c = centres[pick[int(rng.integers(len(pick)))]]
    reach = start + sign * (far[np.flatnonzero(centres == c)[0]] + _CONTACT_OVERLAP_M)
    s0, s1 = sorted((start - sign * _CONTACT_OVERLAP_M, reach))
    h = 0.5 * width
    return np.array([c - h, s0, c + h, s1] if vertical else [s0, c - h, s1, c + h])


def _sub_params(kind: str, rect: np.ndarray, p: MixedParams) -> Any:
    w, h = float(rect[2] - rect[0]), float(rect[3] - rect[1])
    common: dict[str, Any] = {
        "width_m": w,
        "height_m": h,
        "robot_radius_m": p.robot_radius_m,
        "clearance_margin_m": p.clearance_margin_m,
        "wall_thickness_m": p.wall_thickness_m,
    }
    if kind == "rooms":
        return RoomsParams(
            **common,
            clutter_per_10m2=p.clutter_per_10m2,
            door_width_min_m=p.door_width_min_m,
            door_width_max_m=p.door_width_max_m,
        )
    if kind == "open":
        return OpenParams(
            **common, clutter_per_10m2=p.clutter_per_10m2, hall_parts=3, partition_walls=1
        )
    spacing = max(6.0, min(12.0, 0.45 * min(w, h)))
    return CorridorsParams(
        **common, junction_spacing_min_m=spacing - 1.0, junction_spacing_max_m=spacing + 3.0
    )


def _bridge_ends(
    bridge: np.ndarray, side: int, spine_line: np.ndarray, inward_m: float
) -> tuple[np.ndarray, np.ndarray]:
    """(foot on the spine centre line, point ``inward_m`` past the bridge's far end)."""
    x0, y0, x1, y1 = bridge
    if side in (0, 2):
        c = 0.5 * (x0 + x1)
        far = y1 + inward_m if side == 0 else y0 - inward_m
        return np.array([c, spine_line[1]]), np.array([c, far])
    c = 0.5 * (y0 + y1)
    far = x1 + inward_m if side == 3 else x0 - inward_m
    return np.array([spine_line[0], c]), np.array([far, c])


def _join_part(
    kind: str,
    part: Layout,
    region: np.ndarray,
    contacts: list[tuple[int, int]],
    spine_in: np.ndarray,
    spine_lines: np.ndarray,
    p: MixedParams,
    rng: np.random.Generator,
) -> tuple[Layout, np.ndarray, int]:
    """Bridge a corridor or hall region to the spine; returns the part with its links, the
    spine feet of the bridges and the number of bridges."""
    floor = part.floor_geometry()
    if kind == "open":
        width = float(rng.uniform(_HALL_OPENING_MIN_M, _HALL_OPENING_MAX_M))
        inward = p.approach_m
    else:
        width = float(part.features["corridor_width_m"][0])
        inward = 0.5 * width
    bridges, feet, ends = [], [], []
    for spine_idx, side in contacts:
        b = _bridge(
            floor,
            region,
            spine_in[spine_idx],
            side,
            width,
            rng,
            inward_m=inward,
            clearance_m=p.node_clearance_m + _END_CLEARANCE_EXTRA_M,
        )
        if b is not None:
            foot, end = _bridge_ends(b, side, spine_lines[spine_idx], inward)
            bridges.append(b)
            feet.append(foot)
            ends.append(end)
    if not bridges:
        return part, np.zeros((0, 2)), 0
    bridge_arr, feet_arr, ends_arr = np.array(bridges), np.array(feet), np.array(ends)
    # keep the bridge mouths clear: drop clutter standing in front of them
    mouths = boxes(bridge_arr + (p.passage_m + inward) * np.array([-1, -1, 1, 1]))
    clutter = part.clutter
    if clutter:
        hit = shapely.intersects(np.asarray(clutter, object)[:, None], mouths[None, :])
        clutter = [c for c, h in zip(clutter, hit.any(axis=1), strict=True) if not h]
    links = [np.hstack([feet_arr, ends_arr])]
    if kind == "open":
        links.append(
            hall_links(
                floor,
                clutter,
                ends_arr,
                clearance_m=p.node_clearance_m,
                robot_radius_m=p.robot_radius_m,
            )
        )
    else:
        lines = np.asarray(part.features["corridor_segments"], float)
        nearest = np.array([_nearest_line(e, lines) for e in ends_arr])
        hooks = foot_on_segments(ends_arr, lines, nearest)
        links += [np.hstack([ends_arr, hooks]), centreline_links(lines, hooks)]
    joined = Layout(
        floor=[*part.floor, *boxes(bridge_arr)],
        clutter=clutter,
        features=part.features,
        doorways=part.doorways,
        links=links,
    )
    return joined, feet_arr, len(bridges)


def _nearest_line(point: np.ndarray, lines: np.ndarray) -> int:
    hooks = foot_on_segments(np.tile(point, (len(lines), 1)), lines, np.arange(len(lines)))
    return int(np.argmin(np.hypot(*(hooks - point).T)))


def layout_mixed(rect: np.ndarray, p: MixedParams, rng: np.random.Generator) -> Layout:
    ht = 0.5 * p.wall_thickness_m
    inner = np.asarray(rect, float) + np.array([ht, ht, -ht, -ht])
    spine, regions = _spine(inner, p.regions, p.corridor_width_m + p.wall_thickness_m, rng)
    spine_cells = np.array(spine)
    spine_in = shrink(spine_cells, ht)
    spine_lines = cell_centrelines(spine_cells)
    kinds = [str(k) for k in rng.permutation(_PART_KINDS)]
    kinds += [str(k) for k in rng.choice(_PART_KINDS, size=max(0, p.regions - 3))]
    out = Layout(floor=list(boxes(spine_in)))
    parts, spine_feet = [], []
    for (region, contacts), kind in zip(regions, kinds, strict=False):
        sub = _sub_params(kind, region, p)
        if kind == "rooms":
            part, doors = plan_rooms(region, sub, rng, outside=spine_cells)
            feet = foot_on_segments(doors.outer_points, spine_lines, doors.outer_cells)
            part.links = [*(part.links or []), np.hstack([doors.outer_points, feet])]
            n_bridges = len(feet)
        else:
            layout_fn = layout_open if kind == "open" else layout_corridors
            part, feet, n_bridges = _join_part(
                kind, layout_fn(region, sub, rng), region, contacts, spine_in, spine_lines, p, rng
            )
        spine_feet.append(feet)
        out.floor += part.floor
        out.clutter += part.clutter
        out.doorways += part.doorways
        out.links = [*(out.links or []), *(part.links or [])]
        parts.append(
            {
                "kind": kind,
                "bounds": [float(v) for v in region],
                "connections": int(n_bridges),
                "features": part.features,
            }
        )
    out.links = [*(out.links or []), centreline_links(spine_lines, np.vstack(spine_feet))]
    out.features.update(
        parts=parts,
        part_kinds=sorted({str(k["kind"]) for k in parts}),
        spine_width_m=p.corridor_width_m,
        wall_thickness_m=p.wall_thickness_m,
    )
    return out


KIND = WorldKind(
    name="mixed",
    params=MixedParams,
    layout=layout_mixed,
    summary="regions of corridors, rooms and open halls joined by a corridor spine",
    reports_doorways=True,
)
