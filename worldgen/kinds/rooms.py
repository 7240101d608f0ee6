"""The ``rooms`` kind: rooms of varied sizes (binary space partition) joined by doorways.

Walls have the configured thickness (cells shrunk by half of it); doors are gaps in walls
0.8–1.2 m wide by default. A random spanning tree of the room adjacency guarantees every
room is reachable; extra doors add loops. Rooms are furnished against walls and in the
middle, keeping the lanes from each door to the room's centre clear for the roadmap.
"""

from __future__ import annotations

import numpy as np

from worldgen.kinds import WorldKind
from worldgen.kinds._clutter import furnish_rects
from worldgen.kinds._doors import DoorLinks, door_links
from worldgen.kinds._plan import (
    JAMB_M,
    Adjacency,
    Layout,
    adjacency,
    boxes,
    bsp_cells,
    door_rects,
    random_tree_mask,
    shrink,
)
from worldgen.params import RoomsParams

__all__ = ["layout_rooms", "plan_rooms"]

_OUTSIDE_DOORS_MAX = 2


def plan_rooms(
    rect: np.ndarray,
    p: RoomsParams,
    rng: np.random.Generator,
    *,
    outside: np.ndarray | None = None,
) -> tuple[Layout, DoorLinks]:
    """Rooms filling the cell rectangle ``rect`` (its border is a wall centre line).

    With ``outside`` cells (e.g. a corridor next to the rooms), one or two rooms touching
    them get a door onto them; their approach points come back in the DoorLinks."""
    half_t = 0.5 * p.wall_thickness_m
    cells = bsp_cells(np.asarray(rect, float), rng, p.room_size_min_m, p.room_size_max_m)
    interiors = shrink(cells, half_t)
    min_overlap = p.door_width_max_m + p.wall_thickness_m + 2.0 * JAMB_M
    adj = adjacency(cells, min_overlap_m=min_overlap)
    tree = random_tree_mask(len(cells), adj.i, adj.j, rng)
    extra = (~tree) & (rng.random(len(adj)) < p.extra_door_fraction)
    chosen = [adj.take(tree | extra)]
    is_room = [np.ones(len(chosen[0]), dtype=bool)]
    if outside is not None and len(outside):
        out_adj = adjacency(cells, np.asarray(outside, float), min_overlap_m=min_overlap)
        n_out = min(len(out_adj), int(rng.integers(1, _OUTSIDE_DOORS_MAX + 1)))
        pick = np.sort(rng.choice(len(out_adj), size=n_out, replace=False))
        chosen.append(out_adj.take(pick))
        is_room.append(np.zeros(n_out, dtype=bool))
    doors_adj = Adjacency.concat(chosen)
    j_is_room = np.concatenate(is_room)
    rects, segs, zones = door_rects(
        doors_adj,
        rng,
        width_min_m=p.door_width_min_m,
        width_max_m=p.door_width_max_m,
        wall_thickness_m=p.wall_thickness_m,
        zone_depth_m=p.passage_m + 0.3,
    )
    links = door_links(
        interiors,
        rects,
        doors_adj,
        j_is_room,
        offset_m=p.approach_m,
        lane_half_width_m=p.lane_half_width_m,
    )
    clutter = furnish_rects(
        interiors,
        rng,
        per_10m2=p.clutter_per_10m2,
        passage_m=p.passage_m,
        zones=np.vstack([zones, links.lanes]),
    )
    areas = (interiors[:, 2] - interiors[:, 0]) * (interiors[:, 3] - interiors[:, 1])
    layout = Layout(
        floor=[*boxes(interiors), *boxes(rects)],
        clutter=clutter,
        doorways=[segs],
        links=[links.links],
    )
    layout.features.update(
        rooms=len(cells),
        room_rects=interiors.tolist(),
        room_area_m2=[float(areas.min()), float(areas.max())],
        wall_thickness_m=p.wall_thickness_m,
    )
    return layout, links


def layout_rooms(rect: np.ndarray, p: RoomsParams, rng: np.random.Generator) -> Layout:
    """Rooms filling ``rect``; its border is the outer wall, ``wall_thickness_m`` thick."""
    half_t = 0.5 * p.wall_thickness_m
    inner = np.asarray(rect, float) + np.array([half_t, half_t, -half_t, -half_t])
    return plan_rooms(inner, p, rng)[0]


KIND = WorldKind(
    name="rooms",
    params=RoomsParams,
    layout=layout_rooms,
    summary="rooms of varied sizes joined by doorways",
    reports_doorways=True,
)
