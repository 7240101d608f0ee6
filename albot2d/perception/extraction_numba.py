"""The optional compiled line extraction (numba): ``extract_kernel``, one scan in one call.

Importing this module needs numba (a default dependency); ``extract_surfaces``
loads it only when that backend is selected. It runs the pipeline of
``albot2d.perception.extraction`` (breakpoints, split, drop, merge, grow, fit, occlusion,
corner refinement, uncertain jump ends) as scalar loops over the beams, so a scan costs
its work, not ~100 small numpy calls.

Every step repeats the numpy path's float operations in the same order (prefix-sum
moments, the closed-form total-least-squares fit, the same tie-breaking: the first beam
of equal candidates, merges best-first with a stable sort), so both give the same
surfaces (coordinates to 1e-12 m: LLVM may fuse a corner intersection's multiply-adds);
``tests/test_extraction_numba.py`` checks that on random and real scans.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["extract_kernel"]

# Chords shorter than this (metres) are treated as a point when locating a split
# (the same constant as the numpy path).
_MIN_CHORD_M = 1e-9


@njit(cache=True, nogil=True)
def _fit(sums, a, b):
    """Total-least-squares line of beams ``a..b``: unit normal (nx, ny) and offset c."""
    cnt = sums[b + 1, 0] - sums[a, 0]
    mx = (sums[b + 1, 1] - sums[a, 1]) / cnt
    my = (sums[b + 1, 2] - sums[a, 2]) / cnt
    sxx = (sums[b + 1, 3] - sums[a, 3]) / cnt - mx * mx
    syy = (sums[b + 1, 4] - sums[a, 4]) / cnt - my * my
    sxy = (sums[b + 1, 5] - sums[a, 5]) / cnt - mx * my
    phi = 0.5 * np.arctan2(2.0 * sxy, sxx - syy)
    nx, ny = -np.sin(phi), np.cos(phi)
    return nx, ny, nx * mx + ny * my


@njit(cache=True, nogil=True)
def _max_residual(sums, x, y, a, b):
    nx, ny, c = _fit(sums, a, b)
    worst = 0.0
    for i in range(a, b + 1):
        d = abs(nx * x[i] + ny * y[i] - c)
        if i == a or d > worst:
            worst = d
    return worst


@njit(cache=True, nogil=True)
def _farthest_from_chord(x, y, a, b):
    ax, ay = x[a], y[a]
    ex, ey = x[b] - ax, y[b] - ay
    chord = np.hypot(ex, ey)
    short = chord < _MIN_CHORD_M
    ux = 0.0 if short else ex / chord
    uy = 0.0 if short else ey / chord
    best, at = -1.0, a  # the end beams count -1, as in the numpy path
    for i in range(a + 1, b):
        px, py = x[i] - ax, y[i] - ay
        d = np.hypot(px, py) if short else abs(px * uy - py * ux)
        if d > best:
            best, at = d, i
    return at


@njit(cache=True, nogil=True)
def _split(sums, x, y, starts, ends, split_d, min_points):
    """Depth-first IEPF split of every run; pieces come out sorted by first beam."""
    n_max = 2 * len(x) + 2
    out = np.empty((n_max, 2), np.int64)
    stack = np.empty((n_max, 2), np.int64)
    m = 0
    for r in range(len(starts)):
        top = 0
        stack[0, 0], stack[0, 1] = starts[r], ends[r]
        top = 1
        while top:
            top -= 1
            a, b = stack[top, 0], stack[top, 1]
            if _max_residual(sums, x, y, a, b) <= split_d:
                out[m, 0], out[m, 1] = a, b
                m += 1
                continue
            k = _farthest_from_chord(x, y, a, b)
            if b - k + 1 >= min_points:  # right half first: the left one pops first
                stack[top, 0], stack[top, 1] = k, b
                top += 1
            if k - a + 1 >= min_points:
                stack[top, 0], stack[top, 1] = a, k
                top += 1
    return out[:m]


@njit(cache=True, nogil=True)
def _run_of(starts, a):
    return np.searchsorted(starts, a, side="right") - 1


@njit(cache=True, nogil=True)
def _merge(sums, x, y, ab, run, merge_d):
    m = len(ab)
    a = ab[:, 0].copy()
    b = ab[:, 1].copy()
    run = run.copy()
    res = np.empty(max(m, 1))
    pair = np.empty(max(m, 1), np.int64)
    taken = np.zeros(max(m, 1), np.bool_)
    while m > 1:
        n_ok = 0
        any_pair = False
        for i in range(m - 1):
            if run[i] == run[i + 1]:
                any_pair = True
                d = _max_residual(sums, x, y, a[i], b[i + 1])
                if d <= merge_d:
                    pair[n_ok], res[n_ok] = i, d
                    n_ok += 1
        if not any_pair or n_ok == 0:
            break
        order = np.argsort(res[:n_ok], kind="mergesort")
        taken[:m] = False
        first = np.zeros(m, np.bool_)
        for o in order:
            i = pair[o]
            if not (taken[i] or taken[i + 1]):
                taken[i] = taken[i + 1] = True
                first[i] = True
        k = 0
        i = 0
        while i < m:
            a[k], b[k], run[k] = a[i], b[i], run[i]
            if first[i]:
                b[k] = b[i + 1]
                i += 1
            k += 1
            i += 1
        m = k
    return a[:m].copy(), b[:m].copy()


@njit(cache=True, nogil=True)
def _fitting_steps(x, y, end, limit, step, nx, ny, c, tol):
    span = (limit - end) * step
    count = 0
    while count < span:
        i = end + step * (count + 1)
        if abs(nx * x[i] + ny * y[i] - c) > tol:
            break
        count += 1
    return count


@njit(cache=True, nogil=True)
def _grow(sums, x, y, a, b, starts, ends, split_d):
    m = len(a)
    run = _run_of(starts, a)
    nx = np.empty(m)
    ny = np.empty(m)
    c = np.empty(m)
    for i in range(m):
        nx[i], ny[i], c[i] = _fit(sums, a[i], b[i])
    same_next = np.zeros(m, np.bool_)
    for i in range(m - 1):
        same_next[i] = run[i] == run[i + 1]
    new_a = a.copy()
    new_b = b.copy()
    for i in range(m):
        limit = a[i + 1] if same_next[i] else ends[run[i]]
        new_b[i] = b[i] + _fitting_steps(x, y, b[i], limit, 1, nx[i], ny[i], c[i], split_d)
        same_prev = i > 0 and same_next[i - 1]
        limit = b[i - 1] if same_prev else starts[run[i]]
        new_a[i] = a[i] - _fitting_steps(x, y, a[i], limit, -1, nx[i], ny[i], c[i], split_d)
    clash = np.zeros(m, np.bool_)
    for i in range(m - 1):
        clash[i] = same_next[i] and new_b[i] > new_a[i + 1]
    for i in range(m - 1):
        if not clash[i]:
            continue
        j = i + 1
        det = nx[i] * ny[j] - ny[i] * nx[j]
        if abs(det) > 1e-12:
            cx = (c[i] * ny[j] - ny[i] * c[j]) / det
            cy = (nx[i] * c[j] - c[i] * nx[j]) / det
            best, k = math.inf, new_a[j]
            for t in range(new_a[j], new_b[i] + 1):
                d = np.hypot(x[t] - cx, y[t] - cy)
                if d < best:
                    best, k = d, t
        else:
            k = (new_a[j] + new_b[i]) // 2
        new_b[i], new_a[j] = k, k
    for i in range(m):
        if (new_a[i] < a[i] or new_b[i] > b[i]) and _max_residual(
            sums, x, y, new_a[i], new_b[i]
        ) > split_d:
            new_a[i], new_b[i] = a[i], b[i]
    return new_a, new_b


@njit(cache=True, nogil=True)
def _nothing(max_dphi):
    return (max_dphi, np.zeros((0, 4)), np.zeros((0, 2), np.bool_),
            np.zeros((0, 2), np.int64), np.zeros((0, 2), np.bool_))  # fmt: skip


@njit(cache=True, nogil=True)
def extract_kernel(
    ranges, angles, valid, max_range, lam, sigma_add, split_d, merge_d, min_points,
    cont_d, max_gap, corner_sin, corner_max_shift, pose_x, pose_y, pose_cos, pose_sin,
):  # fmt: skip
    """The surfaces of one scan in the laser frame (see ``extraction.extract_surfaces``).

    Returns ``(max_dphi, segs (M, 4), occluded (M, 2), ab (M, 2), uncertain (M, 2))``;
    ``max_dphi`` is the largest beam spacing (the caller rejects ``lam`` not above it,
    and the arrays are then empty). ``corner_max_shift <= 0`` disables corner refinement.
    ``segs`` are mapped by the laser pose (``pose_*``: its position, cos and sin of its
    heading) into the robot frame, in ``geometry.transform_segments``' float operations.
    """
    n = len(ranges)
    hit = np.empty(n, np.bool_)
    r = np.empty(n)
    x = np.empty(n)
    y = np.empty(n)
    for i in range(n):
        ri = ranges[i]
        h = valid[i] and np.isfinite(ri) and ri > 0.0 and ri < max_range
        hit[i] = h
        r[i] = ri if h else 0.0
    for i in range(n):
        x[i] = r[i] * np.cos(angles[i])
        y[i] = r[i] * np.sin(angles[i])
    max_dphi = 0.0
    for i in range(n - 1):
        max_dphi = max(max_dphi, abs(angles[i + 1] - angles[i]))
    if n - 1 > 0 and max_dphi >= lam:
        return _nothing(max_dphi)
    # joined[i]: beams i and i+1 are consecutive points of one run.
    joined = np.zeros(max(n - 1, 0), np.bool_)
    for i in range(n - 1):
        dphi = abs(angles[i + 1] - angles[i])
        d_max = min(r[i], r[i + 1]) * np.sin(dphi) / np.sin(lam - dphi)
        d_max += sigma_add
        gap = np.hypot(x[i + 1] - x[i], y[i + 1] - y[i])
        joined[i] = hit[i] and hit[i + 1] and gap <= d_max
    prev_joined = np.zeros(n, np.bool_)
    next_joined = np.zeros(n, np.bool_)
    prev_joined[1:] = joined
    next_joined[: n - 1] = joined
    starts_all = np.empty(n, np.int64)
    ends_all = np.empty(n, np.int64)
    n_runs = 0
    n_ends = 0
    for i in range(n):
        if hit[i] and not prev_joined[i]:
            starts_all[n_runs] = i
            n_runs += 1
        if hit[i] and not next_joined[i]:
            ends_all[n_ends] = i
            n_ends += 1
    long_run = np.zeros(n_runs, np.bool_)
    for k in range(n_runs):
        long_run[k] = ends_all[k] - starts_all[k] + 1 >= min_points
    starts = starts_all[:n_runs][long_run]
    ends = ends_all[:n_runs][long_run]
    if len(starts) == 0:
        return _nothing(max_dphi)

    sums = np.zeros((n + 1, 6))
    for i in range(n):
        xi, yi = x[i], y[i]
        sums[i + 1, 0] = sums[i, 0] + 1.0
        sums[i + 1, 1] = sums[i, 1] + xi
        sums[i + 1, 2] = sums[i, 2] + yi
        sums[i + 1, 3] = sums[i, 3] + xi * xi
        sums[i + 1, 4] = sums[i, 4] + yi * yi
        sums[i + 1, 5] = sums[i, 5] + xi * yi
    ab = _split(sums, x, y, starts, ends, split_d, min_points)
    if len(ab) == 0:
        return _nothing(max_dphi)
    run = _run_of(starts, ab[:, 0])
    a, b = _merge(sums, x, y, ab, run, merge_d)
    a, b = _grow(sums, x, y, a, b, starts, ends, split_d)

    m = len(a)
    nx = np.empty(m)
    ny = np.empty(m)
    c = np.empty(m)
    segs = np.empty((m, 4))
    for i in range(m):
        nxi, nyi, ci = _fit(sums, a[i], b[i])
        nx[i], ny[i], c[i] = nxi, nyi, ci
        d0 = nxi * x[a[i]] + nyi * y[a[i]] - ci
        d1 = nxi * x[b[i]] + nyi * y[b[i]] - ci
        segs[i, 0] = x[a[i]] - d0 * nxi
        segs[i, 1] = y[a[i]] - d0 * nyi
        segs[i, 2] = x[b[i]] - d1 * nxi
        segs[i, 3] = y[b[i]] - d1 * nyi

    occluded = np.zeros((m, 2), np.bool_)
    for i in range(m):
        for side in range(2):
            end = a[i] if side == 0 else b[i]
            step = -1 if side == 0 else 1
            inside = prev_joined[end] if side == 0 else next_joined[end]
            nb = end + step
            edge = nb < 0 or nb >= n
            nb = min(max(nb, 0), n - 1)
            hidden = edge or not hit[nb] or r[nb] < r[end]
            if cont_d > 0.0:
                off_line = abs(nx[i] * x[nb] + ny[i] * y[nb] - c[i])
                hidden = hidden or off_line <= cont_d
            occluded[i, side] = (not inside) and hidden

    if corner_max_shift > 0.0 and m >= 2:
        out = segs.copy()
        last = n - 1
        for i in range(m - 1):
            j = i + 1
            lo_beam = min(b[i], a[j])
            adjacent = b[i] >= a[j] - 1 and next_joined[lo_beam]
            det = nx[i] * ny[j] - ny[i] * nx[j]
            if not (adjacent and abs(det) >= corner_sin):
                continue
            px = (c[i] * ny[j] - ny[i] * c[j]) / det
            py = (nx[i] * c[j] - c[i] * nx[j]) / det
            shift_i = np.hypot(px - segs[i, 2], py - segs[i, 3])
            shift_j = np.hypot(px - segs[j, 0], py - segs[j, 1])
            near = shift_i <= corner_max_shift and shift_j <= corner_max_shift
            lo = angles[min(max(lo_beam - 1, 0), last)]
            hi = angles[min(max(max(b[i], a[j]) + 1, 0), last)]
            bearing = np.arctan2(py, px)
            between = (
                bearing >= lo and bearing <= hi
                and px * np.cos(bearing) + py * np.sin(bearing) > 0
            )  # fmt: skip
            if near or between:
                out[i, 2], out[i, 3] = px, py
                out[j, 0], out[j, 1] = px, py
        segs = out

    uncertain = np.zeros((m, 2), np.bool_)
    if np.isfinite(max_gap):
        for i in range(m):
            for side in range(2):
                end = a[i] if side == 0 else b[i]
                inside = prev_joined[end] if side == 0 else next_joined[end]
                nb = min(max(end + (-1 if side == 0 else 1), 0), n - 1)
                ux, uy = np.cos(angles[nb]), np.sin(angles[nb])
                denom = nx[i] * ux + ny[i] * uy
                t = c[i] / denom if abs(denom) > 1e-12 else math.inf
                if not t > 0.0:
                    t = math.inf
                gap = math.inf
                if np.isfinite(t):
                    gap = np.hypot(t * ux - segs[i, 2 * side], t * uy - segs[i, 2 * side + 1])
                uncertain[i, side] = (
                    not occluded[i, side] and not inside and gap > max_gap
                )  # fmt: skip
    for i in range(m):
        for col in (0, 2):
            px, py = segs[i, col], segs[i, col + 1]
            segs[i, col] = pose_x + pose_cos * px - pose_sin * py
            segs[i, col + 1] = pose_y + pose_sin * px + pose_cos * py
    ab_out = np.empty((m, 2), np.int64)
    ab_out[:, 0] = a
    ab_out[:, 1] = b
    return max_dphi, segs, occluded, ab_out, uncertain
