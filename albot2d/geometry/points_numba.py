"""The optional compiled laser-hit transform (numba): ``hits_kernel``.

Importing this module needs numba (a default dependency); ``Frame.world_hits``
loads it on first use. A scan's hits cost the numpy path (``Scan.points`` then
``transform_points``) about ten small array calls; this kernel does the two rigid
transforms in one pass with the same float operations in the same order (``x + c·u − s·v``,
``y + s·u + c·v`` per transform, from the caller's numpy ``cos``/``sin`` of the beam angles
and ``math.cos``/``math.sin`` of the headings), so both give the same points bit for bit
(``tests/test_frames.py``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["hits_kernel"]


@njit(cache=True, nogil=True)
def hits_kernel(ranges, cos_a, sin_a, valid, mx, my, mc, ms, tx, ty, tc, ts):  # type: ignore[no-untyped-def]
    """``(k, 2)`` valid beams' points: laser frame → robot frame by the mount
    ``(mx, my, mc, ms)`` → parent frame by ``(tx, ty, tc, ts)``."""
    n = 0
    for i in range(valid.shape[0]):
        if valid[i]:
            n += 1
    out = np.empty((n, 2), np.float64)
    j = 0
    for i in range(valid.shape[0]):
        if valid[i]:
            u = ranges[i] * cos_a[i]
            v = ranges[i] * sin_a[i]
            x = mx + mc * u - ms * v
            y = my + ms * u + mc * v
            out[j, 0] = tx + tc * x - ts * y
            out[j, 1] = ty + ts * x + tc * y
            j += 1
    return out
