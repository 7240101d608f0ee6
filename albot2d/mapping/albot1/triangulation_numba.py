"""The optional compiled triangulation for a few tracked surfaces (numba):
``triangulate_kernel``, ``triangulation.triangulate``'s array path in one call.

Importing this module needs numba (a default dependency; without it ``triangulate`` runs
its numpy path for every size). For fewer than eight surfaces the array path's cost is
numpy's per-call overhead (a few dozen small-array operations per view); this kernel
repeats its float operations in its order. Its only transcendental that numba would
compute differently from numpy on some CPUs is ``arctan2`` (numpy's vectorised one
differs from libm's in the last bit), so the caller passes the directions' differences
computed by numpy; numba's ``cos``, ``sin`` and ``hypot`` are numpy's, and its float ``%``
is Python's. ``tests/test_triangulation_small.py`` holds the two paths equal bit for bit.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["triangulate_kernel"]

_TWO_PI = 2.0 * np.pi


@njit(cache=True, nogil=True)
def _wrap(a):  # type: ignore[no-untyped-def]
    return (a + np.pi) % _TWO_PI - np.pi


@njit(cache=True, nogil=True)
def _fit_weight(segs, beams, i):  # type: ignore[no-untyped-def]
    """max(n · L², 1e-12) with n the surface's beams (1 without)."""
    length = np.hypot(segs[i, 2] - segs[i, 0], segs[i, 3] - segs[i, 1])
    b0, b1 = beams[i, 0], beams[i, 1]
    n = float(b1 - b0 + 1) if b0 >= 0 else 1.0
    return max(n * (length * length), 1e-12)


@njit(cache=True, nogil=True)
def triangulate_kernel(  # type: ignore[no-untyped-def]
    ang_l, ls, cs, loc_ok, cur_ok, lbeams, cbeams, pix, piy, pitheta,
    near_gate_m, turn_gate_rad, consensus_rad, use_outlier_heuristic,
):  # fmt: skip
    """``(found, x, y, heading)``; ``ang_l``: numpy's arctan2 direction of each local
    surface minus its current one's; the gates already scaled by the steps."""
    n = ls.shape[0]
    dtheta = np.empty(n)
    flipped = np.zeros(n, np.bool_)
    for i in range(n):
        d = _wrap(ang_l[i])
        if abs(_wrap(d - pitheta)) > np.pi / 2:
            flipped[i] = True
            d = _wrap(d + np.pi)
        dtheta[i] = d
    idx = np.empty(n, np.int64)
    ends = np.empty(n, np.int64)
    m = 0
    for i in range(n):
        l0, l1 = loc_ok[i, 0], loc_ok[i, 1]
        if flipped[i]:
            l0, l1 = l1, l0
        u0 = l0 and cur_ok[i, 0]
        u1 = l1 and cur_ok[i, 1]
        if u0 and u1:
            d0 = np.hypot(cs[i, 0], cs[i, 1])
            d1 = np.hypot(cs[i, 2], cs[i, 3])
            ends[m] = 0 if d0 <= d1 else 1  # argmin: the first of equals
        elif u0 or u1:
            ends[m] = 0 if u0 else 1
        else:
            continue
        idx[m] = i
        m += 1
    if m == 0:
        return False, 0.0, 0.0, 0.0
    th = np.empty(m)
    xs = np.empty(m)
    ys = np.empty(m)
    pl = np.empty((m, 2))
    pc = np.empty((m, 2))
    keep = np.empty(m, np.int64)
    kept_n = 0
    for j in range(m):
        i, e = idx[j], ends[j]
        t = dtheta[i]
        c, s = np.cos(t), np.sin(t)
        le = 1 - e if flipped[i] else e  # a flipped match pairs the other local end
        pl[j, 0], pl[j, 1] = ls[i, 2 * le], ls[i, 2 * le + 1]
        pc[j, 0], pc[j, 1] = cs[i, 2 * e], cs[i, 2 * e + 1]
        th[j] = t
        xs[j] = pl[j, 0] - (c * pc[j, 0] - s * pc[j, 1])
        ys[j] = pl[j, 1] - (s * pc[j, 0] + c * pc[j, 1])
        # The gate against path integration.
        near = np.hypot(xs[j] - pix, ys[j] - piy)
        if near <= near_gate_m and abs(_wrap(t - pitheta)) <= turn_gate_rad:
            keep[kept_n] = j
            kept_n += 1
    if kept_n == 0:
        return False, 0.0, 0.0, 0.0
    keep = keep[:kept_n]
    th, xs, ys, pl, pc = th[keep], xs[keep], ys[keep], pl[keep], pc[keep]
    m = kept_n
    kept = np.arange(m)
    if use_outlier_heuristic and m > 2:
        sx = 0.0
        sy = 0.0
        for j in range(m):
            sx += xs[j]
            sy += ys[j]
        mx, my = sx / m, sy / m
        d = np.empty(m)
        ss = 0.0
        for j in range(m):
            d[j] = np.hypot(xs[j] - mx, ys[j] - my)
            ss += d[j] * d[j]
        sigma = np.sqrt(ss / m)
        inside = d <= sigma
        kept = np.flatnonzero(inside) if inside.any() else np.flatnonzero(d == d.min())
    best = kept[0]
    low = np.inf
    for j in kept:
        dp = np.hypot(xs[j] - pix, ys[j] - piy)
        if dp < low:  # argmin: the first of equals
            low = dp
            best = j
    # heading="weighted": every tracked surface's direction (the PI gate, consensus).
    chosen = th[best]
    num = 0.0
    den = 0.0
    dev = np.empty(n)
    w = np.empty(n)
    n_ok = 0
    for i in range(n):
        if abs(_wrap(dtheta[i] - pitheta)) <= turn_gate_rad:
            a = _fit_weight(ls, lbeams, i)
            b = _fit_weight(cs, cbeams, i)
            dev[n_ok] = _wrap(dtheta[i] - chosen)
            w[n_ok] = 1.0 / (1.0 / a + 1.0 / b)
            n_ok += 1
    offset = 0.0
    if n_ok:
        for j in range(n_ok):
            num += dev[j] * w[j]
            den += w[j]
        offset = num / den
        num2 = 0.0
        den2 = 0.0
        agree = 0
        for j in range(n_ok):
            if abs(dev[j] - offset) <= consensus_rad:
                num2 += dev[j] * w[j]
                den2 += w[j]
                agree += 1
        if agree:
            offset = num2 / den2
    heading = _wrap(chosen + offset)
    c, s = np.cos(heading), np.sin(heading)
    x = pl[best, 0] - (c * pc[best, 0] - s * pc[best, 1])
    y = pl[best, 1] - (s * pc[best, 0] + c * pc[best, 1])
    return True, x, y, heading
