"""Roadmaps: a sparse graph along the medial axis of free space, safe for the robot's disc.

The medial axis is approximated by the Voronoi diagram of points spaced along every
free-space boundary ring (walls and clutter outlines). Voronoi edges whose endpoints keep
``clearance_m`` from every obstacle form a dense skeleton; short spurs (corner noise) are
pruned and each skeleton chain is simplified into straight edges at most about
``node_spacing_m`` apart. Every kept node lies in free space eroded by ``clearance_m`` and
every edge lies in free space eroded by the robot radius, both checked with vectorised,
prepared shapely predicates. Works for any polygon (generated or imported floor plans) and
is deterministic: the same polygon always gives the same roadmap.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from numpy.typing import ArrayLike, NDArray

from albot2d.errors import InputError
from albot2d.validation import check_positive
from worldgen.world import Roadmap

__all__ = [
    "BUFFER_SLACK_M",
    "RoadmapParams",
    "build_roadmap",
    "compact_graph",
    "count_loops",
    "largest_component",
    "safe_regions",
]

# shapely approximates the arcs of a negative buffer by chords that sit a few millimetres
# closer to reflex corners than the true arc; eroding this much further keeps the promise.
BUFFER_SLACK_M = 0.01
KEY_DECIMALS = 7  # coordinate rounding used to merge coincident Voronoi vertices


@dataclass(frozen=True)
class RoadmapParams:
    """Knobs of the medial-axis roadmap (metres)."""

    site_spacing_m: float = 0.6
    node_spacing_m: float = 3.0
    prune_spur_m: float = 0.6
    seed_link_m: float = 12.0
    seed_links: int = 1

    def __post_init__(self) -> None:
        check_positive(self, "site_spacing_m", "node_spacing_m", "seed_link_m")
        check_positive(self, "prune_spur_m", "seed_links")


def safe_regions(
    free_space: shapely.Polygon, clearance_m: float, robot_radius_m: float
) -> tuple[shapely.Geometry, shapely.Geometry]:
    """(where nodes may lie, where edges may run): free space eroded by clearance / radius."""
    nodes_ok = shapely.buffer(free_space, -(clearance_m + BUFFER_SLACK_M))
    edges_ok = shapely.buffer(free_space, -(robot_radius_m + BUFFER_SLACK_M))
    shapely.prepare(nodes_ok)
    shapely.prepare(edges_ok)
    return nodes_ok, edges_ok


def count_loops(roadmap: Roadmap) -> int:
    """Independent cycles of the roadmap graph: ``E - V + components``."""
    n = len(roadmap.nodes)
    if n == 0:
        return 0
    labels = _component_labels(n, roadmap.edges)
    return int(len(roadmap.edges) - n + len(np.unique(labels)))


def build_roadmap(
    free_space: shapely.Polygon,
    *,
    clearance_m: float,
    robot_radius_m: float | None = None,
    rng: np.random.Generator | None = None,
    seed_points: ArrayLike | None = None,
    params: RoadmapParams | None = None,
) -> Roadmap:
    """The medial-axis roadmap of ``free_space`` (largest connected part only).

    ``seed_points`` (``(K, 2)``) are extra nodes (room centres, the start...) linked to
    nearby roadmap nodes when the straight link is safe; unsafe seeds are dropped.
    ``rng`` is accepted for API symmetry; the construction itself is deterministic.
    """
    del rng
    p = params or RoadmapParams()
    if not clearance_m > 0.0:
        raise InputError(f"build_roadmap: clearance_m must be > 0, got {clearance_m!r}")
    radius = clearance_m if robot_radius_m is None else float(robot_radius_m)
    nodes_ok, edges_ok = safe_regions(free_space, clearance_m, radius)
    if nodes_ok.is_empty:
        return Roadmap(np.zeros((0, 2)), np.zeros((0, 2), dtype=np.int64))

    pts, edges = _skeleton(free_space, nodes_ok, edges_ok, p.site_spacing_m)
    for _ in range(2):
        pts, edges = _prune_spurs(pts, edges, p.prune_spur_m)
    pts, edges = _simplify_chains(pts, edges, edges_ok, p.node_spacing_m)
    if len(pts) == 0:
        pts = np.asarray(shapely.get_coordinates(nodes_ok.representative_point()), float)
        edges = np.zeros((0, 2), dtype=np.int64)
    if seed_points is not None:
        pts, edges = _link_seeds(pts, edges, seed_points, nodes_ok, edges_ok, p)
    pts, edges = largest_component(pts, edges)
    return Roadmap(pts, edges)


def _skeleton(
    free_space: shapely.Polygon,
    nodes_ok: shapely.Geometry,
    edges_ok: shapely.Geometry,
    site_spacing_m: float,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Voronoi edges of boundary sites that keep the clearance: a dense medial skeleton."""
    sites = shapely.get_coordinates(shapely.segmentize(free_space.boundary, site_spacing_m))
    sites = np.unique(np.round(sites, KEY_DECIMALS), axis=0)
    if len(sites) < 3:
        return np.zeros((0, 2)), np.zeros((0, 2), dtype=np.int64)
    vor = shapely.voronoi_polygons(shapely.multipoints(sites), only_edges=True)
    coords = shapely.get_coordinates(vor).reshape(-1, 4)
    a_in = shapely.contains_xy(nodes_ok, coords[:, 0], coords[:, 1])
    b_in = shapely.contains_xy(nodes_ok, coords[:, 2], coords[:, 3])
    coords = coords[a_in & b_in]
    lines = shapely.linestrings(coords.reshape(-1, 2, 2))
    coords = coords[shapely.covers(edges_ok, lines)]
    keys = np.round(coords.reshape(-1, 2), KEY_DECIMALS)
    pts, inverse = np.unique(keys, axis=0, return_inverse=True)
    edges = np.sort(inverse.reshape(-1, 2), axis=1)
    edges = np.unique(edges[edges[:, 0] != edges[:, 1]], axis=0)
    return pts, edges.astype(np.int64)


def _adjacency(n: int, edges: NDArray[np.int64]) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """CSR adjacency: neighbours of ``i`` are ``nbr[start[i]:start[i + 1]]``."""
    both = np.vstack([edges, edges[:, ::-1]])
    order = np.lexsort((both[:, 1], both[:, 0]))
    both = both[order]
    start = np.searchsorted(both[:, 0], np.arange(n + 1))
    return start, both[:, 1]


def _chains(n: int, edges: NDArray[np.int64]) -> list[list[int]]:
    """Split the graph into maximal paths whose inner nodes have degree 2."""
    if len(edges) == 0:
        return []
    start, nbr = _adjacency(n, edges)
    degree = np.diff(start)
    is_key = degree != 2
    used: set[tuple[int, int]] = set()
    chains: list[list[int]] = []

    def walk(a: int, b: int) -> list[int]:
        chain = [a, b]
        prev, cur = a, b
        used.add((min(a, b), max(a, b)))
        while not is_key[cur] and cur != a:
            n0, n1 = nbr[start[cur]], nbr[start[cur] + 1]
            nxt = int(n1 if n0 == prev else n0)
            key = (min(cur, nxt), max(cur, nxt))
            if key in used:
                break
            used.add(key)
            chain.append(nxt)
            prev, cur = cur, nxt
        return chain

    for k in np.flatnonzero(is_key & (degree > 0)):
        for b in nbr[start[k] : start[k + 1]]:
            if (min(k, b), max(k, b)) not in used:
                chains.append(walk(int(k), int(b)))
    # Whatever is left are pure cycles (no junction): start each at its lowest node.
    for i, j in edges:
        if (int(i), int(j)) not in used:
            chains.append(walk(int(i), int(j)))
    return chains


def _chain_lengths(pts: NDArray[np.float64], chains: list[list[int]]) -> NDArray[np.float64]:
    return np.array([np.hypot(*np.diff(pts[c], axis=0).T).sum() for c in chains])


def _prune_spurs(
    pts: NDArray[np.float64], edges: NDArray[np.int64], prune_m: float
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Drop short chains that end in a leaf hanging off a junction (corner noise)."""
    if len(edges) == 0:
        return pts, edges
    chains = _chains(len(pts), edges)
    degree = np.bincount(edges.ravel(), minlength=len(pts))
    lengths = _chain_lengths(pts, chains)
    keep_edges = []
    for chain, length in zip(chains, lengths, strict=True):
        ends = (degree[chain[0]], degree[chain[-1]])
        is_spur = min(ends) == 1 and max(ends) >= 3 and length < prune_m
        if not is_spur:
            keep_edges.append(np.column_stack([chain[:-1], chain[1:]]))
    if not keep_edges:
        return pts, edges
    kept = np.sort(np.vstack(keep_edges), axis=1)
    return compact_graph(pts, np.unique(kept, axis=0))


def compact_graph(
    pts: NDArray[np.float64], edges: NDArray[np.int64]
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Drop nodes no edge uses and renumber."""
    used, inverse = np.unique(edges.ravel(), return_inverse=True)
    return pts[used], inverse.reshape(-1, 2).astype(np.int64)


def _simplify_chains(
    pts: NDArray[np.float64],
    edges: NDArray[np.int64],
    edges_ok: shapely.Geometry,
    spacing_m: float,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Replace each chain by straight edges about ``spacing_m`` long that stay safe."""
    chains = _chains(len(pts), edges)
    if not chains:
        return np.zeros((0, 2)), np.zeros((0, 2), dtype=np.int64)
    # breakpoints[c] is a sorted list of positions (indices into chain c) kept as nodes.
    breaks: list[NDArray[np.int64]] = []
    for chain in chains:
        seg = np.hypot(*np.diff(pts[chain], axis=0).T)
        s = np.concatenate([[0.0], np.cumsum(seg)])
        n_parts = max(1, round(s[-1] / spacing_m))
        if chain[0] == chain[-1]:
            n_parts = max(n_parts, 3)  # a cycle needs at least a triangle
        targets = np.linspace(0.0, s[-1], n_parts + 1)
        idx = np.unique(np.clip(np.searchsorted(s, targets), 0, len(chain) - 1))
        breaks.append(np.unique(np.concatenate([[0, len(chain) - 1], idx])))
    while True:
        cand = [(c, k) for c, b in enumerate(breaks) for k in range(len(b) - 1)]
        segs = np.array(
            [
                np.concatenate([pts[chains[c][breaks[c][k]]], pts[chains[c][breaks[c][k + 1]]]])
                for c, k in cand
            ]
        )
        ok = shapely.covers(edges_ok, shapely.linestrings(segs.reshape(-1, 2, 2)))
        if ok.all():
            break
        for (c, k), good in zip(cand, ok, strict=True):
            if not good:
                lo, hi = breaks[c][k], breaks[c][k + 1]
                if hi - lo > 1:
                    breaks[c] = np.sort(np.append(breaks[c], (lo + hi) // 2))
        # Adjacent skeleton vertices are always safe, so refinement terminates.
    node_ids = np.unique(np.concatenate([np.asarray(chains[c])[b] for c, b in enumerate(breaks)]))
    new_index = np.full(len(pts), -1, dtype=np.int64)
    new_index[node_ids] = np.arange(len(node_ids))
    out = np.vstack(
        [
            np.column_stack(
                [new_index[np.asarray(chains[c])[b[:-1]]], new_index[np.asarray(chains[c])[b[1:]]]]
            )
            for c, b in enumerate(breaks)
        ]
    )
    out = np.sort(out, axis=1)
    out = np.unique(out[out[:, 0] != out[:, 1]], axis=0)
    return pts[node_ids], out


def _link_seeds(
    pts: NDArray[np.float64],
    edges: NDArray[np.int64],
    seed_points: ArrayLike,
    nodes_ok: shapely.Geometry,
    edges_ok: shapely.Geometry,
    p: RoadmapParams,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    seeds = np.asarray(seed_points, dtype=np.float64).reshape(-1, 2)
    seeds = seeds[shapely.contains_xy(nodes_ok, seeds[:, 0], seeds[:, 1])]
    if len(seeds) == 0 or len(pts) == 0:
        return pts, edges
    d = np.hypot(seeds[:, None, 0] - pts[None, :, 0], seeds[:, None, 1] - pts[None, :, 1])
    k = min(p.seed_links, len(pts))
    nearest = np.argsort(d, axis=1, kind="stable")[:, :k]
    si = np.repeat(np.arange(len(seeds)), k)
    ni = nearest.ravel()
    close = d[si, ni] <= p.seed_link_m
    si, ni = si[close], ni[close]
    segs = np.column_stack([seeds[si], pts[ni]])
    ok = shapely.covers(edges_ok, shapely.linestrings(segs.reshape(-1, 2, 2)))
    si, ni = si[ok], ni[ok]
    new_edges = np.column_stack([ni, len(pts) + si])
    all_pts = np.vstack([pts, seeds])
    all_edges = np.vstack([edges, new_edges]).astype(np.int64)
    return all_pts, all_edges


def _component_labels(n: int, edges: NDArray[np.int64]) -> NDArray[np.int64]:
    """Connected-component label per node (min-label propagation, vectorised)."""
    labels = np.arange(n, dtype=np.int64)
    if len(edges) == 0:
        return labels
    a, b = edges[:, 0], edges[:, 1]
    while True:
        m = np.minimum(labels[a], labels[b])
        new = labels.copy()
        np.minimum.at(new, a, m)
        np.minimum.at(new, b, m)
        new = new[new]  # pointer jumping speeds up long chains
        if np.array_equal(new, labels):
            return labels
        labels = new


def largest_component(
    pts: NDArray[np.float64], edges: NDArray[np.int64]
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    if len(pts) <= 1:
        return pts, edges
    labels = _component_labels(len(pts), edges)
    counts = np.bincount(labels, minlength=len(pts))
    best = int(np.argmax(counts))  # ties: lowest label, deterministic
    keep = labels == best
    new_index = np.cumsum(keep) - 1
    mask = keep[edges[:, 0]] & keep[edges[:, 1]]
    return pts[keep], new_index[edges[mask]].astype(np.int64)
