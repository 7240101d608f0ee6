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

Cost: a long run's naive and truth maps hold tens of thousands of surfaces, a million
samples; a nearest-wall tree query per sample was a quarter of ``albot2d run``. So the
true walls near each map surface (within ``_NEAR_M`` of its bounding box) are found once
per surface, and its samples are measured against those few walls in numpy, with GEOS's
own point-to-segment formula (so the distances equal the tree's). Only samples farther
than ``_NEAR_M`` from every such wall (then possibly nearer to another) fall back to
the tree query.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
import shapely
from numpy.typing import ArrayLike, NDArray

from albot2d.geometry import Pose, as_segments, segment_lengths, transform_segments
from albot2d.validation import check_positive, check_positive_int

__all__ = ["MapQuality", "MapQualityParams", "map_quality", "sample_segments"]


@dataclass(frozen=True, slots=True)
class MapQualityParams:
    sample_spacing_m: float = 0.05
    coverage_tolerance_m: float = 0.10
    last_k_views: int = 10

    def __post_init__(self) -> None:
        check_positive(self, "sample_spacing_m", "coverage_tolerance_m")
        check_positive_int(self, "last_k_views")


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


# Walls within this distance of a map surface's bounding box are its candidates (metres).
_NEAR_M = 0.5
# Point-wall pairs measured per numpy chunk (bounds the memory: ~40 bytes a pair).
_CHUNK_PAIRS = 1 << 20


def _point_segment_distance(
    px: NDArray[np.float64], py: NDArray[np.float64], seg: NDArray[np.float64]
) -> NDArray[np.float64]:
    """GEOS's ``Distance::pointToSegment``, term for term (so it equals shapely's result)."""
    ax, ay, bx, by = seg[:, 0], seg[:, 1], seg[:, 2], seg[:, 3]
    ex, ey = bx - ax, by - ay
    len2 = ex * ex + ey * ey
    with np.errstate(divide="ignore", invalid="ignore"):
        r = ((px - ax) * ex + (py - ay) * ey) / len2
        s = ((ay - py) * ex - (ax - px) * ey) / len2
    da = np.sqrt((px - ax) * (px - ax) + (py - ay) * (py - ay))
    db = np.sqrt((px - bx) * (px - bx) + (py - by) * (py - by))
    d = np.where(r <= 0.0, da, np.where(r >= 1.0, db, np.abs(s) * np.sqrt(len2)))
    return np.where((ax == bx) & (ay == by), da, d)


def _sample_distances(
    segs: NDArray[np.float64], spacing_m: float, truth: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Distance from each sample of ``segs`` (``sample_segments`` order) to the truth."""
    samples = sample_segments(segs, spacing_m)
    if len(samples) == 0 or len(truth) == 0:
        return _nearest_distance(samples, truth)
    counts = np.maximum(np.ceil(segment_lengths(segs) / spacing_m).astype(np.int64), 1) + 1
    first = np.cumsum(counts) - counts
    lo = np.minimum(segs[:, :2], segs[:, 2:]) - _NEAR_M
    hi = np.maximum(segs[:, :2], segs[:, 2:]) + _NEAR_M
    tree = shapely.STRtree(shapely.linestrings(truth.reshape(-1, 2, 2)))
    seg_of, wall = tree.query(shapely.box(lo[:, 0], lo[:, 1], hi[:, 0], hi[:, 1]))
    order = np.lexsort((wall, seg_of))
    seg_of, wall = seg_of[order], wall[order]
    walls_per_seg = np.bincount(seg_of, minlength=len(segs))
    wall_start = np.cumsum(walls_per_seg) - walls_per_seg
    dist = np.full(len(samples), np.inf)
    pairs_per_seg = counts * walls_per_seg
    # Chunks of whole surfaces with about _CHUNK_PAIRS sample-wall pairs each.
    bounds = np.searchsorted(np.cumsum(pairs_per_seg), np.arange(1, 1 + pairs_per_seg.sum()
                             // _CHUNK_PAIRS) * _CHUNK_PAIRS)  # fmt: skip
    for s0, s1 in zip(np.r_[0, bounds], np.r_[bounds, len(segs)], strict=True):
        if s1 <= s0:
            continue
        sl = np.arange(s0, s1)
        sl = sl[walls_per_seg[sl] > 0]
        if not len(sl):
            continue
        # Every (sample, candidate wall) pair of these surfaces.
        n_pairs = counts[sl] * walls_per_seg[sl]
        pair_seg = np.repeat(sl, n_pairs)
        k = np.arange(int(n_pairs.sum())) - np.repeat(np.cumsum(n_pairs) - n_pairs, n_pairs)
        w = walls_per_seg[pair_seg]
        sample = first[pair_seg] + k // w
        cand = wall[wall_start[pair_seg] + k % w]
        d = _point_segment_distance(samples[sample, 0], samples[sample, 1], truth[cand])
        # Pairs come sample by sample, so each sample's pairs are one contiguous group.
        group = np.flatnonzero(np.r_[True, sample[1:] != sample[:-1]])
        dist[sample[group]] = np.minimum.reduceat(d, group)
    far = np.flatnonzero(dist > _NEAR_M)
    if len(far):
        dist[far] = _nearest_distance(samples[far], truth)
    return dist


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
    d = _sample_distances(segs_world, p.sample_spacing_m, truth)
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
