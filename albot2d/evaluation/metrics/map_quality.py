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
true walls near each map surface (within 0.5 m of its bounding box) are found once per
surface, and its samples are measured against those few walls in numpy, with GEOS's own
point-to-segment formula (so the distances equal the tree's up to rounding). Samples
farther than that from every candidate (a drifted map) are searched again within 2 m,
then 8 m, and only the rest with the tree query.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
import shapely
from numpy.typing import ArrayLike, NDArray

from albot2d.geometry import Pose, as_segments, segment_lengths, transform_segments
from albot2d.validation import check_positive, check_positive_int

__all__ = [
    "MAX_LAST_K_VIEWS",
    "MapQuality",
    "MapQualityParams",
    "map_quality",
    "nearest_segment_distance",
    "nearest_segment_distance_bounded",
    "point_to_segment_geos",
    "sample_segments",
]


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
    starts = np.cumsum(counts) - counts
    # np.repeat per column instead of gathering rows by owner: the same numbers (the same
    # integer steps, the same b - a per segment), ~2x faster on a million samples.
    t = (np.arange(counts.sum()) - np.repeat(starts, counts)) / np.repeat(counts - 1, counts)
    out = np.empty((len(t), 2))
    for k in (0, 1):
        a = np.repeat(segs[:, k], counts)
        out[:, k] = a + t * np.repeat(segs[:, k + 2] - segs[:, k], counts)
    return out


# Walls within this distance of a map surface's bounding box are its candidates (metres);
# samples farther from all of them than that are searched again with the next distance.
_NEAR_M = (0.5, 2.0, 8.0)
# Point-wall pairs measured per numpy chunk (bounds the memory: ~150 bytes a pair).
_CHUNK_PAIRS = 1 << 16
# Samples measured per block of map surfaces.
_BLOCK_SAMPLES = 1 << 15
# Points per tree query in nearest_segment_distance_bounded.
_BLOCK_POINTS = 1 << 12


def point_to_segment_geos(
    px: NDArray[np.float64], py: NDArray[np.float64], seg: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Distances of points ``(px[i], py[i])`` to segments ``seg[i]`` (pairwise, not all
    pairs) by GEOS's ``Distance::pointToSegment``, term for term (so it equals shapely's
    result)."""
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
    """Distance from each sample of ``segs`` (``sample_segments`` order) to the truth.

    Blocks of surfaces with about ``_BLOCK_SAMPLES`` samples each are sampled and measured
    in turn, so memory stays bounded however large the map."""
    if len(segs) == 0 or len(truth) == 0:
        return nearest_segment_distance(sample_segments(segs, spacing_m), truth)
    counts = np.maximum(np.ceil(segment_lengths(segs) / spacing_m).astype(np.int64), 1) + 1
    cuts = np.searchsorted(np.cumsum(counts), np.arange(_BLOCK_SAMPLES, counts.sum(),
                                                        _BLOCK_SAMPLES))  # fmt: skip
    tree = shapely.STRtree(shapely.linestrings(truth.reshape(-1, 2, 2)))
    # Each block's distances written into one array (no list of blocks then a copy).
    out = np.empty(int(counts.sum()))
    ends = np.cumsum(counts)
    for s0, s1 in zip(np.r_[0, cuts], np.r_[cuts, len(segs)], strict=True):
        if s1 > s0:
            out[ends[s0] - counts[s0] : ends[s1 - 1]] = _block_distances(
                segs[s0:s1], spacing_m, truth, tree
            )
    return out


def _block_distances(
    segs: NDArray[np.float64], spacing_m: float, truth: NDArray[np.float64],
    tree: shapely.STRtree,
) -> NDArray[np.float64]:  # fmt: skip
    samples = sample_segments(segs, spacing_m)
    counts = np.maximum(np.ceil(segment_lengths(segs) / spacing_m).astype(np.int64), 1) + 1
    owner = np.repeat(np.arange(len(segs)), counts)
    dist = np.full(len(samples), np.inf)
    pending = np.arange(len(samples))
    for radius in _NEAR_M:
        dist[pending] = _bounded_distances(samples, pending, owner[pending], segs, truth,
                                           tree, radius)  # fmt: skip
        # A sample nearer than ``radius`` to a candidate has its exact nearest wall.
        pending = pending[~(dist[pending] <= radius)]
        if not len(pending):
            return dist
    dist[pending] = nearest_segment_distance(samples[pending], truth)
    return dist


def _bounded_distances(
    samples: NDArray[np.float64], pending: NDArray[np.int64], owner: NDArray[np.int64],
    segs: NDArray[np.float64], truth: NDArray[np.float64], tree: shapely.STRtree,
    radius: float,
) -> NDArray[np.float64]:  # fmt: skip
    """Per pending sample, its distance to the nearest wall within ``radius`` of its
    surface's bounding box (``inf`` when there is none)."""
    used = np.unique(owner)
    lo = np.minimum(segs[used, :2], segs[used, 2:]) - radius
    hi = np.maximum(segs[used, :2], segs[used, 2:]) + radius
    which, wall = tree.query(shapely.box(lo[:, 0], lo[:, 1], hi[:, 0], hi[:, 1]))
    order = np.lexsort((wall, which))
    which, wall = which[order], wall[order]
    keep = _may_be_nearest(segs[used], which, truth[wall])
    which, wall = which[keep], wall[keep]
    walls_per = np.zeros(len(segs), np.int64)
    walls_per[used] = np.bincount(which, minlength=len(used))
    wall_start = np.zeros(len(segs), np.int64)
    wall_start[used] = np.cumsum(walls_per[used]) - walls_per[used]
    out = np.full(len(pending), np.inf)
    per_sample = walls_per[owner]
    has = np.flatnonzero(per_sample > 0)
    ends = np.cumsum(per_sample[has])
    # Chunks of about _CHUNK_PAIRS (sample, candidate wall) pairs.
    cuts = np.searchsorted(ends, np.arange(_CHUNK_PAIRS, ends[-1] if len(ends) else 0,
                                           _CHUNK_PAIRS), side="right")  # fmt: skip
    for c0, c1 in zip(np.r_[0, cuts], np.r_[cuts, len(has)], strict=True):
        rows = has[c0:c1]
        if not len(rows):
            continue
        w = per_sample[rows]
        row = np.repeat(rows, w)
        k = np.arange(len(row)) - np.repeat(np.cumsum(w) - w, w)
        cand = wall[wall_start[owner[row]] + k]
        pts = samples[pending[row]]
        d = point_to_segment_geos(pts[:, 0], pts[:, 1], truth[cand])
        out[rows] = np.minimum.reduceat(d, np.cumsum(w) - w)
    return out


# Candidate walls farther than this beyond a surface's bound are dropped (metres): far
# above the rounding of the distances, so no wall that could be nearest by a rounding
# difference is dropped and the minimum is the same number.
_PRUNE_MARGIN_M = 1e-6


def _may_be_nearest(
    surfaces: NDArray[np.float64], which: NDArray[np.int64], walls: NDArray[np.float64]
) -> NDArray[np.bool_]:
    """Per (surface ``which[i]``, candidate wall ``walls[i]``) pair: whether the wall may be
    the nearest wall of some point of the surface.

    The distance from a point moving along a segment to a fixed segment is convex, so its
    largest value on the surface is at an endpoint: every point of the surface is within
    ``bound`` = min over its candidates of max(endpoint distances) of some wall. A wall
    whose bounding box is farther than that from the surface's is nobody's nearest. On a
    map along the walls this leaves one or two of a surface's candidates."""
    bound_pair = np.maximum(
        point_to_segment_geos(surfaces[which, 0], surfaces[which, 1], walls),
        point_to_segment_geos(surfaces[which, 2], surfaces[which, 3], walls),
    )
    bound = np.full(len(surfaces), np.inf)
    np.minimum.at(bound, which, bound_pair)
    s_lo = np.minimum(surfaces[:, :2], surfaces[:, 2:])[which]
    s_hi = np.maximum(surfaces[:, :2], surfaces[:, 2:])[which]
    w_lo, w_hi = np.minimum(walls[:, :2], walls[:, 2:]), np.maximum(walls[:, :2], walls[:, 2:])
    gap = np.maximum(np.maximum(w_lo - s_hi, s_lo - w_hi), 0.0)
    return np.hypot(gap[:, 0], gap[:, 1]) <= bound[which] + _PRUNE_MARGIN_M


def nearest_segment_distance(
    points: NDArray[np.float64], segments: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Distance of each ``(P, 2)`` point to the nearest of ``(S, 4)`` segments (inf if none),
    by an STRtree nearest query."""
    if len(points) == 0:
        return np.zeros(0)
    if len(segments) == 0:
        return np.full(len(points), np.inf)
    lines = shapely.linestrings(segments.reshape(-1, 2, 2))
    tree = shapely.STRtree(lines)
    pts = shapely.points(points)
    _, dist = tree.query_nearest(pts, return_distance=True, all_matches=False)
    return np.asarray(dist, dtype=np.float64)


def nearest_segment_distance_bounded(
    points: NDArray[np.float64], segments: NDArray[np.float64],
    radii_m: tuple[float, ...] = (0.5, 2.0),
    *,
    beyond: str = "nearest",
) -> NDArray[np.float64]:  # fmt: skip
    """``nearest_segment_distance`` with the same numbers, faster when most points lie near
    a segment: each point's candidates are the segments whose bounding box meets its box
    of half-side ``radii_m[0]``, measured with GEOS's formula (``point_to_segment_geos``);
    a point whose nearest candidate is within that radius has its exact nearest segment
    (any nearer one would be a candidate too). The others try the next radius, then the
    tree's nearest query; with ``beyond="inf"`` they are ``inf`` instead (for a caller who
    only asks which points lie within the last radius: the same answer)."""
    if beyond not in ("nearest", "inf"):
        raise ValueError(f"beyond must be 'nearest' or 'inf', got {beyond!r}")
    out = np.full(len(points), np.inf)
    if len(points) == 0 or len(segments) == 0:
        return nearest_segment_distance(points, segments)
    tree = shapely.STRtree(shapely.linestrings(segments.reshape(-1, 2, 2)))
    pending = np.arange(len(points))
    for radius in radii_m:
        for b0 in range(0, len(pending), _BLOCK_POINTS):
            rows = pending[b0 : b0 + _BLOCK_POINTS]
            pts = points[rows]
            lo, hi = pts - radius, pts + radius
            which, seg = tree.query(shapely.box(lo[:, 0], lo[:, 1], hi[:, 0], hi[:, 1]))
            for c0 in range(0, len(which), _CHUNK_PAIRS):
                w, sg = which[c0 : c0 + _CHUNK_PAIRS], seg[c0 : c0 + _CHUNK_PAIRS]
                d = point_to_segment_geos(pts[w, 0], pts[w, 1], segments[sg])
                np.minimum.at(out, rows[w], d)
        pending = pending[~(out[pending] <= radius)]
        if not len(pending):
            return out
    if beyond == "nearest":
        out[pending] = nearest_segment_distance(points[pending], segments)
    else:
        out[pending] = np.inf
    return out


# Cell of the grid of seen points ``_near_points`` tests surfaces against (metres), and
# surfaces per block of that test.
_NEAR_CELL_M = 1.0
_NEAR_BLOCK = 1 << 16


def _near_points(
    segs: NDArray[np.float64], points: NDArray[np.float64], reach_m: float
) -> NDArray[np.bool_]:
    """Per segment: whether a grid cell its bounding box, grown by ``reach_m`` (and a
    rounding margin), touches holds one of ``points``. A segment for which this is False is
    farther than ``reach_m`` from every point (its distance is at least the boxes' gap)."""
    reach = reach_m + _PRUNE_MARGIN_M
    origin = points.min(axis=0) - _NEAR_CELL_M
    cells = np.floor((points - origin) / _NEAR_CELL_M).astype(np.int64)
    nx, ny = cells.max(axis=0) + 2
    occupied = np.zeros((nx + 1, ny + 1), np.int64)  # summed-area table, zero first row/col
    np.add.at(occupied, (cells[:, 0] + 1, cells[:, 1] + 1), 1)
    table = occupied.cumsum(axis=0).cumsum(axis=1)
    out = np.zeros(len(segs), bool)
    for b0 in range(0, len(segs), _NEAR_BLOCK):  # blocks: a long run's map is ~800k
        block = segs[b0 : b0 + _NEAR_BLOCK]
        out[b0 : b0 + len(block)] = _touches(block, table, origin, reach)
    return out


def _touches(
    segs: NDArray[np.float64], table: NDArray[np.int64], origin: NDArray[np.float64],
    reach: float,
) -> NDArray[np.bool_]:  # fmt: skip
    nx, ny = table.shape[0] - 1, table.shape[1] - 1
    lo = np.floor((np.minimum(segs[:, :2], segs[:, 2:]) - reach - origin) / _NEAR_CELL_M)
    hi = np.floor((np.maximum(segs[:, :2], segs[:, 2:]) + reach - origin) / _NEAR_CELL_M)
    inside = np.all((hi >= 0) & (lo <= np.array([nx - 1, ny - 1])), axis=1)
    x0, y0 = (
        np.clip(lo[:, 0], 0, nx - 1).astype(np.int64),
        np.clip(lo[:, 1], 0, ny - 1).astype(np.int64),
    )
    x1, y1 = (
        np.clip(hi[:, 0], 0, nx - 1).astype(np.int64),
        np.clip(hi[:, 1], 0, ny - 1).astype(np.int64),
    )
    count = table[x1 + 1, y1 + 1] - table[x0, y1 + 1] - table[x1 + 1, y0] + table[x0, y0]
    return inside & (count > 0)


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
            # Only surfaces within reach of a seen point can cover it: a tree over the
            # few near the last views, not over a long run's whole map (820,000 surfaces
            # cost ~250 MB of GEOS geometries). The same share: farther ones are > tol.
            near = segs_world[_near_points(segs_world, seen, p.coverage_tolerance_m)]
            # Whether a point is covered needs only its candidates within the tolerance
            # (the same distances, so the same verdicts as the nearest query).
            tol = p.coverage_tolerance_m
            cover = nearest_segment_distance_bounded(seen, near, (tol,), beyond="inf")
            completeness = float(np.mean(cover <= tol))
    if len(d) == 0:
        return MapQuality(None, None, None, completeness, 0)
    if len(truth) == 0:  # nothing to be accurate against: accuracy is undefined, not inf
        return MapQuality(None, None, None, completeness, len(segs_world))
    mean, largest = float(d.mean()), float(d.max())
    # The same partition as on a copy, done in place: ``d`` is not needed after this.
    p95 = float(np.percentile(d, 95, overwrite_input=True))
    return MapQuality(mean, p95, largest, completeness, len(segs_world))
