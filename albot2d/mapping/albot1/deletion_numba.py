"""The optional compiled sight-line test of the deletion rule (numba): ``visible_share_kernel``,
and the facing / seen-side tests in one pass (``facing_seen_kernel``).

Importing this module needs numba (a default dependency);
``albot2d.mapping.albot1.deletion.visible_share`` loads it on first use and keeps its numpy path
otherwise. An update tests a few dozen sample points against a dozen view surfaces, so the
numpy path's cost is its ~30 array calls and ``(K, M)`` temporaries, not arithmetic.

The kernel repeats the numpy path's float operations in the same order (sample points,
the ray/surface crossing parameters ``t`` and ``u``, the nearest crossing, the
``beyond_m`` test, count / samples), so both give the same shares bit for bit;
``tests/test_deletion_numba.py`` checks that on random scenes and a real run.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["facing_seen_kernel", "visible_share_kernel"]


@njit(cache=True, nogil=True)
def visible_share_kernel(segs, vsegs, rx, ry, beyond_m, samples):
    """``(N,)`` share of each surface's ``samples`` points seen through the view surfaces."""
    n, m = segs.shape[0], vsegs.shape[0]
    out = np.zeros(n)
    ex = np.empty(m)
    ey = np.empty(m)
    wx = np.empty(m)
    wy = np.empty(m)
    for j in range(m):
        ex[j] = vsegs[j, 2] - vsegs[j, 0]
        ey[j] = vsegs[j, 3] - vsegs[j, 1]
        wx[j] = vsegs[j, 0] - rx
        wy[j] = vsegs[j, 1] - ry
    for i in range(n):
        x0, y0 = segs[i, 0], segs[i, 1]
        dx, dy = segs[i, 2] - x0, segs[i, 3] - y0
        count = 0
        for k in range(samples):
            frac = (k + 0.5) / samples
            vx = (x0 + frac * dx) - rx
            vy = (y0 + frac * dy) - ry
            length = np.hypot(vx, vy)
            nearest = np.inf
            for j in range(m):
                den = vx * ey[j] - vy * ex[j]
                if not abs(den) > 1e-12:
                    continue
                t = (wx[j] * ey[j] - wy[j] * ex[j]) / den
                u = (wx[j] * vy - wy[j] * vx) / den
                if u >= 0.0 and u <= 1.0 and t > 0.0 and t < nearest:
                    nearest = t
            if np.isfinite(nearest) and (1.0 - nearest) * length <= beyond_m:
                count += 1
        out[i] = count / samples
    return out


# -- the touching test without building P (speed only; see ``deletion.touching_prefilter``) --
OUT, IN, UNSURE = 0, 1, 2


@njit(cache=True, nogil=True, inline="always")
def _offset_to_seg(px, py, ax, ay, bx, by):
    """The vector from the point of segment ab nearest to p, to p."""
    dx, dy = bx - ax, by - ay
    den = dx * dx + dy * dy
    t = 0.0
    if den > 0.0:
        t = min(max(((px - ax) * dx + (py - ay) * dy) / den, 0.0), 1.0)
    return px - (ax + t * dx), py - (ay + t * dy)


@njit(cache=True, nogil=True, inline="always")
def _point_seg_dist(px, py, ax, ay, bx, by):
    ex, ey = _offset_to_seg(px, py, ax, ay, bx, by)
    return np.hypot(ex, ey)


@njit(cache=True, nogil=True, inline="always")
def _point_seg_dist2(px, py, ax, ay, bx, by):
    ex, ey = _offset_to_seg(px, py, ax, ay, bx, by)
    return ex * ex + ey * ey


@njit(cache=True, nogil=True, inline="always")
def _orient(ax, ay, bx, by, cx, cy):
    return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)


@njit(cache=True, nogil=True, inline="always")
def _cross_properly(ax, ay, bx, by, cx, cy, dx, dy):
    """Segments ab and cd cross at a point interior to both (strict orientation signs)."""
    o1 = _orient(ax, ay, bx, by, cx, cy)
    o2 = _orient(ax, ay, bx, by, dx, dy)
    o3 = _orient(cx, cy, dx, dy, ax, ay)
    o4 = _orient(cx, cy, dx, dy, bx, by)
    return ((o1 > 0.0 and o2 < 0.0) or (o1 < 0.0 and o2 > 0.0)) and (
        (o3 > 0.0 and o4 < 0.0) or (o3 < 0.0 and o4 > 0.0)
    )


@njit(cache=True, nogil=True)
def _seg_seg_dist(ax, ay, bx, by, cx, cy, dx, dy):
    if _cross_properly(ax, ay, bx, by, cx, cy, dx, dy):
        return 0.0
    return min(
        min(_point_seg_dist(ax, ay, cx, cy, dx, dy), _point_seg_dist(bx, by, cx, cy, dx, dy)),
        min(_point_seg_dist(cx, cy, ax, ay, bx, by), _point_seg_dist(dx, dy, ax, ay, bx, by)),
    )


@njit(cache=True, nogil=True)
def _inside(px, py, ring):
    """Crossing-number point-in-polygon test (the ring is simple: any rule agrees)."""
    n = ring.shape[0]
    inside = False
    j = n - 1
    for i in range(n):
        xi, yi, xj, yj = ring[i, 0], ring[i, 1], ring[j, 0], ring[j, 1]
        if (yi > py) != (yj > py) and px < (xj - xi) * (py - yi) / (yj - yi) + xi:
            inside = not inside
        j = i
    return inside


@njit(cache=True, nogil=True)
def _near_polygon(ax, ay, bx, by, ring, lim):
    """Whether segment ab comes within ``lim`` of the simple polygon ``ring`` (inside
    counts); edges whose box is ``lim`` away from the segment's are skipped."""
    if _inside(ax, ay, ring) or _inside(bx, by, ring):
        return True
    sx0, sx1 = min(ax, bx), max(ax, bx)
    sy0, sy1 = min(ay, by), max(ay, by)
    lim2 = lim * lim
    n = ring.shape[0]
    for i in range(n):
        j = (i + 1) % n
        cx, cy, dx, dy = ring[i, 0], ring[i, 1], ring[j, 0], ring[j, 1]
        if (min(cx, dx) - sx1 >= lim or sx0 - max(cx, dx) >= lim
                or min(cy, dy) - sy1 >= lim or sy0 - max(cy, dy) >= lim):  # fmt: skip
            continue
        if _cross_properly(ax, ay, bx, by, cx, cy, dx, dy):
            return True
        if (_point_seg_dist2(ax, ay, cx, cy, dx, dy) < lim2
                or _point_seg_dist2(bx, by, cx, cy, dx, dy) < lim2
                or _point_seg_dist2(cx, cy, ax, ay, bx, by) < lim2
                or _point_seg_dist2(dx, dy, ax, ay, bx, by) < lim2):  # fmt: skip
            return True
    return False


@njit(cache=True, nogil=True)
def quick_ring(segs, rx, ry, eps):
    """The view polygon's vertices (the viewpoint, then the surfaces' endpoints in order,
    a vertex repeated where surfaces meet dropped: the same polygon), or an empty array
    when that polygon is not clearly simple (``ring_is_clearly_simple``)."""
    n = segs.shape[0]
    ring = np.empty((2 * n + 1, 2))
    ring[0, 0], ring[0, 1] = rx, ry
    m = 1
    for i in range(n):
        for k in range(2):
            x, y = segs[i, 2 * k], segs[i, 2 * k + 1]
            if x != ring[m - 1, 0] or y != ring[m - 1, 1]:
                ring[m, 0], ring[m, 1] = x, y
                m += 1
    if m > 1 and ring[m - 1, 0] == rx and ring[m - 1, 1] == ry:
        m -= 1
    ring = ring[:m].copy()
    if not ring_is_clearly_simple(ring, eps):
        return np.empty((0, 2))
    return ring


@njit(cache=True, nogil=True)
def ring_is_clearly_simple(ring, eps):
    """The closed polygon through ``ring`` (``(n, 2)``, first vertex not repeated) is simple
    with room to spare: every edge longer than ``eps``, non-adjacent edges farther apart
    than ``eps``, adjacent ones not folding back onto each other. False means unsure."""
    n = ring.shape[0]
    if n < 3:
        return False
    for i in range(n):
        j = (i + 1) % n
        if np.hypot(ring[j, 0] - ring[i, 0], ring[j, 1] - ring[i, 1]) <= eps:
            return False
    for i in range(n):
        i1 = (i + 1) % n
        i2 = (i + 2) % n
        # adjacent edges i and i+1 share vertex i+1: neither far end may lie on the other
        if _point_seg_dist(ring[i2, 0], ring[i2, 1], ring[i, 0], ring[i, 1],
                           ring[i1, 0], ring[i1, 1]) <= eps:  # fmt: skip
            return False
        if _point_seg_dist(ring[i, 0], ring[i, 1], ring[i1, 0], ring[i1, 1],
                           ring[i2, 0], ring[i2, 1]) <= eps:  # fmt: skip
            return False
        for k in range(i + 2, n):
            if i == 0 and k == n - 1:
                continue  # adjacent through the closing vertex
            k1 = (k + 1) % n
            d = _seg_seg_dist(ring[i, 0], ring[i, 1], ring[i1, 0], ring[i1, 1],
                              ring[k, 0], ring[k, 1], ring[k1, 0], ring[k1, 1])  # fmt: skip
            if d <= eps:
                return False
    return True


@njit(cache=True, nogil=True)
def classify_touching(segs, ring, rx, ry, c, s, out_m, in_m, side_m):
    """Per surface: ``OUT`` (``out_m`` or farther from the polygon, or wholly more than
    ``side_m`` behind the robot's lateral axis), ``IN`` (some part at least ``side_m`` in
    front of the axis lies within ``in_m`` of the polygon), else ``UNSURE``."""
    n = segs.shape[0]
    out = np.empty(n, np.int8)
    rx0, ry0 = ring[:, 0].min() - out_m, ring[:, 1].min() - out_m
    rx1, ry1 = ring[:, 0].max() + out_m, ring[:, 1].max() + out_m
    for i in range(n):
        ax, ay, bx, by = segs[i, 0], segs[i, 1], segs[i, 2], segs[i, 3]
        if max(ax, bx) <= rx0 or min(ax, bx) >= rx1 or max(ay, by) <= ry0 or min(ay, by) >= ry1:
            out[i] = OUT
            continue
        fa = c * (ax - rx) + s * (ay - ry)
        fb = c * (bx - rx) + s * (by - ry)
        if (fa < -side_m and fb < -side_m) or not _near_polygon(ax, ay, bx, by, ring, out_m):
            out[i] = OUT
            continue
        out[i] = UNSURE
        if fa < side_m and fb < side_m:
            continue
        if fa < side_m:  # keep the part in front of the axis (+ side_m)
            t = (side_m - fa) / (fb - fa)
            ax, ay = ax + t * (bx - ax), ay + t * (by - ay)
        elif fb < side_m:
            t = (side_m - fb) / (fa - fb)
            bx, by = bx + t * (ax - bx), by + t * (ay - by)
        if in_m > 0.0 and _near_polygon(ax, ay, bx, by, ring, in_m):
            out[i] = IN
    return out


@njit(cache=True, nogil=True)
def facing_seen_kernel(segs, rx, ry, c, s, test, front):
    """``facing_mask`` (``test``: 0 both endpoints, 1 midpoint, 2 any endpoint) and, when
    ``front``, ``seen_side_mask``, in one pass with their float operations."""
    n = segs.shape[0]
    out = np.empty(n, np.bool_)
    for i in range(n):
        f0 = c * (segs[i, 0] - rx) + s * (segs[i, 1] - ry)
        f1 = c * (segs[i, 2] - rx) + s * (segs[i, 3] - ry)
        if test == 0:
            ok = f0 > 0.0 and f1 > 0.0
        elif test == 1:
            ok = (f0 + f1) > 0.0
        else:
            ok = f0 > 0.0 or f1 > 0.0
        if ok and front:
            ex = segs[i, 2] - segs[i, 0]
            ey = segs[i, 3] - segs[i, 1]
            ok = ex * (ry - segs[i, 1]) - ey * (rx - segs[i, 0]) > 0.0
        out[i] = ok
    return out
