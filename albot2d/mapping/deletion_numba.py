"""The optional compiled sight-line test of the deletion rule (numba): ``visible_share_kernel``.

Importing this module needs numba (``pip install 'albot2d[fast]'``);
``albot2d.mapping.deletion.visible_share`` loads it on first use and keeps its numpy path
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

__all__ = ["visible_share_kernel"]


@njit(cache=True, nogil=True)
def visible_share_kernel(segs, vsegs, rx, ry, beyond_m, samples):  # type: ignore[no-untyped-def]
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
