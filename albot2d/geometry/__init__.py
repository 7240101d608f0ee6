"""Geometry: SE(2) poses and vectorised segment math (the bottom layer of albot2d)."""

from albot2d.geometry.pose import (
    Pose,
    add_angle,
    between_arrays,
    compose_arrays,
    invert_arrays,
    transform_points,
    wrap_angle,
)
from albot2d.geometry.segments import (
    as_segments,
    point_segment_distance,
    polygon_ring_segments,
    segment_angles,
    segment_lengths,
    segment_midpoints,
    transform_segments,
    undirected_angle_difference,
)

__all__ = [
    "Pose",
    "add_angle",
    "as_segments",
    "between_arrays",
    "compose_arrays",
    "invert_arrays",
    "point_segment_distance",
    "polygon_ring_segments",
    "segment_angles",
    "segment_lengths",
    "segment_midpoints",
    "transform_points",
    "transform_segments",
    "undirected_angle_difference",
    "wrap_angle",
]
