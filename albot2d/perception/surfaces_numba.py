"""The optional compiled rigid transform of segments (numba): ``transform_kernel``.

Importing this module needs numba (a default dependency); ``Surfaces.transformed``
and ``surfaces.transform_segments_fast`` load it on first use. A view's few segments cost
``geometry.transform_segments`` ~9 µs of small array calls and this kernel ~2; it repeats
the same float operations in the same order (``x + c·u − s·v``, ``y + s·u + c·v`` with the
caller's ``math.cos``/``math.sin``), so both give the same numbers bit for bit
(``tests/test_surfaces_numba.py``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["transform_kernel"]


@njit(cache=True, nogil=True)
def transform_kernel(px, py, c, s, segs):
    """``(N, 4)`` segments mapped by the pose ``(px, py)`` with heading cosine ``c``, sine
    ``s`` from its frame into the parent frame."""
    out = np.empty((segs.shape[0], 4), np.float64)
    for i in range(segs.shape[0]):
        for j in range(0, 4, 2):
            u = segs[i, j]
            v = segs[i, j + 1]
            out[i, j] = px + c * u - s * v
            out[i, j + 1] = py + s * u + c * v
    return out
