"""The optional compiled RTSV matching (numba): ``match_kernel``, one view in one call.

Importing this module needs numba (a default dependency); ``match_surfaces``
loads it only for the settings it covers (the paper's: corresponding endpoints, no line
fallback, greedy by distance, no fitness floor). A view has a few tracked and a few
candidate surfaces, so the numpy path's cost is its ~40 small array calls, not arithmetic.

The kernel repeats the numpy path's float operations (the same undirected angle
difference, the same hypot per corresponding endpoint, the same gates) and its order (a
stable sort by distance over the pairs in row-major order is the numpy path's
``lexsort((view, tracked, distance))``), so both give the same matches;
``tests/test_tracking_numba.py`` checks that on random views and a real run.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["match_kernel"]


@njit(cache=True, nogil=True)
def match_kernel(pseg, pocc, vseg, vocc, cand, pang, vang, max_angle, max_dist):  # type: ignore[no-untyped-def]
    """Greedy one-to-one matches ``(tracked, view, distance, angle)`` sorted by tracked
    index; ``pang``/``vang`` are the segments' directed angles (numpy's arctan2)."""
    k, n = pseg.shape[0], vseg.shape[0]
    pi_ = np.empty(k * n, np.int64)
    vj_ = np.empty(k * n, np.int64)
    pd = np.empty(k * n, np.float64)
    pa = np.empty(k * n, np.float64)
    m = 0
    for i in range(k):
        for j in range(n):
            if not cand[j]:
                continue
            d = abs(pang[i] - vang[j]) % np.pi
            ang = min(d, np.pi - d)
            if not ang < max_angle:
                continue
            dist = np.inf
            for e in range(2):
                if not pocc[i, e] and not vocc[j, e]:
                    h = np.hypot(
                        pseg[i, 2 * e] - vseg[j, 2 * e], pseg[i, 2 * e + 1] - vseg[j, 2 * e + 1]
                    )
                    if h < dist:
                        dist = h
            if not dist < max_dist:
                continue
            pi_[m], vj_[m], pd[m], pa[m] = i, j, dist, ang
            m += 1
    order = np.argsort(pd[:m], kind="mergesort")
    used_p = np.zeros(k, np.bool_)
    used_v = np.zeros(n, np.bool_)
    best = np.full(k, -1, np.int64)  # chosen pair per tracked surface
    for o in order:
        i, j = pi_[o], vj_[o]
        if not (used_p[i] or used_v[j]):
            used_p[i] = True
            used_v[j] = True
            best[i] = o
    count = 0
    for i in range(k):
        if best[i] >= 0:
            count += 1
    mi = np.empty(count, np.int64)
    mj = np.empty(count, np.int64)
    md = np.empty(count, np.float64)
    ma = np.empty(count, np.float64)
    c = 0
    for i in range(k):
        o = best[i]
        if o >= 0:
            mi[c], mj[c], md[c], ma[c] = i, vj_[o], pd[o], pa[o]
            c += 1
    return mi, mj, md, ma
