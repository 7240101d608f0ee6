"""worldgen: procedural 2D worlds (corridors, rooms, open halls, offices) for robot simulation.

Imports only ``albot2d.geometry`` / ``albot2d.errors`` / ``albot2d.seeding`` from albot2d,
never its higher layers.
"""

from worldgen.assemble import make_world
from worldgen.generate import KINDS, generate, make_params
from worldgen.houseexpo import from_houseexpo
from worldgen.io import load, save, world_from_json, world_to_json
from worldgen.regions import REGION_KINDS, RegionParams, region_kind_at
from worldgen.roadmap import build_roadmap
from worldgen.space import build_space
from worldgen.tours import TOUR_KINDS, make_tour, plan_tour
from worldgen.world import DynamicObstacle, Roadmap, Tour, World

__all__ = [
    "KINDS",
    "REGION_KINDS",
    "TOUR_KINDS",
    "DynamicObstacle",
    "RegionParams",
    "Roadmap",
    "Tour",
    "World",
    "build_roadmap",
    "build_space",
    "from_houseexpo",
    "generate",
    "load",
    "make_params",
    "make_tour",
    "make_world",
    "plan_tour",
    "region_kind_at",
    "save",
    "world_from_json",
    "world_to_json",
]
