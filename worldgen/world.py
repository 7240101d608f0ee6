"""The ``World`` value type and its parts: ``Roadmap``, ``Tour``, ``DynamicObstacle``.

A World is immutable geometry in metres (REP-103 frame): the wall segments that
line free space, clutter polygons inside it, the free-space polygon itself, a start
pose and a roadmap graph along which tours are planned. Generators, HouseExpo import
and JSON loading all produce this one type.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import shapely
from numpy.typing import NDArray

from albot2d.geometry import Pose, as_segments, polygon_ring_segments

if TYPE_CHECKING:
    import networkx as nx

__all__ = ["DynamicObstacle", "Roadmap", "Tour", "TourKind", "World"]

FloatArray = NDArray[np.float64]
TourKind = Literal["loop", "out_and_back", "backtracking", "circuit"]


def _frozen(arr: np.ndarray) -> np.ndarray:
    arr = np.array(arr, copy=True)
    arr.flags.writeable = False
    return arr


@dataclass(frozen=True, eq=False)
class Roadmap:
    """An undirected graph of collision-free straight edges between free-space nodes.

    ``nodes`` is ``(N, 2)`` float64 (metres); ``edges`` is ``(E, 2)`` int64 node indices
    with ``i < j``. Every node has clearance ≥ robot radius + margin and every edge is
    collision-free for the robot's disc (the generator checks both).
    """

    nodes: FloatArray
    edges: NDArray[np.int64]

    def __repr__(self) -> str:
        return f"Roadmap(nodes={len(self.nodes)}, edges={len(self.edges)})"

    def __post_init__(self) -> None:
        nodes = np.asarray(self.nodes, dtype=np.float64).reshape(-1, 2)
        edges = np.asarray(self.edges, dtype=np.int64).reshape(-1, 2)
        object.__setattr__(self, "nodes", _frozen(nodes))
        object.__setattr__(self, "edges", _frozen(edges))

    @functools.cached_property
    def graph(self) -> nx.Graph:
        """The roadmap as a networkx Graph with Euclidean ``weight`` on each edge."""
        import networkx as nx

        g = nx.Graph()
        g.add_nodes_from(range(len(self.nodes)))
        for i, j in self.edges:
            w = float(np.hypot(*(self.nodes[i] - self.nodes[j])))
            g.add_edge(int(i), int(j), weight=w)
        return g

    def nearest_node(self, point: Any) -> int:
        p = np.asarray(point, dtype=np.float64).reshape(2)
        return int(np.argmin(np.hypot(*(self.nodes - p).T)))


@dataclass(frozen=True, eq=False)
class Tour:
    """Waypoints ``(K, 2)`` for the robot to drive through in order, starting at the start pose."""

    waypoints: FloatArray
    kind: str
    node_ids: tuple[int, ...] = ()

    def __repr__(self) -> str:
        return (f"Tour(kind={self.kind!r}, waypoints={len(self.waypoints)}, "
                f"length_m={self.length_m:.6g})")

    def __post_init__(self) -> None:
        wp = np.asarray(self.waypoints, dtype=np.float64).reshape(-1, 2)
        object.__setattr__(self, "waypoints", _frozen(wp))

    @property
    def length_m(self) -> float:
        if len(self.waypoints) < 2:
            return 0.0
        return float(np.hypot(*np.diff(self.waypoints, axis=0).T).sum())

    @property
    def legs(self) -> FloatArray:
        """The straight legs as an ``(K-1, 4)`` segment array."""
        return np.hstack([self.waypoints[:-1], self.waypoints[1:]])


@dataclass(frozen=True, eq=False)
class DynamicObstacle:
    """An obstacle that moves: a movable ``box`` (a dynamic body the robot can push) or a
    ``person`` walking back and forth along ``path`` at ``speed_m_s``.

    ``shape`` is the outline ``(K, 2)`` in the obstacle's own frame; ``pose`` is its start pose.
    """

    kind: Literal["box", "person"]
    shape: FloatArray
    pose: Pose
    path: FloatArray = field(default_factory=lambda: np.zeros((0, 2)))
    speed_m_s: float = 0.0
    mass_kg: float = 10.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "shape", _frozen(np.asarray(self.shape, float).reshape(-1, 2)))
        object.__setattr__(self, "path", _frozen(np.asarray(self.path, float).reshape(-1, 2)))


@dataclass(frozen=True, eq=False)
class World:
    """A 2D environment. See the module docstring; fields are read-only.

    - ``walls``: ``(N, 4)`` float64 segments lining free space (not clutter outlines).
    - ``clutter``: polygons inside free space (pillars, tables, chairs...).
    - ``free_space``: one connected shapely Polygon (holes allowed), clutter subtracted.
    - ``bounds``: ``(xmin, ymin, xmax, ymax)`` of the whole world.
    - ``features``: what the generator promises, e.g. ``doorways`` as ``(K, 4)`` segments.
    """

    walls: FloatArray
    clutter: tuple[shapely.Polygon, ...]
    free_space: shapely.Polygon
    bounds: tuple[float, float, float, float]
    start: Pose
    roadmap: Roadmap
    kind: str = "custom"
    seed: int | None = None
    params: Mapping[str, Any] = field(default_factory=dict)
    dynamic_obstacles: tuple[DynamicObstacle, ...] = ()
    features: Mapping[str, Any] = field(default_factory=dict)
    robot_radius_m: float = 0.25

    def __repr__(self) -> str:
        return (
            f"World(kind={self.kind!r}, seed={self.seed!r}, size_m=({self.width_m:.6g}, "
            f"{self.height_m:.6g}), walls={len(self.walls)}, clutter={len(self.clutter)}, "
            f"dynamic_obstacles={len(self.dynamic_obstacles)}, roadmap={self.roadmap!r}, "
            f"start={self.start!r})"
        )

    def __post_init__(self) -> None:
        object.__setattr__(self, "walls", _frozen(as_segments(self.walls)))
        object.__setattr__(self, "clutter", tuple(self.clutter))
        object.__setattr__(self, "dynamic_obstacles", tuple(self.dynamic_obstacles))
        object.__setattr__(self, "bounds", tuple(float(b) for b in self.bounds))

    @functools.cached_property
    def clutter_segments(self) -> FloatArray:
        """Outlines of all clutter polygons as one ``(M, 4)`` segment array."""
        parts = [polygon_ring_segments(np.asarray(p.exterior.coords)) for p in self.clutter]
        return _frozen(np.vstack(parts) if parts else np.zeros((0, 4)))

    @functools.cached_property
    def obstacle_segments(self) -> FloatArray:
        """Every static surface a laser can hit: walls followed by clutter outlines."""
        return _frozen(np.vstack([self.walls, self.clutter_segments]))

    @property
    def width_m(self) -> float:
        return self.bounds[2] - self.bounds[0]

    @property
    def height_m(self) -> float:
        return self.bounds[3] - self.bounds[1]

    def tour(
        self,
        rng: np.random.Generator | int | np.random.SeedSequence,
        *,
        kind: TourKind = "loop",
        min_length_m: float = 50.0,
    ) -> Tour:
        """Plan waypoints along the roadmap from the start; see ``worldgen.tours``.

        ``rng`` is a Generator or an int seed. The tour the command line drives on this
        world is ``worldgen.plan_tour(world, ...)`` (it derives its own stream).
        """
        from worldgen.tours import make_tour

        return make_tour(self, rng, kind=kind, min_length_m=min_length_m)
