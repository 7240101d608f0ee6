"""2D pose graphs as g2o text files (``VERTEX_SE2`` / ``EDGE_SE2``).

The format g2o, GTSAM (``gtsam.readG2o(path, is3D=False)``), SE-Sync and most pose-graph
tools read: one line per vertex ``VERTEX_SE2 id x y θ`` and per edge
``EDGE_SE2 i j dx dy dθ I11 I12 I13 I22 I23 I33``, the measurement being vertex ``j``'s
pose in vertex ``i``'s frame and ``I`` the upper triangle of its 3×3 information matrix
(x, y, θ), row by row. Numbers are written with 17 significant digits, so a reader gets
the same doubles back. The file holds nothing else: GTSAM's reader stops reading edges
at the first line it does not know (a comment, g2o's ``FIX``), so the reader fixes the
gauge itself (e.g. a prior on the first vertex).
"""

from __future__ import annotations

import io

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["g2o_text"]

_UPPER = np.triu_indices(3)


def g2o_text(vertices: ArrayLike, ij: ArrayLike, measurements: ArrayLike,
             information: ArrayLike) -> str:  # fmt: skip
    """``(K, 3)`` vertex poses (ids 0..K−1), ``(E, 2)`` edge vertex ids, ``(E, 3)``
    measurements and ``(E, 3, 3)`` information matrices as a g2o file."""
    v = np.asarray(vertices, dtype=np.float64).reshape(-1, 3)
    pairs = np.asarray(ij, dtype=np.int64).reshape(-1, 2)
    z = np.asarray(measurements, dtype=np.float64).reshape(-1, 3)
    info = np.asarray(information, dtype=np.float64).reshape(-1, 3, 3)
    if not len(pairs) == len(z) == len(info):
        raise ValueError(f"g2o_text: {len(pairs)} edges, {len(z)} measurements, "
                         f"{len(info)} information matrices")  # fmt: skip
    if len(pairs) and (pairs.min() < 0 or pairs.max() >= len(v)):
        raise ValueError(f"g2o_text: an edge names a vertex outside 0..{len(v) - 1}")
    if not np.allclose(info, info.transpose(0, 2, 1), rtol=1e-12, atol=0.0):
        raise ValueError("g2o_text: information matrices must be symmetric")
    out = io.StringIO()
    rows = np.column_stack([np.arange(len(v)), v])
    np.savetxt(out, rows, fmt=["VERTEX_SE2 %d"] + ["%.17g"] * 3)
    upper = info[:, _UPPER[0], _UPPER[1]]
    edges = np.column_stack([pairs.astype(np.float64), z, upper])
    np.savetxt(out, edges, fmt=["EDGE_SE2 %d", "%d"] + ["%.17g"] * 9)
    return out.getvalue()
