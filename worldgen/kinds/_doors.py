"""Doors turned into roadmap links: crossings through each door and lanes to room hubs.

Every door gets an approach point on each side (``offset_m`` in front of the wall face); a
link crosses the door between them along its axis. On a room side the approach point is
joined to the room's hub (its centre) by an L-shaped lane that furniture must keep clear
of; on a corridor or hall side the caller joins it to its own network.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from numpy.typing import NDArray

from worldgen.kinds._plan import Adjacency, door_approaches, lanes_to_hubs
from worldgen.roadmap import RoadmapParams, build_roadmap

__all__ = ["DoorLinks", "door_links", "hall_links"]

_HALL_ROADMAP = RoadmapParams(seed_links=3)

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class DoorLinks:
    """Roadmap links and clutter-free lanes for a set of doors.

    ``outer_points``/``outer_cells`` are the approach points on the non-room (``j``) side of
    doors whose ``j`` is not a room, for the caller to link into its corridors or halls."""

    links: FloatArray
    lanes: FloatArray
    outer_points: FloatArray
    outer_cells: NDArray[np.int64]


def door_links(
    interiors: FloatArray,
    door_rects: FloatArray,
    adj: Adjacency,
    j_is_room: NDArray[np.bool_],
    *,
    offset_m: float,
    lane_half_width_m: float,
) -> DoorLinks:
    """Links for doors between room ``adj.i`` and room or other cell ``adj.j``."""
    if len(adj) == 0:
        empty = np.zeros((0, 4))
        return DoorLinks(empty, empty, np.zeros((0, 2)), np.zeros(0, dtype=np.int64))
    a_i, a_j = door_approaches(door_rects, adj, offset_m)
    lane_i, zone_i = lanes_to_hubs(interiors, adj.i, a_i, adj.axis, lane_half_width_m)
    m = np.asarray(j_is_room, dtype=bool)
    lane_j, zone_j = lanes_to_hubs(interiors, adj.j[m], a_j[m], adj.axis[m], lane_half_width_m)
    return DoorLinks(
        links=np.vstack([np.hstack([a_i, a_j]), lane_i, lane_j]),
        lanes=np.vstack([zone_i, zone_j]),
        outer_points=a_j[~m],
        outer_cells=adj.j[~m],
    )


def hall_links(
    hall: shapely.Polygon,
    clutter: list[shapely.Polygon],
    entries: FloatArray,
    *,
    clearance_m: float,
    robot_radius_m: float,
) -> FloatArray:
    """A medial-axis roadmap of one open hall, linked to its ``entries``, as links (M, 4)."""
    floor = hall
    if clutter:
        floor = shapely.difference(hall, shapely.union_all(np.asarray(clutter, dtype=object)))
    if floor.geom_type != "Polygon":
        parts = shapely.get_parts(floor)
        floor = parts[int(np.argmax(shapely.area(parts)))]
    roadmap = build_roadmap(
        floor,
        clearance_m=clearance_m,
        robot_radius_m=robot_radius_m,
        seed_points=entries,
        params=_HALL_ROADMAP,
    )
    return roadmap.nodes[roadmap.edges].reshape(-1, 4)
