"""Mapping: the Albot1 view-based mapper, its route and global maps, and the Albot_x baselines."""

from albot2d.mapping.albot1.global_map import GlobalMap, GlobalMapParams, UpdateReport, view_polygon
from albot2d.mapping.albot1.mapper import Albot1, Albot1Params, StepRecord
from albot2d.mapping.albot1.route_map import LocalMap, Method, RouteMap
from albot2d.mapping.albot1.triangulation import (
    Affordances,
    TriangulationParams,
    pose_affordances,
    triangulate,
)
from albot2d.mapping.baselines import GroundTruthIntegration, NaiveIntegration
from albot2d.mapping.protocol import (
    LoopClosingMapper,
    Mapper,
    MapperCounts,
    MapSnapshot,
    PerceivingMapper,
    StageTimer,
    ViewBasedMapper,
)

__all__ = [
    "Affordances",
    "Albot1",
    "Albot1Params",
    "GlobalMap",
    "GlobalMapParams",
    "GroundTruthIntegration",
    "LocalMap",
    "LoopClosingMapper",
    "MapSnapshot",
    "Mapper",
    "MapperCounts",
    "Method",
    "NaiveIntegration",
    "PerceivingMapper",
    "RouteMap",
    "StageTimer",
    "StepRecord",
    "TriangulationParams",
    "UpdateReport",
    "ViewBasedMapper",
    "pose_affordances",
    "triangulate",
    "view_polygon",
]
