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

__all__ = ["REGION_KINDS", "RegionParams", "isovist_ranges", "region_kind_at"]

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
    for i in np.flatnonzero(inside):
        r = isovist_ranges(world.walls, pts[i], params.rays, params.max_range_m)
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
