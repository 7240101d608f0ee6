"""Where a surface really ends: corner refinement and endpoint-uncertainty flags.

A laser samples a surface only at its beams, so an endpoint taken from the last hit is
uncertain by the spacing of the beams on that surface. Triangulation trusts unoccluded
endpoints as real corners, so two refinements matter:

- **Corners between adjacent surfaces** (a split point inside a continuous run, where two
  walls meet): the corner is the intersection of the two fitted lines, not the beam
  nearest it. Used when the lines meet at an angle of at least ``corner_min_angle_deg``
  and the intersection lies where the corner can be: between the beams on either side of
  the split (one beam of slack), or within ``corner_max_shift_m`` of both endpoints.
- **Ends at a range jump** to a farther neighbour: the surface ends somewhere between the
  last hit and where the neighbouring beam crosses the surface's line. When that interval
  is longer than ``max_endpoint_gap_m`` (a wall seen at a grazing angle), the end is not
  known well enough to localise from: it is flagged occluded ("unknown").
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

__all__ = ["jump_end_gaps", "refine_corners"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


def refine_corners(
    segs: FloatArray,
    a: IntArray,
    b: IntArray,
    lines: tuple[FloatArray, FloatArray, FloatArray],
    joined_next: NDArray[np.bool_],
    beam_angles: FloatArray,
    *,
    min_angle_deg: float,
    max_shift_m: float,
) -> FloatArray:
    """Move shared corners of consecutive surfaces to their lines' intersection.

    ``segs`` (laser frame) are in scan order; surface ``i`` and ``i+1`` share a corner when
    ``b[i] >= a[i+1] - 1`` and the beams between them are joined in one run.
    """
    n = len(segs)
    if n < 2:
        return segs
    nx, ny, c = lines
    i = np.arange(n - 1)
    j = i + 1
    adjacent = (b[i] >= a[j] - 1) & joined_next[np.minimum(b[i], a[j])]
    det = nx[i] * ny[j] - ny[i] * nx[j]  # sin of the angle between the lines
    sharp = np.abs(det) >= math.sin(math.radians(min_angle_deg))
    ok = adjacent & sharp
    if not ok.any():
        return segs
    safe = np.where(ok, det, 1.0)
    px = (c[i] * ny[j] - ny[i] * c[j]) / safe
    py = (nx[i] * c[j] - c[i] * nx[j]) / safe
    shift_i = np.hypot(px - segs[i, 2], py - segs[i, 3])
    shift_j = np.hypot(px - segs[j, 0], py - segs[j, 1])
    near = (shift_i <= max_shift_m) & (shift_j <= max_shift_m)
    last = len(beam_angles) - 1
    lo = beam_angles[np.clip(np.minimum(b[i], a[j]) - 1, 0, last)]
    hi = beam_angles[np.clip(np.maximum(b[i], a[j]) + 1, 0, last)]
    bearing = np.arctan2(py, px)
    between = (bearing >= lo) & (bearing <= hi) & (px * np.cos(bearing) + py * np.sin(bearing) > 0)
    ok &= near | between
    out = segs.copy()
    k = np.flatnonzero(ok)
    out[k, 2], out[k, 3] = px[k], py[k]
    out[k + 1, 0], out[k + 1, 1] = px[k], py[k]
    return out


def jump_end_gaps(
    ends_xy: FloatArray,
    neighbour_angle: FloatArray,
    lines: tuple[FloatArray, FloatArray, FloatArray],
) -> FloatArray:
    """Length of the interval in which each surface may really end (metres, laser frame).

    ``ends_xy (M, 2)`` are the endpoints on the fitted lines; ``neighbour_angle (M,)`` the
    bearing of the beam next to each end (outside the surface). The gap is the distance
    from the endpoint to where that beam crosses the line; ``inf`` when it never does
    in front of the laser.
    """
    nx, ny, c = lines
    ux, uy = np.cos(neighbour_angle), np.sin(neighbour_angle)
    denom = nx * ux + ny * uy
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(np.abs(denom) > 1e-12, c / denom, np.inf)
    t = np.where(t > 0.0, t, np.inf)
    with np.errstate(invalid="ignore"):
        gap = np.hypot(t * ux - ends_xy[:, 0], t * uy - ends_xy[:, 1])
    return np.where(np.isfinite(t), gap, np.inf)
