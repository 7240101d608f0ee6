"""Metrics: numbers that judge a mapper's poses and maps against the truth.

- ``rpe``: relative pose error against a relations file (Kümmerle et al. 2009);
- ``alignment``: a mapper's frame → the world frame, and the absolute pose error after
  SE(2) alignment;
- ``homing``: the paper's orientation to the start (Table 1);
- ``map_quality``: a map against the true walls (simulation only);
- ``egocentric``: a map judged from where the robot is now (simulation only);
- ``updates``: moves per global-map update by region kind (the paper's Fig. 14).

Pure functions over arrays and typed results; they know nothing of runs or files.
May import: geometry and core helpers, ``worldgen``, ``albot2d.mapping`` (for types).
"""

from albot2d.evaluation.metrics.alignment import (
    AbsolutePoseError,
    absolute_pose_error,
    in_world_frame,
    map_in_world_frame,
)
from albot2d.evaluation.metrics.homing import HomingResult, homing, homing_to_start
from albot2d.evaluation.metrics.map_quality import MapQuality, MapQualityParams, map_quality
from albot2d.evaluation.metrics.rpe import RPEResult, RPEStats, relative_pose_error

__all__ = [
    "AbsolutePoseError",
    "HomingResult",
    "MapQuality",
    "MapQualityParams",
    "RPEResult",
    "RPEStats",
    "absolute_pose_error",
    "homing",
    "homing_to_start",
    "in_world_frame",
    "map_in_world_frame",
    "map_quality",
    "relative_pose_error",
]
