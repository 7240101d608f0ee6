"""Albot_x as SLAM robots (optional ``[slam]`` extra: kiss-icp, gtsam).

- ``mapper``: ``LoopClosingSLAM`` (``slam``) and ``ScanMatchingSLAM`` (``scan_odometry``);
- ``front_end``: KISS-ICP scan-to-map odometry with the wheel odometry as the prediction;
- ``loop_closure``: closure candidates by proximity, verified by registration;
- ``pose_graph``: the 2D pose graph of keyframes, optimised by GTSAM;
- ``graph_export``: the pose graph's factors as plain data with their effective information
  (the g2o export).

The extra's libraries are imported on first use, so importing this package costs nothing
without them. May import: geometry and core helpers, perception,
``albot2d.mapping.protocol`` and ``albot2d.mapping.baselines``.
"""

from albot2d.mapping.slam.front_end import MISSING_EXTRA, KissIcpOdometry, ScanMatchingParams
from albot2d.mapping.slam.loop_closure import LoopClosureParams
from albot2d.mapping.slam.mapper import LoopClosingSLAM, ScanMatchingSLAM, SlamParams
from albot2d.mapping.slam.pose_graph import PoseGraphParams

__all__ = [
    "MISSING_EXTRA",
    "KissIcpOdometry",
    "LoopClosingSLAM",
    "LoopClosureParams",
    "PoseGraphParams",
    "ScanMatchingParams",
    "ScanMatchingSLAM",
    "SlamParams",
]
