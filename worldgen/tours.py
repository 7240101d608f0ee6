"""Tours: waypoint sequences along the roadmap, starting at the world's start pose.

- ``loop``: like the paper's S→E1→…→X: visit several far-apart places (within reach of
  the wanted length) in order around their centre, so the route goes round the building's
  loops, then come back to the start; excursions to far places are added if it is short.
- ``out_and_back``: go out to a place about half the length away and return exactly the
  same way.
- ``backtracking``: short trips that often turn back and revisit earlier places (like the
  Howard & Roy data set's robot), ending wherever the length is reached.

Every leg is a roadmap edge, so every leg is collision-free for the robot's disc. When the
places run out before ``min_length_m`` the tour is repeated (loops and out-and-backs both
end where they started, so repeating them is still a valid tour).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import networkx as nx
import numpy as np

from albot2d.errors import InputError
from worldgen.world import Tour

if TYPE_CHECKING:
    from worldgen.world import World

__all__ = ["TOUR_KINDS", "make_tour"]

TOUR_KINDS = ("loop", "out_and_back", "backtracking")
_MIN_ROADMAP_M = 2.0  # less roadmap than this cannot make a tour
_PLACE_MIN_M = 3.0  # a new place is at least this far (along the roadmap) from the route
_FAR_CHOICES = 5  # pick among this many farthest places, for variety
_MAX_TOUR_M = 1.0e6
_BACK_P = 0.4  # backtracking: chance to head back to an earlier place
_TURN_P = 0.6  # backtracking: chance to turn back part-way after reaching a new place
_NEAR_FACTOR = 6.0  # backtracking: new places lie within this many _PLACE_MIN_M by road
_LOOP_PLACES = 6  # far-apart places a loop passes through
_LOOP_RADIUS_FRACTION = 0.5  # loop places lie within this fraction of the length (by road)
_LOOP_RADIUS_MIN_M = 10.0
_OUT_BAND = 1.3  # out-and-back turns round between half the length and this much more


def _walk_length(nodes: np.ndarray, walk: list[int]) -> float:
    if len(walk) < 2:
        return 0.0
    return float(np.hypot(*np.diff(nodes[walk], axis=0).T).sum())


def _far_place(
    graph: nx.Graph, sources: list[int], rng: np.random.Generator, min_m: float
) -> tuple[int, list[int]] | None:
    """A node far (along the roadmap) from all ``sources``: (node, path from the nearest
    source to it), picked at random among the few farthest; None if all are near."""
    dist, paths = nx.multi_source_dijkstra(graph, sources, weight="weight")
    ids = np.fromiter(dist.keys(), dtype=np.int64, count=len(dist))
    far = np.fromiter(dist.values(), dtype=np.float64, count=len(dist))
    order = np.lexsort((ids, -far))
    top = order[:_FAR_CHOICES][far[order[:_FAR_CHOICES]] >= min_m]
    if len(top) == 0:
        return None
    node = int(ids[top[int(rng.integers(len(top)))]])
    return node, [int(v) for v in paths[node]]


def _splice_excursion(walk: list[int], path: list[int]) -> list[int]:
    """Insert ``path`` (from a walk node out to a place) and its way back into ``walk``."""
    at = walk.index(path[0])
    trip = path[1:] + path[-2::-1]
    return walk[: at + 1] + trip + walk[at + 1 :]


def _repeat_until(nodes: np.ndarray, walk: list[int], min_length_m: float) -> list[int]:
    """Repeat a closed walk (first node == last node) until it is long enough."""
    lap = _walk_length(nodes, walk)
    if lap <= 0.0 or _walk_length(nodes, walk) >= min_length_m:
        return walk
    laps = math.ceil(min_length_m / lap)
    return walk + walk[1:] * (laps - 1)


def _spread_places(
    nodes: np.ndarray, candidates: np.ndarray, s: int, k: int, rng: np.random.Generator
) -> list[int]:
    """``k`` far-apart candidate nodes (farthest-point sampling from the start)."""
    chosen: list[int] = []
    d = np.hypot(*(nodes[candidates] - nodes[s]).T)
    for _ in range(min(k, len(candidates))):
        order = np.argsort(-d, kind="stable")[:_FAR_CHOICES]
        order = order[d[order] > 0.0]
        if len(order) == 0:
            break
        pick = int(order[int(rng.integers(len(order)))]) if not chosen else int(order[0])
        chosen.append(int(candidates[pick]))
        d = np.minimum(d, np.hypot(*(nodes[candidates] - nodes[candidates[pick]]).T))
    return chosen


def _loop(
    graph: nx.Graph, nodes: np.ndarray, s: int, rng: np.random.Generator, min_length_m: float
) -> list[int]:
    """Visit far-apart places in turn around their centre, then return to the start."""
    dist = nx.single_source_dijkstra_path_length(graph, s, weight="weight")
    ids = np.array(sorted(dist), dtype=np.int64)
    reach = np.array([dist[v] for v in ids])
    radius = max(_LOOP_RADIUS_FRACTION * min_length_m, _LOOP_RADIUS_MIN_M)
    candidates = ids[reach <= radius]
    places = _spread_places(nodes, candidates, s, _LOOP_PLACES, rng)
    walk = [s]
    if places:
        centre = nodes[candidates].mean(axis=0)
        rel = nodes[places] - centre
        angle = np.arctan2(rel[:, 1], rel[:, 0])
        start_angle = np.arctan2(*(nodes[s] - centre)[::-1])
        turn = 1.0 if rng.random() < 0.5 else -1.0
        ahead = np.mod(turn * (angle - start_angle), 2.0 * np.pi)
        for place in np.asarray(places)[np.argsort(ahead, kind="stable")]:
            walk += _path(graph, walk[-1], int(place))[1:]
        walk += _path(graph, walk[-1], s)[1:]
    while _walk_length(nodes, walk) < min_length_m:
        found = _far_place(graph, walk, rng, _PLACE_MIN_M)
        if found is None:
            break
        walk = _splice_excursion(walk, found[1])
    return _repeat_until(nodes, walk, min_length_m)


def _path(graph: nx.Graph, a: int, b: int) -> list[int]:
    return [int(v) for v in nx.shortest_path(graph, a, b, weight="weight")]


def _out_and_back(
    graph: nx.Graph, nodes: np.ndarray, s: int, rng: np.random.Generator, min_length_m: float
) -> list[int]:
    """Out to a place about half the length away (through more places if the roadmap is
    short), then back along exactly the same way."""
    dist = nx.single_source_dijkstra_path_length(graph, s, weight="weight")
    ids = np.array(sorted(dist), dtype=np.int64)
    reach = np.array([dist[v] for v in ids])
    half = 0.5 * min_length_m
    band = ids[(reach >= half) & (reach <= _OUT_BAND * half + _PLACE_MIN_M) & (reach > 0.0)]
    if len(band):
        out = _path(graph, s, int(band[int(rng.integers(len(band)))]))
    else:
        out = _path(graph, s, int(ids[int(np.argmax(reach))]))
    while 2.0 * _walk_length(nodes, out) < min_length_m:
        found = _far_place(graph, out, rng, _PLACE_MIN_M)
        if found is None:
            break
        out += _path(graph, out[-1], found[0])[1:]
    walk = out + out[-2::-1]
    return _repeat_until(nodes, walk, min_length_m)


def _backtracking(
    graph: nx.Graph, nodes: np.ndarray, s: int, rng: np.random.Generator, min_length_m: float
) -> list[int]:
    walk = [s]
    places = [s]
    while _walk_length(nodes, walk) < min_length_m or len(walk) == 1:
        here = walk[-1]
        earlier = [v for v in places if v != here]
        if earlier and rng.random() < _BACK_P:
            target = earlier[int(rng.integers(len(earlier)))]
            walk += [int(v) for v in nx.shortest_path(graph, here, target, weight="weight")[1:]]
            places.append(target)
            continue
        # only nearby places matter, so the search stops at the farthest one wanted
        dist = nx.single_source_dijkstra_path_length(
            graph, here, cutoff=_NEAR_FACTOR * _PLACE_MIN_M, weight="weight"
        )
        ids = np.array(sorted(dist), dtype=np.int64)
        d = np.array([dist[v] for v in ids])
        near = ids[d >= _PLACE_MIN_M]
        if len(near) == 0:
            near = ids[d == d.max()]
        target = int(near[int(rng.integers(len(near)))])
        path = [int(v) for v in nx.shortest_path(graph, here, target, weight="weight")]
        walk += path[1:]
        places.append(target)
        if len(path) > 2 and rng.random() < _TURN_P:
            back = int(rng.integers(1, len(path) - 1))  # turn round part-way back
            walk += path[len(path) - 2 : back - 1 : -1]
            places.append(path[back])
    return walk


def make_tour(
    world: World,
    rng: np.random.Generator,
    *,
    kind: str = "loop",
    min_length_m: float = 50.0,
) -> Tour:
    """A tour of ``kind`` (see the module docstring) at least ``min_length_m`` long."""
    if kind not in TOUR_KINDS:
        raise InputError(f"unknown tour kind {kind!r}; valid kinds: {', '.join(TOUR_KINDS)}")
    if not (isinstance(min_length_m, int | float) and 0.0 <= min_length_m <= _MAX_TOUR_M):
        raise InputError(f"min_length_m must be in [0, {_MAX_TOUR_M:g}], got {min_length_m!r}")
    roadmap = world.roadmap
    nodes = roadmap.nodes
    total = float(np.hypot(*(nodes[roadmap.edges[:, 0]] - nodes[roadmap.edges[:, 1]]).T).sum())
    if len(nodes) < 2 or total < _MIN_ROADMAP_M:
        raise InputError(
            f"roadmap too small for a tour: {len(nodes)} nodes, {total:.2f} m of edges "
            f"(need at least {_MIN_ROADMAP_M} m); make the world bigger or the robot smaller"
        )
    graph = roadmap.graph
    start_xy = np.array([world.start.x, world.start.y])
    s = roadmap.nearest_node(start_xy)
    if graph.degree(s) == 0:
        raise InputError(f"start node {s} has no roadmap edges; no tour can leave it")
    builders = {"loop": _loop, "out_and_back": _out_and_back, "backtracking": _backtracking}
    walk = builders[kind](graph, nodes, s, rng, float(min_length_m))
    walk = [v for k, v in enumerate(walk) if k == 0 or v != walk[k - 1]]
    waypoints = nodes[walk]
    if not np.array_equal(waypoints[0], start_xy):
        waypoints = np.vstack([start_xy, waypoints])
    return Tour(waypoints=waypoints, kind=kind, node_ids=tuple(walk))
