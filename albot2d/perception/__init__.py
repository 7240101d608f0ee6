"""Perception: laser points → surfaces (line extraction, occlusion) and surface tracking."""

from albot2d.perception.extraction import ExtractionParams, extract_surfaces
from albot2d.perception.surfaces import Surface, Surfaces
from albot2d.perception.tracking import (
    MatchInfo,
    TrackedSurfaces,
    TrackingParams,
    match_surfaces,
    rtsv,
    start_tracking,
    trackable_mask,
    view_angles_rad,
)

__all__ = [
    "ExtractionParams",
    "MatchInfo",
    "Surface",
    "Surfaces",
    "TrackedSurfaces",
    "TrackingParams",
    "extract_surfaces",
    "match_surfaces",
    "rtsv",
    "start_tracking",
    "trackable_mask",
    "view_angles_rad",
]
