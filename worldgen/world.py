"""The ``World`` value type and its parts: ``Roadmap``, ``Tour``, ``DynamicObstacle``.

A World is immutable geometry in metres (REP-103 frame): the wall segments that
line free space, clutter polygons inside it, the free-space polygon itself, a start
pose and a roadmap graph along which tours are planned. Generators, HouseExpo import
and JSON loading all produce this one type.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import shapely
from numpy.typing import NDArray

from albot2d.arrays import readonly
from albot2d.errors import InputError
from albot2d.geometry import Pose, as_segments, polygon_ring_segments

if TYPE_CHECKING:
    import networkx as nx

__all__ = [
    "MAX_OBSTACLE_MASS_KG",
    "MAX_OBSTACLE_POINTS",
    "MAX_OBSTACLE_SPEED_M_S",
    "MIN_WALK_PATH_M",
    "DynamicObstacle",
    "Roadmap",
    "Tour",
    "TourKind",
    "World",
]

FloatArray = NDArray[np.float64]
TourKind = Literal["loop", "out_and_back", "backtracking", "circuit"]


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
        object.__setattr__(self, "nodes", readonly(nodes))
        object.__setattr__(self, "edges", readonly(edges))

    @functools.cached_property
    def graph(self) -> nx.Graph:
        """The roadmap as a networkx Graph with Euclidean ``weight`` on each edge."""
        import networkx as nx

        g: nx.Graph[int] = nx.Graph()
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
        return (
            f"Tour(kind={self.kind!r}, waypoints={len(self.waypoints)}, "
            f"length_m={self.length_m:.6g})"
        )

    def __post_init__(self) -> None:
        wp = np.asarray(self.waypoints, dtype=np.float64).reshape(-1, 2)
        object.__setattr__(self, "waypoints", readonly(wp))

    @property
    def length_m(self) -> float:
        if len(self.waypoints) < 2:
            return 0.0
        return float(np.hypot(*np.diff(self.waypoints, axis=0).T).sum())

    @property
    def legs(self) -> FloatArray:
        """The straight legs as an ``(K-1, 4)`` segment array."""
        return np.hstack([self.waypoints[:-1], self.waypoints[1:]])


# Limits of a moving obstacle (each bounds the simulator's work; see DynamicObstacle).
MAX_OBSTACLE_SPEED_M_S = 5.0
MIN_WALK_PATH_M = 0.1
MAX_OBSTACLE_POINTS = 10_000
MAX_OBSTACLE_MASS_KG = 1e6
_OBSTACLE_KINDS = ("box", "person")


@dataclass(frozen=True, eq=False)
class DynamicObstacle:
    """An obstacle that moves: a movable ``box`` (a dynamic body the robot can push) or a
    ``person`` walking back and forth along ``path`` at ``speed_m_s``.

    ``shape`` is the outline ``(K, 2)`` in the obstacle's own frame; ``pose`` is its start pose.

    Values are checked here (``InputError`` naming the field, the value and the limit): every
    number finite, a shape of positive area, at most ``MAX_OBSTACLE_POINTS`` shape or path
    points, ``0 <= speed_m_s <= MAX_OBSTACLE_SPEED_M_S`` and ``0 < mass_kg <=
    MAX_OBSTACLE_MASS_KG``. The simulator (``albot2d.sim.dynamics``) also refuses a walking
    person whose path is shorter than ``MIN_WALK_PATH_M``: with the speed limit this bounds
    the work of every simulated second (a person turns back at most a few times per physics
    step).
    """

    kind: Literal["box", "person"]
    shape: FloatArray
    pose: Pose
    path: FloatArray = field(default_factory=lambda: np.zeros((0, 2)))
    speed_m_s: float = 0.0
    mass_kg: float = 10.0

    def __post_init__(self) -> None:
        if self.kind not in _OBSTACLE_KINDS:
            raise InputError(
                f"DynamicObstacle.kind must be one of {_OBSTACLE_KINDS}, got {self.kind!r}"
            )
        shape = _obstacle_points(self.shape, "shape")
        path = _obstacle_points(self.path, "path")
        _obstacle_points([self.pose.x, self.pose.y], "pose")
        _obstacle_number(self.pose.theta, "pose theta")
        if len(shape) < 3 or shapely.Polygon(shape).convex_hull.area <= 0.0:
            raise InputError(
                f"DynamicObstacle.shape must be an outline of positive area "
                f"(3 or more points, not all on one line), got {_head(shape)}"
            )
        speed = _obstacle_number(self.speed_m_s, "speed_m_s")
        if not 0.0 <= speed <= MAX_OBSTACLE_SPEED_M_S:
            raise InputError(
                f"DynamicObstacle.speed_m_s must be in [0, {MAX_OBSTACLE_SPEED_M_S}] "
                f"m/s (MAX_OBSTACLE_SPEED_M_S), got {speed!r}"
            )
        mass = _obstacle_number(self.mass_kg, "mass_kg")
        if not 0.0 < mass <= MAX_OBSTACLE_MASS_KG:
            raise InputError(
                f"DynamicObstacle.mass_kg must be in (0, {MAX_OBSTACLE_MASS_KG:g}] "
                f"kg (MAX_OBSTACLE_MASS_KG), got {mass!r}"
            )
        object.__setattr__(self, "shape", readonly(shape))
        object.__setattr__(self, "path", readonly(path))


def _head(points: FloatArray, count: int = 4) -> str:
    text = str(points[:count].tolist())
    return text if len(points) <= count else f"{text[:-1]}, ... ({len(points)} points)]"


def _obstacle_number(value: Any, name: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        raise InputError(f"DynamicObstacle.{name} must be a number, got {value!r}")
    if not math.isfinite(value):
        raise InputError(f"DynamicObstacle.{name} must be finite, got {value!r}")
    return float(value)


def _obstacle_points(value: Any, name: str) -> FloatArray:
    """``value`` as an ``(K, 2)`` float array of finite coordinates."""
    try:
        pts = np.asarray(value, dtype=np.float64).reshape(-1, 2)
    except (TypeError, ValueError):
        raise InputError(f"DynamicObstacle.{name} must be [x, y] points, got {value!r}") from None
    if len(pts) > MAX_OBSTACLE_POINTS:
        raise InputError(
            f"DynamicObstacle.{name} has {len(pts)} points; at most "
            f"{MAX_OBSTACLE_POINTS} (MAX_OBSTACLE_POINTS)"
        )
    bad = ~np.isfinite(pts)
    if bad.any():
        k = int(np.flatnonzero(bad.any(axis=1))[0])
        raise InputError(f"DynamicObstacle.{name} point {k} must be finite, got {pts[k].tolist()}")
    return pts


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
        object.__setattr__(self, "walls", readonly(as_segments(self.walls)))
        object.__setattr__(self, "clutter", tuple(self.clutter))
        object.__setattr__(self, "dynamic_obstacles", tuple(self.dynamic_obstacles))
        object.__setattr__(self, "bounds", tuple(float(b) for b in self.bounds))

    @functools.cached_property
    def clutter_segments(self) -> FloatArray:
        """Outlines of all clutter polygons as one ``(M, 4)`` segment array."""
        parts = [polygon_ring_segments(np.asarray(p.exterior.coords)) for p in self.clutter]
        return readonly(np.vstack(parts) if parts else np.zeros((0, 4)))

    @functools.cached_property
    def obstacle_segments(self) -> FloatArray:
        """Every static surface a laser can hit: walls followed by clutter outlines."""
        return readonly(np.vstack([self.walls, self.clutter_segments]))

    @property
    def width_m(self) -> float:
        return self.bounds[2] - self.bounds[0]

    @property
    def height_m(self) -> float:
        return self.bounds[3] - self.bounds[1]
