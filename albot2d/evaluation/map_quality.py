"""Map quality against the true walls (simulation only).

- Accuracy: map surfaces are sampled every ``sample_spacing_m`` along their length and
  each sample's distance to the nearest true obstacle segment is taken; mean, p95 and
  max are length-weighted by construction.
- Completeness: of the true surface points seen in the last ``last_k_views`` views (the
  valid laser hits, placed by the true pose), the share that lies within
  ``coverage_tolerance_m`` of a map surface. Albot1's map is transient by design, so only
  what was recently seen is asked of it.

The map is compared in the world frame: a mapper's global frame is its first pose's
frame, so map segments are mapped by the true start pose first.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
import shapely
from numpy.typing import ArrayLike, NDArray

from albot2d.geometry import Pose, as_segments, segment_lengths, transform_segments
from albot2d.validation import check_positive, check_positive_int

__all__ = ["MAX_LAST_K_VIEWS", "MapQuality", "MapQualityParams", "map_quality", "sample_segments"]


#: Most recent views map completeness may be asked over (more than any run has).
MAX_LAST_K_VIEWS = 1_000_000


@dataclass(frozen=True, slots=True)
class MapQualityParams:
    sample_spacing_m: float = 0.05
    coverage_tolerance_m: float = 0.10
    last_k_views: int = 10

    def __post_init__(self) -> None:
        check_positive(self, "sample_spacing_m", "coverage_tolerance_m")
        check_positive_int(self, "last_k_views", maximum=MAX_LAST_K_VIEWS)


@dataclass(frozen=True, slots=True)
class MapQuality:
    accuracy_m_mean: float | None
    accuracy_m_p95: float | None
    accuracy_m_max: float | None
    completeness: float | None
    surfaces: int

    def to_dict(self) -> dict[str, float | int | None]:
        return asdict(self)


def sample_segments(segments: ArrayLike, spacing_m: float) -> NDArray[np.float64]:
    """Points every ≤ ``spacing_m`` along each segment, endpoints included; ``(P, 2)``."""
    segs = as_segments(segments)
    if len(segs) == 0:
        return np.zeros((0, 2))
    counts = np.maximum(np.ceil(segment_lengths(segs) / spacing_m).astype(np.int64), 1) + 1
    owner = np.repeat(np.arange(len(segs)), counts)
    starts = np.cumsum(counts) - counts
    t = (np.arange(counts.sum()) - starts[owner]) / (counts[owner] - 1)
    a, b = segs[owner, :2], segs[owner, 2:]
    return a + t[:, None] * (b - a)


def _nearest_distance(points: NDArray[np.float64], segments: NDArray[np.float64]) -> NDArray:
    if len(points) == 0:
        return np.zeros(0)
    if len(segments) == 0:
        return np.full(len(points), np.inf)
    lines = shapely.linestrings(segments.reshape(-1, 2, 2))
    tree = shapely.STRtree(lines)
    pts = shapely.points(points)
    _, dist = tree.query_nearest(pts, return_distance=True, all_matches=False)
    return np.asarray(dist, dtype=np.float64)


def map_quality(
    map_segments: ArrayLike,
    true_segments: ArrayLike,
    *,
    start_pose: Pose,
    seen_points: ArrayLike | None = None,
    params: MapQualityParams | None = None,
) -> MapQuality:
    """Accuracy and completeness of a map (in the mapper's frame) against the truth.

    ``seen_points``: true surface points (world frame) to measure completeness on; the
    caller collects them from the last K views.
    """
    p = params or MapQualityParams()
    segs_world = transform_segments(start_pose.as_array(), as_segments(map_segments))
    truth = as_segments(true_segments)
    samples = sample_segments(segs_world, p.sample_spacing_m)
    d = _nearest_distance(samples, truth)
    completeness = None
    if seen_points is not None:
        seen = np.asarray(seen_points, np.float64).reshape(-1, 2)
        if len(seen):
            cover = _nearest_distance(seen, segs_world)
            completeness = float(np.mean(cover <= p.coverage_tolerance_m))
    if len(d) == 0:
        return MapQuality(None, None, None, completeness, 0)
    return MapQuality(
        float(d.mean()), float(np.percentile(d, 95)), float(d.max()), completeness, len(segs_world)
    )
