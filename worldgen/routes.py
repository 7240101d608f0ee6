"""Tours given by named waypoints: ``route_tour(world, name)`` for worlds that name them.

A kind that promises named places (the ``fig6`` kind) lists them in
``world.features["waypoints"]`` (name → ``[x, y]``) and its routes in
``world.features["routes"]`` (route name → the waypoint names driven through in straight
legs). The route's tour starts at its first waypoint, facing along its first leg
(``route_start``), so a run on a route starts where the paper's robot started.
"""

from __future__ import annotations

import math

import numpy as np

from albot2d.errors import InputError
from albot2d.geometry import Pose
from worldgen.world import Tour, World

__all__ = ["route_names", "route_start", "route_tour", "waypoint_arclength_m"]


def route_names(world: World) -> tuple[str, ...]:
    """The routes ``world`` names (empty for kinds without named waypoints)."""
    return tuple(world.features.get("routes", {}))


def _route(world: World, name: str) -> tuple[list[str], np.ndarray]:
    routes = world.features.get("routes", {})
    if name not in routes:
        valid = ", ".join(routes) or "none (this world names no routes)"
        raise InputError(f"unknown route {name!r} for a {world.kind} world; valid: {valid}")
    names = list(routes[name])
    places = world.features["waypoints"]
    return names, np.array([places[n] for n in names], dtype=np.float64)


def route_tour(world: World, name: str) -> Tour:
    """The Tour through route ``name``'s waypoints (kind ``route:NAME``)."""
    _, points = _route(world, name)
    keep = np.r_[True, np.hypot(*np.diff(points, axis=0).T) > 0.0]
    return Tour(waypoints=points[keep], kind=f"route:{name}")


def route_start(world: World, name: str) -> Pose:
    """The route's first waypoint, facing along its first leg."""
    _, points = _route(world, name)
    legs = np.diff(points, axis=0)
    lead = legs[np.flatnonzero(np.hypot(*legs.T) > 0.0)[0]]
    return Pose(float(points[0, 0]), float(points[0, 1]), math.atan2(lead[1], lead[0]))


def waypoint_arclength_m(world: World, name: str) -> dict[str, list[float]]:
    """Distance along route ``name`` (metres from its start) at which each named waypoint
    is reached, every time it is reached."""
    names, points = _route(world, name)
    along = np.r_[0.0, np.cumsum(np.hypot(*np.diff(points, axis=0).T))]
    out: dict[str, list[float]] = {}
    for n, s in zip(names, along, strict=True):
        out.setdefault(n, []).append(float(s))
    return out
