"""The laser-hit check's optional compiled grid query (numba): ``within_kernel``.

Importing this module needs numba (a default dependency);
``albot2d.evaluation.sim_invariants.SegmentGrid.within`` loads it on first use and keeps its
numpy path otherwise. A batch of 64 frames asks ~11,000 hits, each against the few
segments its grid cell lists: the numpy path's cost is its ragged (hit, segment) pair
arrays, the kernel walks each hit's cell and stops at the first segment within reach.

The distance is the numpy path's (``_pair_distance``: the projection clipped to the
segment, ``hypot`` of the remainder), in the same float operations; a hit is within when
some listed segment is at most its tolerance away, as there.
``tests/test_campaign_speed.py`` checks both against a shapely tree query.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["ray_ranges_kernel", "within_kernel"]


@njit(cache=True, nogil=True)
def within_kernel(pts, tol, ox, oy, cell, nx, ny, start, segment_of, segs):
    """``(P,)``: each point lies within its ``tol`` of a segment its grid cell lists."""
    out = np.zeros(pts.shape[0], np.bool_)
    for i in range(pts.shape[0]):
        px, py = pts[i, 0], pts[i, 1]
        cx, cy = math.floor((px - ox) / cell), math.floor((py - oy) / cell)
        if not (0.0 <= cx < nx and 0.0 <= cy < ny):
            continue  # outside the grid: beyond every segment's reach
        c = int(cx) * ny + int(cy)
        for q in range(start[c], start[c + 1]):
            s = segment_of[q]
            ax, ay = segs[s, 0], segs[s, 1]
            dx, dy = segs[s, 2] - ax, segs[s, 3] - ay
            wx, wy = px - ax, py - ay
            length2 = dx * dx + dy * dy
            t = (wx * dx + wy * dy) / (length2 if length2 > 0.0 else 1.0)
            t = min(max(t, 0.0), 1.0)
            if math.hypot(wx - t * dx, wy - t * dy) <= tol[i]:
                out[i] = True
                break
    return out


@njit(cache=True, nogil=True)
def ray_ranges_kernel(origins, angles, segs):
    """``(M, K)``: the exact distance along each ray (``origins (M, 2)``, world ``angles
    (M, K)``, NaN: no ray) to the nearest segment; inf where a ray hits nothing. The numpy
    path's crossing parameters (``t`` along the ray, ``u`` along the segment) in the same
    float operations."""
    m, k = angles.shape
    out = np.full((m, k), np.inf)
    for i in range(m):
        ox, oy = origins[i, 0], origins[i, 1]
        for r in range(k):
            a = angles[i, r]
            if a != a:  # NaN: no ray
                continue
            dx, dy = np.cos(a), np.sin(a)
            best = np.inf
            for s in range(segs.shape[0]):
                ex, ey = segs[s, 2] - segs[s, 0], segs[s, 3] - segs[s, 1]
                wx, wy = segs[s, 0] - ox, segs[s, 1] - oy
                denom = dx * ey - dy * ex
                if denom == 0.0:
                    continue
                t = (wx * ey - wy * ex) / denom
                u = (wx * dy - wy * dx) / denom
                if t >= 0.0 and u >= 0.0 and u <= 1.0 and t < best:
                    best = t
            out[i, r] = best
    return out
