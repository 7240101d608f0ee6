"""Albot₁, the paper's view-based mapper: its main loop, route map, global map and parts.

- ``mapper``: ``Albot1`` and ``Albot1Params`` — algorithms #2–#4 (main loop, update the
  maps, path integration);
- ``route_map``: the remembered views and each one's pose in its predecessor;
- ``triangulation``: localising a view in the current local map from tracked surfaces
  (with ``triangulation_numba``, its optional compiled kernel);
- ``global_map``: the transient global map of algorithm #5, with ``deletion`` (the rule
  that decides what an incoming view deletes; ``deletion_numba`` its compiled kernels).

May import: geometry and core helpers, perception, ``albot2d.mapping.protocol``.
"""

from albot2d.mapping.albot1.global_map import GlobalMap, GlobalMapParams, UpdateReport, view_polygon
from albot2d.mapping.albot1.mapper import Albot1, Albot1Params, StepRecord, UpdateSummary
from albot2d.mapping.albot1.route_map import LocalMap, Method, RouteMap
from albot2d.mapping.albot1.triangulation import (
    Affordances,
    TriangulationParams,
    pose_affordances,
    triangulate,
)

__all__ = [
    "Affordances",
    "Albot1",
    "Albot1Params",
    "GlobalMap",
    "GlobalMapParams",
    "LocalMap",
    "Method",
    "RouteMap",
    "StepRecord",
    "TriangulationParams",
    "UpdateReport",
    "UpdateSummary",
    "pose_affordances",
    "triangulate",
    "view_polygon",
]
