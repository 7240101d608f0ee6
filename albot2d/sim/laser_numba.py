"""The optional compiled laser noise model (numba): ``apply_noise``, one call per scan.

Importing this module needs numba (a default dependency); ``Laser.scan`` uses it
when numba imports. The random draws stay in numpy (``Laser.scan`` draws exactly what the
numpy path draws, in the same order), so both paths consume the same stream; this kernel
only replaces the ~25 small array operations on them, in the same float operations, so
the ranges are the same bit for bit (``tests/test_laser.py`` checks it).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["apply_noise"]


@njit(cache=True, nogil=True)
def apply_noise(
    r, hit, mixed_prob, edges, mixed_draws, sigma_m, sigma_per_m, normal,
    inv_resolution, resolution, min_range, max_range, dropout_prob, dropout_draws,
):  # fmt: skip
    """Steps 2–6 of the noise model on ``r`` (in place); returns ``(ranges, valid)``.

    ``edges`` marks the beam pairs that can mix (``Laser._mixing_edges``);
    ``mixed_draws`` is the ``(3, n - 1)`` uniform draw (happens, side, fraction) or empty
    when mixed pixels are off; ``normal`` the ``(n,)`` standard normals or empty when
    range noise is off; ``resolution`` 0 disables quantisation; ``dropout_draws`` the
    ``(n,)`` uniforms or empty when dropouts are off.
    """
    n = len(r)
    if mixed_prob > 0.0:
        orig = r.copy()
        for i in range(n - 1):
            left, right = orig[i], orig[i + 1]
            if edges[i] and mixed_draws[0, i] < mixed_prob:
                near = min(left, right)
                blended = near + mixed_draws[2, i] * (max(left, right) - near)
                r[i + 1 if mixed_draws[1, i] < 0.5 else i] = blended
    if len(normal):
        for i in range(n):
            s = sigma_per_m * r[i]
            s += sigma_m
            s *= normal[i]
            r[i] += s
    if resolution > 0.0:
        for i in range(n):
            r[i] = np.rint(r[i] * inv_resolution) * resolution
    valid = np.empty(n, np.bool_)
    ranges = np.empty(n)
    for i in range(n):
        ok = hit[i] and r[i] >= min_range and r[i] < max_range
        if dropout_prob > 0.0:
            ok = ok and dropout_draws[i] >= dropout_prob
        valid[i] = ok
        ranges[i] = r[i] if ok else max_range
    return ranges, valid
