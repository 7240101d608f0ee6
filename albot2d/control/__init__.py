"""Controllers: policies that drive the simulator through ``Simulator.step``.

Controllers sit above the simulation layer (``albot2d.sim``) and below evaluation: they
import only ``albot2d.sim``, ``albot2d.geometry``, ``albot2d.frames``, the core helpers and
``worldgen``. This package owns

- ``knowledge``: ``KnowledgeGrid``, what the laser has shown (free / occupied / unknown
  cells, ray-cast from scans);
- ``floor``: the reachable floor of a world (the area the robot's disc can sweep from the
  start), the denominator of every coverage figure;
- ``grid_search``: shortest paths on an occupancy grid (Dijkstra, compiled when numba
  imports) and path simplification;
- ``explorer``: ``FrontierExplorer``, the scripted operator that drives to the nearest
  reachable frontier of what it has seen (it knows its true pose, as the paper's human
  operator did; a mapper fed its frames never sees that pose);
- ``navigation``: what grid controllers share: cost grids, Dijkstra plans cut to corners,
  steering along them;
- ``goal_seeker``: ``GoalSeeker``, a driver to a goal pose in its own odometry frame
  (``albot2d/GoTo-v0``'s baseline; it never sees the true pose);
- ``exploration``: ``explore`` runs an explorer in a simulator and records coverage
  against time; ``explore_frames`` turns such a drive into views for the mappers
  (``albot2d run --tour explore``).
"""

from albot2d.control.exploration import (
    EXPLORE_TOUR,
    ExplorationResult,
    ExploreDrive,
    explore,
)
from albot2d.control.explorer import ExplorerParams, FrontierExplorer
from albot2d.control.floor import ReachableFloor, reachable_floor
from albot2d.control.goal_seeker import GoalSeeker, GoalSeekerParams
from albot2d.control.knowledge import FREE, OCCUPIED, UNKNOWN, GridSpec, KnowledgeGrid

__all__ = [
    "EXPLORE_TOUR",
    "FREE",
    "OCCUPIED",
    "UNKNOWN",
    "ExplorationResult",
    "ExploreDrive",
    "ExplorerParams",
    "FrontierExplorer",
    "GoalSeeker",
    "GoalSeekerParams",
    "GridSpec",
    "KnowledgeGrid",
    "ReachableFloor",
    "explore",
    "reachable_floor",
]
