"""worldgen: procedural 2D worlds (corridors, rooms, open halls, offices) for robot simulation.

Imports only ``albot2d.geometry`` / ``albot2d.errors`` / ``albot2d.seeding`` from albot2d,
never its higher layers.
"""

from worldgen.assemble import make_world
from worldgen.generate import generate, kind_names, make_params
from worldgen.houseexpo import from_houseexpo
from worldgen.io import load, save, world_from_json, world_to_json
from worldgen.kinds import WorldKind, get_kind, register_kind, world_kinds
from worldgen.regions import REGION_KINDS, RegionParams, region_kind_at
from worldgen.roadmap import build_roadmap
from worldgen.space import build_space
from worldgen.tours import TOUR_KINDS, make_tour, plan_tour
from worldgen.world import DynamicObstacle, Roadmap, Tour, World

__all__ = [
    "REGION_KINDS",
    "TOUR_KINDS",
    "DynamicObstacle",
    "RegionParams",
    "Roadmap",
    "Tour",
    "World",
    "WorldKind",
    "build_roadmap",
    "build_space",
    "from_houseexpo",
    "generate",
    "get_kind",
    "kind_names",
    "load",
    "make_params",
    "make_tour",
    "make_world",
    "plan_tour",
    "region_kind_at",
    "register_kind",
    "save",
    "world_from_json",
    "world_kinds",
    "world_to_json",
]
