"""The compiled fan test (numba): ``knowledge.fan_cells`` as one loop over the window.

Loaded through ``albot2d.compiled`` (off with ``ALBOT2D_KERNELS=numpy``). The numpy
reference builds a dozen window-sized temporaries per scan; this kernel visits each cell
once and keeps nothing but the answer, so a step's cost and memory traffic stay with the
cells in the fan. Same arithmetic in the same order, same cells in the same (row-major)
order: ``tests/test_knowledge.py`` holds them equal.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numpy.typing import NDArray

__all__ = ["fan_cells"]

FloatArray = NDArray[np.float64]


@njit(cache=True, nogil=True)
def fan_cells(
    laser_x: float, laser_y: float, laser_theta: float, angles: FloatArray, reach: FloatArray,
    origin_x_m: float, origin_y_m: float, resolution_m: float,
    ix0: int, ix1: int, iy0: int, iy1: int, nx: int, margin_m: float,
) -> NDArray[np.intp]:  # fmt: skip
    """See ``knowledge.fan_cells`` (the reference)."""
    n_beams = angles.shape[0]
    a0 = angles[0]
    two_pi = 2.0 * math.pi
    out = np.empty((iy1 - iy0) * (ix1 - ix0), dtype=np.intp)
    k = 0
    for iy in range(iy0, iy1):
        dy = origin_y_m + (iy + 0.5) * resolution_m - laser_y
        for ix in range(ix0, ix1):
            dx = origin_x_m + (ix + 0.5) * resolution_m - laser_x
            phi = math.atan2(dy, dx) - laser_theta
            phi = (phi - a0 + math.pi) % two_pi - math.pi + a0
            # searchsorted(angles, phi, side="right") - 1: the last beam at or before phi
            lo, hi = 0, n_beams
            while lo < hi:
                mid = (lo + hi) // 2
                if angles[mid] <= phi:
                    lo = mid + 1
                else:
                    hi = mid
            j = lo - 1
            if j < 0 or j >= n_beams - 1:
                continue
            limit = min(reach[j], reach[j + 1])
            if math.hypot(dx, dy) < limit - margin_m:
                out[k] = iy * nx + ix
                k += 1
    return out[:k]
