"""Tours: waypoint sequences along the roadmap, starting at the world's start pose.

- ``loop``: like the paper's S→E1→…→X: visit several far-apart places (within reach of
  the wanted length) in order around their centre, so the route goes round the building's
  loops, then come back to the start; excursions to far places are added if it is short.
- ``out_and_back``: go out to a place about half the length away and return exactly the
  same way.
- ``backtracking``: short trips that often turn back and revisit earlier places (like the
  Howard & Roy data set's robot), ending wherever the length is reached.
- ``circuit``: like ``loop`` but along the corridors only, for the paper's start–stop
  experiments: its places lie on the cycles (the 2-core) of the roadmap without its room
  nodes (``worldgen.regions``; the whole roadmap's cycles if that leaves none, e.g. in a
  world of rooms), so it never wanders round the furniture of a room, and no leg runs
  into a dead end (a room behind a doorway, a corridor stub) just to come back out; each leg to
  the next place avoids the way it arrived (no U-turn at a place) and prefers corridors
  not yet driven. The only dead-end stretch is the way from a start off the cycles to the
  nearest cycle and back at the end. A roadmap without cycles (a tree) has no circuit:
  the tour is then an out-and-back. The roadmap's small jogs (its nodes follow the
  medial axis, which shifts sideways at doorways and junctions) are straightened: a run
  of waypoints becomes one leg when none of them is more than ``_STRAIGHTEN_OFFSET_M``
  off it and the leg keeps ``_STRAIGHTEN_CLEARANCE_M`` more than the robot's radius from
  every obstacle, so the robot drives along a corridor as a person would, turning only
  at its corners.

``plan_tour(world, kind=..., length_m=..., seed=...)`` is the tour the command line plans
(``albot2d world/simulate/run``): the world's seed (or ``seed``) spawns two streams and
the second plans the tour, so the tour never shifts the world's random numbers.

Length. ``length_m`` is the tour's length within ``TOUR_LENGTH_TOLERANCE``: the planned
tour is between ``length_m`` and ``(1 + TOUR_LENGTH_TOLERANCE) * length_m`` long (100 m →
100-130 m). Loops and circuits are first planned through places within a smaller radius
until one fits; when none does (a coarse roadmap, a long corridor), the tour is cut short
(``_fit_length``): a closed tour turns home along the shortest way at the first point
where going on and coming back reaches the length (turning round part-way along a leg if
a whole leg would overshoot), an open one (``backtracking``) ends part-way along a leg.
``min_length_m`` (``make_tour``; ``plan_tour(..., at_least=True)``; ``--min-tour-length``
on the command line) keeps the older meaning: at least that long, however much longer
the places and repeats make it.

Every leg is a roadmap edge, so every leg is collision-free for the robot's disc. When the
places run out before ``min_length_m`` the tour is repeated (loops and out-and-backs both
end where they started, so repeating them is still a valid tour).
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Callable
from typing import TYPE_CHECKING, get_args

import networkx as nx
import numpy as np
import shapely

from albot2d.errors import InputError
from albot2d.seeding import WORLD_STREAMS, SeedLike, make_rng, stream_rng
from worldgen.world import Tour, TourKind

if TYPE_CHECKING:
    from worldgen.world import World

__all__ = ["TOUR_KINDS", "TOUR_LENGTH_TOLERANCE", "make_tour", "plan_tour"]

TOUR_KINDS: tuple[str, ...] = get_args(TourKind)  # the one list: world.TourKind
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
_REUSE_PENALTY = 4.0  # circuit: an edge already driven costs this many times more
_MAX_PLAN_STEPS = 100_000  # backtracking: planning steps before giving up (never reached
# on a roadmap that can make a tour; bounds the planning of one that cannot)
_STRAIGHTEN_OFFSET_M = 0.5  # circuit: a skipped waypoint lies at most this far off a leg
_STRAIGHTEN_CLEARANCE_M = 0.25  # circuit: straightened legs keep radius + this from walls
TOUR_LENGTH_TOLERANCE = 0.3
"""A tour planned for ``length_m`` is ``length_m`` to ``(1 + this) * length_m`` long."""
# loop/circuit: place radii tried (fractions of the length), largest first, for a tour
# that fits the tolerance without being cut short
_FIT_RADIUS_FRACTIONS = (0.5, 0.4, 0.32, 0.25, 0.2, 0.16, 0.12, 0.09, 0.06)


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
    assert isinstance(dist, dict) and isinstance(paths, dict)  # no target: per-node results
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


# (graph, node positions, start node, rng, minimum length in metres) -> walk of nodes
_TourBuilder = Callable[[nx.Graph, np.ndarray, int, np.random.Generator, float], list[int]]


def _loop(
    graph: nx.Graph,
    nodes: np.ndarray,
    s: int,
    rng: np.random.Generator,
    min_length_m: float,
    radius_fraction: float = _LOOP_RADIUS_FRACTION,
) -> list[int]:
    """Visit far-apart places in turn around their centre, then return to the start."""
    walk = [s]
    places = _places_in_turn(graph, nodes, s, rng, _place_radius(radius_fraction, min_length_m))
    if places:
        for place in places:
            walk += _path(graph, walk[-1], place)[1:]
        walk += _path(graph, walk[-1], s)[1:]
    while _walk_length(nodes, walk) < min_length_m:
        found = _far_place(graph, walk, rng, _PLACE_MIN_M)
        if found is None:
            break
        walk = _splice_excursion(walk, found[1])
    return _repeat_until(nodes, walk, min_length_m)


def _places_in_turn(
    graph: nx.Graph, nodes: np.ndarray, s: int, rng: np.random.Generator, radius_m: float
) -> list[int]:
    """Up to ``_LOOP_PLACES`` far-apart places within ``radius_m`` of ``s`` by road, in
    the order met going round their centre from ``s`` (one way or the other, at random)."""
    dist = nx.single_source_dijkstra_path_length(graph, s, weight="weight")
    ids = np.array(sorted(dist), dtype=np.int64)
    reach = np.array([dist[v] for v in ids])
    candidates = ids[reach <= radius_m]
    places = _spread_places(nodes, candidates, s, _LOOP_PLACES, rng)
    if not places:
        return []
    centre = nodes[candidates].mean(axis=0)
    rel = nodes[places] - centre
    angle = np.arctan2(rel[:, 1], rel[:, 0])
    start_angle = np.arctan2(*(nodes[s] - centre)[::-1])
    turn = 1.0 if rng.random() < 0.5 else -1.0
    ahead = np.mod(turn * (angle - start_angle), 2.0 * np.pi)
    return [int(v) for v in np.asarray(places)[np.argsort(ahead, kind="stable")]]


def _place_radius(fraction: float, length_m: float) -> float:
    """How far (by road) a loop's places may lie: ``fraction`` of the length; at least
    ``_LOOP_RADIUS_MIN_M`` when planning for the default fraction (a minimum length),
    less when fitting a length (small radii are how a short loop is found)."""
    floor = _LOOP_RADIUS_MIN_M if fraction >= _LOOP_RADIUS_FRACTION else 1.0
    return max(fraction * length_m, floor)


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
    steps = 0
    while _walk_length(nodes, walk) < min_length_m or len(walk) == 1:
        steps += 1
        if steps > _MAX_PLAN_STEPS:
            raise InputError(
                f"backtracking tour: no {min_length_m:g} m tour after {_MAX_PLAN_STEPS} "
                f"planning steps ({_walk_length(nodes, walk):.2f} m so far); the roadmap "
                "around the start is too small"
            )
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


def _straightener(world: World) -> Callable[[list[int]], list[int]]:
    """``walk -> walk`` without the waypoints a safe straight leg can skip (see above)."""
    nodes = world.roadmap.nodes
    safe = shapely.buffer(world.free_space, -(world.robot_radius_m + _STRAIGHTEN_CLEARANCE_M))
    shapely.prepare(safe)

    def ok(a: int, b: int, skipped: list[int]) -> bool:
        pa, pb = nodes[a], nodes[b]
        ab = pb - pa
        denom = float(ab @ ab)
        pts = nodes[skipped]
        t = np.zeros(len(pts)) if denom == 0.0 else np.clip((pts - pa) @ ab / denom, 0.0, 1.0)
        if np.hypot(*(pts - (pa + t[:, None] * ab)).T).max() > _STRAIGHTEN_OFFSET_M:
            return False
        return bool(safe.covers(shapely.LineString([pa, pb])))

    def straighten(walk: list[int]) -> list[int]:
        if len(walk) <= 2:
            return walk
        kept = [walk[0]]
        anchor = 0
        j = 1
        while j < len(walk) - 1:
            if ok(walk[anchor], walk[j + 1], walk[anchor + 1 : j + 1]):
                j += 1
                continue
            kept.append(walk[j])
            anchor = j
            j += 1
        kept.append(walk[-1])
        return kept

    return straighten


def _circuit(
    graph: nx.Graph,
    nodes: np.ndarray,
    s: int,
    rng: np.random.Generator,
    min_length_m: float,
    straighten: Callable[[list[int]], list[int]] = lambda walk: walk,
    rooms: frozenset[int] = frozenset(),
    radius_fraction: float = _LOOP_RADIUS_FRACTION,
) -> list[int]:
    """A loop through far-apart places on the roadmap's cycles; see the module docstring."""
    core_nodes = set(nx.k_core(graph.subgraph(set(graph) - rooms), 2).nodes)
    if not core_nodes:
        core_nodes = set(nx.k_core(graph, 2).nodes)
    if not core_nodes:
        return _out_and_back(graph, nodes, s, rng, min_length_m)
    dist, paths = nx.single_source_dijkstra(graph, s, weight="weight")
    assert isinstance(dist, dict) and isinstance(paths, dict)  # no target: per-node results
    reachable_core = sorted(v for v in core_nodes if v in dist)
    if not reachable_core:
        return _out_and_back(graph, nodes, s, rng, min_length_m)
    entry = min(reachable_core, key=lambda v: (dist[v], v))
    way_in = [int(v) for v in paths[entry]]
    core: nx.Graph[int] = nx.Graph(
        graph.subgraph(nx.node_connected_component(graph.subgraph(core_nodes), entry))
    )
    lap = [entry]
    places = _places_in_turn(core, nodes, entry, rng, _place_radius(radius_fraction, min_length_m))
    if places:
        for place in [*places, entry]:
            if place != lap[-1]:
                lap += _onward_path(core, lap, place)[1:]
    if len(lap) < 2:  # no place apart from the entry: go round the nearest cycle
        lap = _nearest_cycle(core, entry)
    lap = straighten(lap)
    way_in = straighten(way_in)
    walk = _repeat_until(nodes, lap, max(min_length_m - 2.0 * _walk_length(nodes, way_in), 0))
    return way_in[:-1] + walk + way_in[-2::-1]


def _onward_path(core: nx.Graph, walk: list[int], target: int) -> list[int]:
    """Shortest path from ``walk[-1]`` to ``target`` that does not leave the way it came
    (no U-turn) and avoids edges already driven where it can."""
    here = walk[-1]
    used = set(itertools.pairwise(walk))
    used |= {(b, a) for a, b in used}

    def cost(a: int, b: int, data: dict) -> float | None:
        if len(walk) > 1 and a == here and b == walk[-2]:
            return None  # hidden edge: no turning back along the way in
        w = float(data["weight"])
        return w * (1.0 + _REUSE_PENALTY) if (a, b) in used else w

    try:
        return [int(v) for v in nx.shortest_path(core, here, target, weight=cost)]
    except nx.NetworkXNoPath:
        return _path(core, here, target)


def _nearest_cycle(core: nx.Graph, entry: int) -> list[int]:
    """A closed walk round the shortest cycle through ``entry`` (the core has one)."""
    best: list[int] | None = None
    for nb in sorted(core.neighbors(entry)):
        g = core.copy()
        g.remove_edge(entry, nb)
        try:
            back = [int(v) for v in nx.shortest_path(g, nb, entry, weight="weight")]
        except nx.NetworkXNoPath:
            continue
        cycle = [entry, *back]
        if best is None or len(cycle) < len(best):
            best = cycle
    return best if best is not None else [entry]


def _room_nodes(world: World) -> frozenset[int]:
    from worldgen.regions import region_kind_at

    labels = region_kind_at(world, world.roadmap.nodes)
    return frozenset(int(i) for i in np.flatnonzero(labels == "room"))


def _component_length_m(graph: nx.Graph, s: int) -> float:
    """Total length of the roadmap edges reachable from node ``s``."""
    return float(graph.subgraph(nx.node_connected_component(graph, s)).size(weight="weight"))


def make_tour(
    world: World,
    rng: np.random.Generator | SeedLike,
    *,
    kind: str = "loop",
    min_length_m: float | None = None,
    length_m: float | None = None,
) -> Tour:
    """A tour of ``kind`` (see the module docstring): ``length_m`` long (within
    ``TOUR_LENGTH_TOLERANCE``), or at least ``min_length_m`` long (give one; neither:
    at least 50 m).

    ``rng`` is a Generator (used as it is) or an int seed / SeedSequence (``make_rng``).
    The CLI's tour for a world is ``plan_tour``, not ``make_tour(world, seed)``.
    """
    rng = make_rng(rng)
    if kind not in TOUR_KINDS:
        raise InputError(f"unknown tour kind {kind!r}; valid kinds: {', '.join(TOUR_KINDS)}")
    if min_length_m is not None and length_m is not None:
        raise InputError("give a tour length or a minimum tour length, not both")
    fit = length_m is not None
    name = "length_m" if fit else "min_length_m"
    wanted = length_m if fit else (50.0 if min_length_m is None else min_length_m)
    if not (
        isinstance(wanted, int | float)
        and not isinstance(wanted, bool)
        and 0.0 <= wanted <= _MAX_TOUR_M
    ):
        raise InputError(f"{name} must be in [0, {_MAX_TOUR_M:g}], got {wanted!r}")
    if fit and wanted <= 0.0:
        raise InputError(f"length_m must be positive, got {wanted!r}")
    min_length_m = float(wanted)
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
    reachable = _component_length_m(graph, s)
    if reachable < _MIN_ROADMAP_M:
        raise InputError(
            f"roadmap too small for a tour: the start node {s} reaches only {reachable:.2f} m "
            f"of roadmap edges (need at least {_MIN_ROADMAP_M} m; zero-length edges or a "
            "roadmap cut off from the start)"
        )
    builders: dict[str, _TourBuilder] = {
        "loop": _loop, "out_and_back": _out_and_back, "backtracking": _backtracking,
        "circuit": functools.partial(_circuit, straighten=_straightener(world),
                                     rooms=_room_nodes(world)),
    }  # fmt: skip
    if not fit:
        walk = builders[kind](graph, nodes, s, rng, min_length_m)
        waypoints = nodes[walk]
    else:
        walk, waypoints = _fitted_walk(builders[kind], kind, graph, nodes, s, rng, min_length_m)
    walk, waypoints = _tidy(walk, waypoints, start_xy)
    tour = Tour(waypoints=waypoints, kind=kind, node_ids=tuple(walk))
    if tour.length_m <= 0.0:
        raise InputError(
            f"{kind} tour from the start has length 0 m: the roadmap near "
            f"the start has no edge of positive length"
        )
    return tour


def plan_tour(
    world: World,
    kind: str = "loop",
    length_m: float = 100.0,
    seed: SeedLike | None = None,
    *,
    at_least: bool = False,
) -> Tour:
    """The tour the command line plans for ``world``: ``kind``, ``length_m`` long within
    ``TOUR_LENGTH_TOLERANCE`` (``at_least``: at least ``length_m`` long).

    ``seed`` defaults to the world's seed (0 if it has none); its ``"tour"`` stream
    (``albot2d.seeding.WORLD_STREAMS``) plans it, as ``albot2d world``, ``simulate`` and
    ``run`` do, so ``plan_tour(world)`` is the tour those commands drive on that world.
    """
    if seed is None:
        seed = world.seed or 0
    rng = stream_rng(seed, WORLD_STREAMS, "tour")
    if at_least:
        return make_tour(world, rng, kind=kind, min_length_m=length_m)
    return make_tour(world, rng, kind=kind, length_m=length_m)


# -- fitting a tour to a length -------------------------------------------------------------
NOT_A_NODE = -1
"""``Tour.node_ids`` entry of a waypoint part-way along a roadmap edge (a cut tour's end
or turning point)."""


def _tidy(
    walk: list[int], waypoints: np.ndarray, start_xy: np.ndarray
) -> tuple[list[int], np.ndarray]:
    """The start put in front when the walk does not begin on it; repeated nodes and
    zero-length legs (coincident roadmap nodes) dropped: they would be no motion."""
    waypoints = np.asarray(waypoints, dtype=np.float64).reshape(-1, 2)
    if not np.array_equal(waypoints[0], start_xy):
        waypoints = np.vstack([start_xy, waypoints])  # node_ids stay the roadmap walk
    keep = np.r_[True, np.hypot(*np.diff(waypoints, axis=0).T) > 0.0]
    if not keep.all():
        offset = len(waypoints) - len(walk)  # 1 when the start was put in front
        walk = [v for v, k in zip(walk, keep[offset:], strict=True) if k]
        waypoints = waypoints[keep]
    return walk, waypoints


def _fitted_walk(
    builder: _TourBuilder,
    kind: str,
    graph: nx.Graph,
    nodes: np.ndarray,
    s: int,
    rng: np.random.Generator,
    length_m: float,
) -> tuple[list[int], np.ndarray]:
    """A walk (node ids, ``NOT_A_NODE`` for a point along an edge) and its waypoints,
    ``length_m`` to ``(1 + TOUR_LENGTH_TOLERANCE) * length_m`` long where the roadmap
    allows it (see the module docstring)."""
    hi = (1.0 + TOUR_LENGTH_TOLERANCE) * length_m
    state = rng.bit_generator.state
    shortest: list[int] | None = None
    fractions = _FIT_RADIUS_FRACTIONS if kind in ("loop", "circuit") else (None,)
    for fraction in fractions:
        rng.bit_generator.state = state  # every candidate from the same draws
        sized: Callable[..., list[int]] = builder
        if fraction is not None:  # loop and circuit take the radius of their places
            sized = functools.partial(sized, radius_fraction=fraction)
        walk = sized(graph, nodes, s, rng, length_m)
        got = _walk_length(nodes, walk)
        if length_m <= got <= hi:
            return walk, nodes[walk]
        if got >= length_m and (shortest is None or got < _walk_length(nodes, shortest)):
            shortest = walk
    if shortest is None:  # the roadmap cannot make it long enough: the longest there is
        return walk, nodes[walk]
    return _fit_length(graph, nodes, shortest, s, length_m, closed=kind != "backtracking")


def _fit_length(
    graph: nx.Graph,
    nodes: np.ndarray,
    walk: list[int],
    s: int,
    length_m: float,
    *,
    closed: bool,
) -> tuple[list[int], np.ndarray]:
    """``walk`` (at least ``length_m`` long) cut to ``length_m``-ish: see the module
    docstring. Closed: going on to node ``i`` and then home by the shortest way costs
    ``f(i) = along(i) + home(i)``, which never decreases along the walk (triangle
    inequality) and ends at the walk's length; the first ``i`` with ``f(i)`` in the
    tolerance is where it turns home, or, if a whole leg overshoots, a point on that leg
    where turning round gives exactly ``length_m``."""
    hi = (1.0 + TOUR_LENGTH_TOLERANCE) * length_m
    pts = nodes[walk]
    legs = np.hypot(*np.diff(pts, axis=0).T)
    along = np.r_[0.0, np.cumsum(legs)]
    if not closed:
        i = int(np.searchsorted(along, length_m))  # along[i - 1] < length_m <= along[i]
        if along[i] <= hi:
            return walk[: i + 1], pts[: i + 1]
        t = (length_m - along[i - 1]) / legs[i - 1]
        end = pts[i - 1] + t * (pts[i] - pts[i - 1])
        return [*walk[:i], NOT_A_NODE], np.vstack([pts[:i], end])
    home, paths = nx.single_source_dijkstra(graph, s, weight="weight")
    assert isinstance(home, dict) and isinstance(paths, dict)  # no target: per-node results
    f = along + np.array([home.get(v, np.inf) for v in walk])
    for i in range(1, len(walk)):
        if length_m <= f[i] <= hi:
            back = [int(v) for v in paths[walk[i]]][::-1]
            ids = walk[: i + 1] + back[1:]
            return ids, nodes[ids]
        if f[i] > hi and f[i - 1] < length_m:
            # turn round on the leg (i-1, i) and go home by the shortest way from i-1
            t = (length_m - f[i - 1]) / (2.0 * legs[i - 1])
            if 0.0 < t <= 1.0:
                turn = pts[i - 1] + t * (pts[i] - pts[i - 1])
                back = [int(v) for v in paths[walk[i - 1]]][::-1]
                ids = [*walk[:i], NOT_A_NODE, *back]
                return ids, np.vstack([pts[:i], turn, nodes[back]])
    return walk, pts
