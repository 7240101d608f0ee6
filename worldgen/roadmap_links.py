"""Roadmaps from planned links, checked exactly against the free space.

Generators know where their corridors, doors and rooms are, so they propose straight
links (centre lines, door crossings, lanes); this module splits long links, merges shared
endpoints and keeps only what is safe: nodes farther than the clearance from every
boundary segment, links that no boundary segment comes within the robot radius of. The
tests go through one STRtree of boundary segments, so cost follows the links, not the
world's size.
"""

from __future__ import annotations

import numpy as np
import shapely
from numpy.typing import ArrayLike, NDArray

from worldgen.roadmap import KEY_DECIMALS, compact_graph, largest_component
from worldgen.world import Roadmap

__all__ = ["ClearanceChecker", "roadmap_from_links"]


class ClearanceChecker:
    """Exact clearance tests against one polygon's boundary, vectorised through an STRtree.

    A point is safe if it is inside the polygon and farther than ``clearance_m`` from every
    boundary segment; a straight segment is safe if both ends are inside and no boundary
    segment comes within ``radius_m`` of it (so it cannot cross the boundary either).
    """

    def __init__(self, polygon: shapely.Polygon) -> None:
        rings = [polygon.exterior, *polygon.interiors]
        segs = np.vstack([_ring_segments(r) for r in rings])
        self.polygon = polygon
        shapely.prepare(polygon)
        self.tree = shapely.STRtree(shapely.linestrings(segs.reshape(-1, 2, 2)))

    def points_ok(self, pts: ArrayLike, clearance_m: float) -> NDArray[np.bool_]:
        p = np.asarray(pts, dtype=np.float64).reshape(-1, 2)
        ok = shapely.contains_xy(self.polygon, p[:, 0], p[:, 1])
        hits = self.tree.query(shapely.points(p), predicate="dwithin", distance=clearance_m)
        ok[hits[0]] = False
        return ok

    def segments_ok(self, segs: ArrayLike, radius_m: float) -> NDArray[np.bool_]:
        s = np.asarray(segs, dtype=np.float64).reshape(-1, 4)
        ok = shapely.contains_xy(self.polygon, s[:, 0], s[:, 1])
        ok &= shapely.contains_xy(self.polygon, s[:, 2], s[:, 3])
        lines = shapely.linestrings(s.reshape(-1, 2, 2))
        hits = self.tree.query(lines, predicate="dwithin", distance=radius_m)
        ok[hits[0]] = False
        return ok


def _ring_segments(ring: shapely.LinearRing) -> NDArray[np.float64]:
    c = np.asarray(ring.coords)
    return np.hstack([c[:-1], c[1:]])


def _subdivide(links: NDArray[np.float64], max_len_m: float) -> NDArray[np.float64]:
    """Split each segment into equal pieces no longer than ``max_len_m`` (vectorised)."""
    length = np.hypot(links[:, 2] - links[:, 0], links[:, 3] - links[:, 1])
    pieces = np.maximum(1, np.ceil(length / max_len_m - 1e-9)).astype(np.int64)
    owner = np.repeat(np.arange(len(links)), pieces)
    first = np.repeat(np.cumsum(pieces) - pieces, pieces)
    k = np.arange(len(owner)) - first
    t0 = k / pieces[owner]
    t1 = (k + 1) / pieces[owner]
    a, d = links[owner, :2], links[owner, 2:] - links[owner, :2]
    return np.hstack([a + t0[:, None] * d, a + t1[:, None] * d])


def roadmap_from_links(
    free_space: shapely.Polygon,
    links: ArrayLike,
    *,
    clearance_m: float,
    robot_radius_m: float,
    node_spacing_m: float = 3.0,
    checker: ClearanceChecker | None = None,
) -> Roadmap:
    """A roadmap from planned straight links ``(M, 4)`` (corridor centre lines, door
    crossings, lanes in rooms): long links are split, endpoints closer than a micrometre
    are merged, unsafe nodes and links are dropped and the largest component is kept."""
    segs = np.asarray(links, dtype=np.float64).reshape(-1, 4)
    if len(segs) == 0:
        return Roadmap(np.zeros((0, 2)), np.zeros((0, 2), dtype=np.int64))
    segs = _subdivide(segs, node_spacing_m)
    keys = np.round(segs.reshape(-1, 2), KEY_DECIMALS - 1)
    pts, inverse = np.unique(keys, axis=0, return_inverse=True)
    edges = np.sort(inverse.reshape(-1, 2), axis=1)
    edges = np.unique(edges[edges[:, 0] != edges[:, 1]], axis=0).astype(np.int64)
    check = checker or ClearanceChecker(free_space)
    node_ok = check.points_ok(pts, clearance_m)
    edges = edges[node_ok[edges[:, 0]] & node_ok[edges[:, 1]]]
    edge_ok = check.segments_ok(np.hstack([pts[edges[:, 0]], pts[edges[:, 1]]]), robot_radius_m)
    edges = edges[edge_ok]
    if len(edges) == 0:
        good = np.flatnonzero(node_ok)
        return Roadmap(pts[good[:1]], np.zeros((0, 2), dtype=np.int64))
    pts, edges = compact_graph(pts, edges)
    pts, edges = largest_component(pts, edges)
    return Roadmap(pts, edges)
