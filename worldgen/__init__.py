"""worldgen: procedural 2D worlds (corridors, rooms, open halls, offices) for robot simulation.

Imports only ``albot2d.geometry`` / ``albot2d.errors`` / ``albot2d.seeding`` from albot2d,
never its higher layers.
"""

from worldgen.houseexpo import from_houseexpo
from worldgen.io import load, save, world_from_json, world_to_json
from worldgen.space import build_space
from worldgen.world import DynamicObstacle, Roadmap, Tour, World

__all__ = [
    "DynamicObstacle",
    "Roadmap",
    "Tour",
    "World",
    "build_space",
    "from_houseexpo",
    "load",
    "save",
    "world_from_json",
    "world_to_json",
]
