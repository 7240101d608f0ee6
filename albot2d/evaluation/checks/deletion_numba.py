"""The deletion invariant's optional compiled prefilter (numba): ``possible_points``.

Importing this module needs numba (a default dependency);
``albot2d.evaluation.checks.deletion`` loads it on first use and keeps its numpy path
otherwise. An update asks a few hundred sample points of the older surfaces against a
dozen view surfaces, so the numpy path's cost is its array calls, not arithmetic.

The kernel proves points unseen by the same three tests as the numpy path
(``_SightLines.out_of_reach`` and ``surely_unseen``: beyond the view's reach, outside every
fan, or past the farther end of a fan they lie inside), with the same margins, and a
fourth: inside a surface's narrowed fan (so the sight line crosses that surface), more
than ``beyond_m`` (and a micrometre) past the crossing, measured along the sight line
(where the line through the viewpoint and the point meets the surface's line). It stops
asking a surface's points once too many are unseen for the surface to reach its share.
Neither path decides that a point is seen: shapely does, for the points left.
``tests/test_deletion_invariant.py`` checks both give the same verdicts.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["facing_front", "possible_points"]


@njit(cache=True, nogil=True)
def possible_points(segs, vsegs, ox, oy, beyond_m, samples, need, margin_m, margin_rad):
    """``(N, samples)``: the surfaces' sample points not proven unseen (False also for the
    points of a surface left once it has more than ``samples - need`` unseen)."""
    n, m = segs.shape[0], vsegs.shape[0]
    out = np.zeros((n, samples), np.bool_)
    start = np.empty(m)
    span = np.empty(m)
    far = np.empty(m)
    reach = 0.0
    fans = True
    for j in range(m):
        ax, ay = vsegs[j, 0] - ox, vsegs[j, 1] - oy
        bx, by = vsegs[j, 2] - ox, vsegs[j, 3] - oy
        ra, rb = math.sqrt(ax * ax + ay * ay), math.sqrt(bx * bx + by * by)
        reach = max(reach, ra, rb)
        s = math.atan2(ax * by - ay * bx, ax * bx + ay * by)
        st = math.atan2(ay, ax)
        if s < 0.0:
            st += s
            s = -s
        start[j], span[j], far[j] = st, s, max(ra, rb)
        if ra < margin_m or rb < margin_m or s > math.pi - margin_rad:
            fans = False
    turn = 2.0 * math.pi
    for i in range(n):
        x0, y0 = segs[i, 0], segs[i, 1]
        dx, dy = segs[i, 2] - x0, segs[i, 3] - y0
        unseen = 0
        for k in range(samples):
            f = (k + 0.5) / samples
            vx, vy = x0 + f * dx - ox, y0 + f * dy - oy
            dist = math.sqrt(vx * vx + vy * vy)
            short = dist - beyond_m
            ok = short <= reach + margin_m
            if ok and fans and dist > margin_m:
                bearing = math.atan2(vy / dist, vx / dist)
                inside = False
                crossing = math.inf
                behind = False
                ux, uy = vx / dist, vy / dist
                for j in range(m):
                    off = (bearing - start[j] + margin_rad) % turn
                    if off <= span[j] + 2.0 * margin_rad:
                        inside = True
                        if off >= 2.0 * margin_rad and off <= span[j]:
                            crossing = min(crossing, far[j])
                            # The sight line crosses this surface (its bearing is well
                            # inside the fan): where, along the line from the viewpoint.
                            ex, ey = vsegs[j, 2] - vsegs[j, 0], vsegs[j, 3] - vsegs[j, 1]
                            ax, ay = vsegs[j, 0] - ox, vsegs[j, 1] - oy
                            across = ux * ey - uy * ex
                            if across != 0.0 and (ax * ey - ay * ex) / across < short - margin_m:
                                behind = True
                if not inside or behind or short > crossing + margin_m:
                    ok = False
            out[i, k] = ok
            if not ok:
                unseen += 1
                if unseen > samples - need:
                    break
    return out


@njit(cache=True, nogil=True)
def facing_front(segs, ox, oy, c, s, test, front):
    """``(N,)``: the surfaces on the facing side (``test`` 0: any endpoint in front of the
    robot, 1: both, 2: their mean) and, with ``front``, seen from their front (the robot on
    the left of the directed surface): ``facing_mask`` and the seen-side test of the numpy
    path, in the same float operations."""
    n = segs.shape[0]
    out = np.zeros(n, np.bool_)
    for i in range(n):
        x0, y0, x1, y1 = segs[i, 0], segs[i, 1], segs[i, 2], segs[i, 3]
        fwd0 = c * (x0 - ox) + s * (y0 - oy)
        fwd1 = c * (x1 - ox) + s * (y1 - oy)
        if test == 0:
            ok = fwd0 > 0.0 or fwd1 > 0.0
        elif test == 1:
            ok = fwd0 > 0.0 and fwd1 > 0.0
        else:
            ok = (fwd0 + fwd1) > 0.0
        if ok and front:
            ok = (x1 - x0) * (oy - y0) - (y1 - y0) * (ox - x0) > 0.0
        out[i] = ok
    return out
