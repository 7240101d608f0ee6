"""Region kinds of a world's places: ``corridor``, ``room`` or ``hall`` (an open area).

The paper's Fig. 14 contrasts updating "in a corridor" with updating in "a more open
spaced area"; this module labels any point of any world (generated, HouseExpo or loaded)
from its walls alone, by the shape of what can be seen from it (an *isovist*, Benedikt
1979): rays are cast from the point in ``RegionParams.rays`` directions against the walls
(not the clutter: a table does not make a hall a room), and

- ``corridor``: the narrowest cross-section through the point (the shortest
  ``r(θ) + r(θ + π)``) is at most ``corridor_max_width_m`` and the longest is at least
  ``corridor_min_aspect`` times it: a long, narrow space;
- ``hall``: otherwise, when the area seen (the isovist, rays capped at ``max_range_m``)
  is at least ``hall_min_area_m2``;
- ``room``: otherwise (a small enclosed space).

A point in a doorway counts as a corridor (narrow, and long through the door); the
3.5 m width lets a junction of two ~2.2 m corridors (diagonal ~3.1 m) stay a corridor.
On office seed 0 the defaults label 46 of the 50 roadmap nodes in its open area ``hall``
and 2 of the 569 outside it. Points outside the free space get ``outside``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import shapely
from numpy.typing import ArrayLike, NDArray

from albot2d.errors import InputError
from albot2d.validation import check_positive, check_positive_int

if TYPE_CHECKING:
    from worldgen.world import World

__all__ = [
    "REGION_KINDS",
    "RegionParams",
    "isovist_ranges",
    "isovist_ranges_many",
    "region_kind_at",
]

REGION_KINDS = ("corridor", "room", "hall")


@dataclass(frozen=True)
class RegionParams:
    """Thresholds of the isovist classification (see the module docstring)."""

    rays: int = 72
    max_range_m: float = 30.0
    corridor_max_width_m: float = 3.5
    corridor_min_aspect: float = 3.0
    hall_min_area_m2: float = 100.0

    def __post_init__(self) -> None:
        check_positive_int(self, "rays")
        check_positive(
            self, "max_range_m", "corridor_max_width_m", "corridor_min_aspect", "hall_min_area_m2"
        )
        if self.rays % 2:
            raise InputError(f"RegionParams.rays must be even (opposite pairs), got {self.rays}")


def isovist_ranges(
    segments: np.ndarray, xy: ArrayLike, rays: int, max_range_m: float
) -> NDArray[np.float64]:
    """Distance from ``xy`` to the first segment along ``rays`` evenly spaced directions
    (the first along +x), capped at ``max_range_m``."""
    p = np.asarray(xy, dtype=np.float64).reshape(2)
    theta = np.arange(rays) * (2.0 * np.pi / rays)
    d = np.column_stack([np.cos(theta), np.sin(theta)])  # (R, 2)
    if len(segments) == 0:
        return np.full(rays, max_range_m)
    a = segments[:, :2] - p  # (S, 2)
    e = segments[:, 2:] - segments[:, :2]  # (S, 2)
    # p + t·d = a + u·e  →  t·d − u·e = a; Cramer's rule per (ray, segment)
    den = d[:, None, 0] * (-e[None, :, 1]) - d[:, None, 1] * (-e[None, :, 0])
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (a[None, :, 0] * (-e[None, :, 1]) - a[None, :, 1] * (-e[None, :, 0])) / den
        u = (d[:, None, 0] * a[None, :, 1] - d[:, None, 1] * a[None, :, 0]) / den
    hit = (np.abs(den) > 1e-12) & (t >= 0.0) & (u >= 0.0) & (u <= 1.0)
    t = np.where(hit, t, np.inf).min(axis=1)
    return np.minimum(t, max_range_m)


# A ray whose direction is within this angle (rad) of a segment's angular span from the
# point is measured against it; far above the rounding of the span's angles, so every
# (ray, segment) pair that isovist_ranges' test could accept is measured.
_ANGLE_MARGIN_RAD = 1e-6
# A segment whose line passes this close to the point (relative to its length) spans an
# ill-defined angle from it: every ray is measured against it.
_COLLINEAR_REL = 1e-9
# Points per block in isovist_ranges_many: its temporaries are points × segments × rays
# in each segment's span (48 MB in blocks of 256 on the office world, a run's memory peak
# when its updates were labelled; 12 MB in blocks of 64, at no measured cost in time).
# Each point gets the same ranges whatever the block.
_BLOCK_POINTS = 64


def isovist_ranges_many(
    segments: np.ndarray, points: ArrayLike, rays: int, max_range_m: float
) -> NDArray[np.float64]:
    """``isovist_ranges`` of each of the ``(P, 2)`` points, as a ``(P, rays)`` array: the
    same numbers, bit for bit, ~10x faster on a world of a thousand walls.

    A ray can only hit a segment whose angular span seen from the point contains the ray's
    direction, and a ray crosses a few of a world's walls, not all: so each segment is
    measured (with ``isovist_ranges``' own formula, term for term) only against the rays
    within its span (plus a margin), and the nearest hit per ray is a minimum over those."""
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    segs = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
    if len(segs) == 0:
        return np.full((len(pts), rays), max_range_m)
    step = 2.0 * np.pi / rays
    theta = np.arange(rays) * step
    d = np.column_stack([np.cos(theta), np.sin(theta)])  # (R, 2), as isovist_ranges
    e = segs[:, 2:] - segs[:, :2]  # (S, 2)
    length = np.hypot(e[:, 0], e[:, 1])
    out = np.empty((len(pts), rays))
    for b0 in range(0, len(pts), _BLOCK_POINTS):
        block = pts[b0 : b0 + _BLOCK_POINTS]
        ax = segs[None, :, 0] - block[:, None, 0]  # (B, S): segments[:, :2] - p
        ay = segs[None, :, 1] - block[:, None, 1]
        bx, by = ax + e[None, :, 0], ay + e[None, :, 1]  # the far ends (for the span only)
        phi_a, phi_b = np.arctan2(ay, ax), np.arctan2(by, bx)
        sweep = np.mod(phi_b - phi_a + np.pi, 2.0 * np.pi) - np.pi  # signed, (-π, π]
        start = np.where(sweep >= 0.0, phi_a, phi_b)
        first = np.ceil((start - _ANGLE_MARGIN_RAD) / step).astype(np.int64)
        last = np.floor((start + np.abs(sweep) + _ANGLE_MARGIN_RAD) / step).astype(np.int64)
        # Nearly collinear with the point (or degenerate): measured against every ray.
        cross = np.abs(ax * e[None, :, 1] - ay * e[None, :, 0])
        near_line = cross <= _COLLINEAR_REL * np.maximum(length, 1.0)[None, :] ** 2
        first = np.where(near_line, 0, first)
        last = np.where(near_line, rays - 1, np.minimum(last, first + rays - 1))
        count = np.maximum(last - first + 1, 0).ravel()
        pair_pt, pair_seg = np.divmod(np.repeat(np.arange(count.size), count), len(segs))
        offset = np.arange(len(pair_pt)) - np.repeat(np.cumsum(count) - count, count)
        ray = np.mod(first.ravel()[pair_pt * len(segs) + pair_seg] + offset, rays)
        # isovist_ranges' formula, term for term, on the (ray, segment) pairs
        a0, a1 = ax[pair_pt, pair_seg], ay[pair_pt, pair_seg]
        e0, e1 = e[pair_seg, 0], e[pair_seg, 1]
        d0, d1 = d[ray, 0], d[ray, 1]
        den = d0 * (-e1) - d1 * (-e0)
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (a0 * (-e1) - a1 * (-e0)) / den
            u = (d0 * a1 - d1 * a0) / den
        hit = (np.abs(den) > 1e-12) & (t >= 0.0) & (u >= 0.0) & (u <= 1.0)
        nearest = np.full(len(block) * rays, np.inf)
        np.minimum.at(nearest, pair_pt[hit] * rays + ray[hit], t[hit])
        out[b0 : b0 + len(block)] = np.minimum(nearest.reshape(len(block), rays), max_range_m)
    return out


def region_kind_at(
    world: World, xy: ArrayLike, params: RegionParams | None = None
) -> NDArray[np.str_]:
    """The region kind (``corridor``, ``room``, ``hall``; ``outside`` off the free space)
    at each of the ``(N, 2)`` points ``xy`` (or one point)."""
    params = params or RegionParams()
    pts = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    if not np.isfinite(pts).all():
        raise InputError("region_kind_at: points must be finite")
    inside = shapely.covers(world.free_space, shapely.points(pts))
    out = np.full(len(pts), "outside", dtype="<U8")
    half = params.rays // 2
    step = 2.0 * np.pi / params.rays
    rows = np.flatnonzero(inside)
    ranges = isovist_ranges_many(world.walls, pts[rows], params.rays, params.max_range_m)
    for i, r in zip(rows, ranges, strict=True):
        across = r[:half] + r[half:]
        width, length = float(across.min()), float(across.max())
        area = 0.5 * float((r * r).sum()) * step
        if width <= params.corridor_max_width_m and length >= params.corridor_min_aspect * width:
            out[i] = "corridor"
        elif area >= params.hall_min_area_m2:
            out[i] = "hall"
        else:
            out[i] = "room"
    return out
