"""The reachable floor of a world: ``ReachableFloor`` and ``reachable_floor``.

The floor the robot can reach is the area its disc can sweep from the start: the world's
free space (walls and clutter removed) eroded by the robot's radius (the places its centre
can be), the connected part holding the start, grown back by the radius (morphological
opening, exact in shapely). Rooms behind a gap narrower than the robot, and corners too
tight for the disc, are not reachable floor. Coverage is the fraction of this area, rastered
on a ``GridSpec`` (cells whose centre lies inside), that the laser has shown.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import shapely
from numpy.typing import NDArray

from albot2d.control.knowledge import GridSpec
from albot2d.errors import InputError
from worldgen.world import World

__all__ = ["ReachableFloor", "reachable_floor"]

# Arc resolution of the buffers (segments per quarter circle): shapely's default, 8,
# is coarse against a 0.25 m disc; 16 keeps the area within ~0.1 % of the exact opening.
_QUAD_SEGS = 16


@dataclass(frozen=True, eq=False)
class ReachableFloor:
    """The reachable floor as a polygon (``area_m2``) and as a cell mask over ``spec``."""

    polygon: shapely.Geometry
    spec: GridSpec
    mask: NDArray[np.bool_]

    @property
    def area_m2(self) -> float:
        return float(self.polygon.area)

    @cached_property
    def cells(self) -> int:
        # Cached: coverage is read every step, and a sum over the whole grid would make a
        # step's cost follow the building's size instead of what the laser reaches.
        return int(np.count_nonzero(self.mask))

    def coverage(self, seen: NDArray[np.bool_]) -> float:
        """The fraction of the reachable floor's cells in ``seen`` (a mask over ``spec``)."""
        return float(np.count_nonzero(seen & self.mask)) / max(self.cells, 1)


def reachable_floor(world: World, spec: GridSpec, radius_m: float | None = None) -> ReachableFloor:
    """The floor the robot's disc (``radius_m``, default the world's robot radius) can sweep
    from the world's start, as a polygon and rastered on ``spec``."""
    radius = world.robot_radius_m if radius_m is None else float(radius_m)
    centres = shapely.buffer(world.free_space, -radius, quad_segs=_QUAD_SEGS)
    start = shapely.Point(world.start.x, world.start.y)
    parts = [p for p in shapely.get_parts(centres) if p.distance(start) <= 1e-6]
    if not parts:
        raise InputError(
            f"world {world.kind} seed {world.seed}: the start ({world.start.x:.3f}, "
            f"{world.start.y:.3f}) has no room for a robot of radius {radius} m"
        )
    swept = shapely.intersection(
        shapely.buffer(parts[0], radius, quad_segs=_QUAD_SEGS), world.free_space
    )
    xs, ys = spec.centres()
    mask = shapely.contains_xy(swept, xs, ys)
    return ReachableFloor(swept, spec, np.asarray(mask, dtype=bool))
