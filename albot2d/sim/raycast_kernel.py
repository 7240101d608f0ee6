"""The raycasting kernel: ``BeamFan`` (prepared beam directions) and ``cast_pieces``.

For each piece (a segment cut to one grid cell) the kernel finds the half-open run of beams
whose directions lie between the piece's two endpoint directions, by one binary search
over the sorted beam directions; for each (beam, piece) pair in those runs it computes the
exact distance to the piece's line and keeps the nearest per beam (``np.maximum.at`` on
the reciprocal). At a few hundred pieces per scan the cost is per-call overhead, so the
kernel is a fixed, short sequence of ufuncs and array methods.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from albot2d.arrays import readonly
from albot2d.errors import InputError

__all__ = ["BeamFan", "beam_directions", "cast_pieces"]

FloatArray = NDArray[np.float64]

_TWO_PI = 2.0 * math.pi


@dataclass(frozen=True, eq=False)
class BeamFan:
    """Beam directions in the laser's own frame, prepared once for repeated casts.

    The fan is centred: ``angles - mid_rad`` lies in ``[-pi, pi]`` and is sorted, so a cast
    only rotates it by the laser's heading. Build it with ``BeamFan.from_angles``.
    """

    angles: FloatArray  # (B,) as given, radians
    order: NDArray[np.intp] | None  # sorting permutation, None when already sorted
    mid_rad: float  # centre of the fan
    half_span_rad: float  # covers every beam: |angle - mid_rad| <= half_span_rad < pi
    ext_rel: FloatArray  # (3B,) sorted centred angles - 2 pi, the same, the same + 2 pi
    ext_dir: NDArray[np.complex128]  # (3B,) unit directions e^{i angle} matching ext_rel

    @classmethod
    def from_angles(cls, angles: ArrayLike) -> BeamFan:
        a = np.asarray(angles, dtype=np.float64)
        if a.ndim != 1 or len(a) == 0:
            raise InputError(f"beam angles must be a non-empty 1-D array, got shape {a.shape}")
        if not np.isfinite(a).all():
            raise InputError("beam angles must be finite")
        rel = (a - a[0]) % _TWO_PI
        order = None
        if len(a) > 1 and not (rel[1:] >= rel[:-1]).all():
            order = np.argsort(rel, kind="stable")
            rel = rel[order]
        half = 0.5 * float(rel[-1])
        mid = float(a[0]) + half
        centred = rel - half
        sorted_angles = a if order is None else a[order]
        directions = np.exp(1j * sorted_angles)
        return cls(
            angles=readonly(a.copy(), copy=False),
            order=order,
            mid_rad=mid,
            half_span_rad=half,
            ext_rel=readonly(
                np.concatenate([centred - _TWO_PI, centred, centred + _TWO_PI]), copy=False
            ),
            ext_dir=readonly(np.concatenate([directions, directions, directions]), copy=False),
        )

    def jittered(self, offsets: FloatArray) -> BeamFan:
        """This fan with beam ``k`` turned by ``offsets[k]`` radians (e.g. angular jitter).

        Cheap while the turned beams keep their order, otherwise rebuilt from scratch.
        """
        n = self.n_beams
        if self.order is None:
            ext_rel = (self.ext_rel.reshape(3, n) + offsets).ravel()
            widest = self.half_span_rad + float(abs(offsets).max())
            if widest < math.pi and (ext_rel[1:] >= ext_rel[:-1]).all():
                ext_dir = (self.ext_dir.reshape(3, n) * np.exp(1j * offsets)).ravel()
                return BeamFan(
                    angles=readonly(self.angles + offsets, copy=False),
                    order=None,
                    mid_rad=self.mid_rad,
                    half_span_rad=widest,
                    ext_rel=readonly(ext_rel, copy=False),
                    ext_dir=readonly(ext_dir, copy=False),
                )
        return BeamFan.from_angles(self.angles + offsets)

    @property
    def n_beams(self) -> int:
        return len(self.angles)


_ARANGE = np.arange(1 << 12)


def _arange(n: int) -> NDArray[np.intp]:
    """``np.arange(n)`` as a view of a cached, grow-only array (saves an allocation a scan)."""
    global _ARANGE
    if n > len(_ARANGE):
        _ARANGE = np.arange(max(n, 2 * len(_ARANGE)))
    return _ARANGE[:n]


def beam_directions(fan: BeamFan, heading: float) -> NDArray[np.complex128]:
    """``(B,)`` world directions of the fan's beams (in sorted order) turned by ``heading``.

    Computed once per scan and shared by every pass and backend, so they all see the very
    same directions.
    """
    return fan.ext_dir[: fan.n_beams] * complex(math.cos(heading), math.sin(heading))


def _pairs(z: np.ndarray) -> FloatArray:
    """A contiguous complex array seen as ``(..., 2)`` floats ``[real, imag]`` (no copy)."""
    return z.view(np.float64).reshape(*z.shape, 2)


def cast_pieces(
    table: np.ndarray,
    ox: float,
    oy: float,
    mid: float,
    directions: NDArray[np.complex128],
    fan: BeamFan,
    r_max: float,
    tol: float,
) -> FloatArray:
    """The vectorised kernel: ranges of every beam of ``fan`` against the pieces ``table``.

    ``table`` is ``(3, K)`` complex: rows endpoint a, endpoint b, conj(unit normal);
    ``directions`` come from ``beam_directions``. The calls are ufuncs and array methods on
    purpose: at a few hundred pieces a scan is dominated by per-call overhead, not
    arithmetic. Distances use plain float products and sums, never a complex product
    (numpy may fuse those into FMAs), so the compiled kernel reproduces them bit for bit.
    """
    n_beams = fan.n_beams
    if table.shape[1] == 0:
        return np.full(n_beams, np.inf)
    conj_n = table[2]
    z = table[0:2] - complex(ox, oy)  # (2, K) endpoints relative to the origin
    s = z[0].real * conj_n.real
    s -= z[0].imag * conj_n.imag  # signed distance origin → line: Re(z * conj(n)) = z · n
    # w = conj(n) / s = 1 / (foot of the perpendicular): a beam of direction d meets the
    # line at 1 / Re(d * w).
    edge_on = None
    if abs(s).min() <= tol:
        inside, w, edge_on = _degenerate(z, s, conj_n, tol)
        if inside:
            return np.zeros(n_beams)
    else:
        w = conj_n * (1.0 / s)  # complex times real: each part one rounded product
    ang = np.arctan2(z.imag, z.real)  # endpoint directions...
    ang -= mid  # ...relative to the fan centre (mid in [-pi, pi]), in [-2 pi, 2 pi]
    # Beams from each endpoint's direction on; ext_rel repeats the fan at ±2 pi, so moving
    # a direction by 2 pi moves its index by exactly n_beams. Intervals are half-open,
    # [first, last): of two walls meeting at a vertex, exactly one owns a ray through it.
    idx = fan.ext_rel.searchsorted(ang)
    if edge_on is not None:  # a point-like target: close its interval to catch the ray
        idx[1, edge_on] = fan.ext_rel.searchsorted(ang[1, edge_on], side="right")
    lo, hi = idx.min(axis=0), idx.max(axis=0)
    span = hi - lo
    # A piece subtends less than pi; a larger gap means it spans the ±pi seam, and its
    # beams run from the larger index to the smaller one one turn later.
    wrap = abs(ang[1] - ang[0]) > math.pi
    first = np.where(wrap, hi, lo)
    counts = np.where(wrap, n_beams - span, span)
    cum = counts.cumsum()
    n_pairs = int(cum[-1])
    # 1 / range per beam; no pair leaves 2 * r_max, beyond range like any hit past r_max.
    den = np.full(3 * n_beams, 0.5 / r_max)
    if n_pairs:
        first += counts
        first -= cum
        pos = first.repeat(counts)
        pos += _arange(n_pairs)
        prod = _pairs(np.concatenate((directions, directions, directions)).take(pos))
        prod *= _pairs(w.repeat(counts))  # [Re d * Re w, Im d * Im w]
        np.maximum.at(den, pos, np.subtract(prod[:, 0], prod[:, 1]))
    ranges = den.reshape(3, n_beams).max(axis=0)
    np.divide(1.0, ranges, out=ranges)
    ranges[ranges > r_max] = np.inf
    if fan.order is not None:
        unsorted = np.empty_like(ranges)
        unsorted[fan.order] = ranges
        return unsorted
    return ranges


def _degenerate(
    z: NDArray[np.complex128], s: FloatArray, conj_n: NDArray[np.complex128], tol: float
) -> tuple[bool, NDArray[np.complex128], NDArray[np.bool_]]:
    """Pieces whose line passes within ``tol`` of the origin; returns (inside, w, edge_on).

    ``inside`` when the origin is on a piece. A piece seen edge-on collapses (in place, in
    ``z``) to its near endpoint, hit only by the ray that points straight at it. Float
    arithmetic only, in the order the compiled kernel uses.
    """
    deg = abs(s) <= tol
    ar, ai = z[0, deg].real, z[0, deg].imag
    br, bi = z[1, deg].real, z[1, deg].imag
    er, ei = br - ar, bi - ai
    length = np.hypot(er, ei)
    t = -(ar * er + ai * ei) / (length * length)
    slack = tol / length
    w = conj_n * (1.0 / np.where(deg, 1.0, s))
    if ((t >= -slack) & (t <= 1.0 + slack)).any():
        return True, w, deg
    qa, qb = ar * ar + ai * ai, br * br + bi * bi
    a_nearer = qa <= qb
    nr, ni = np.where(a_nearer, ar, br), np.where(a_nearer, ai, bi)
    q = np.where(a_nearer, qa, qb)
    z[:, deg] = nr + 1j * ni
    w.real[deg] = nr / q  # 1 / near
    w.imag[deg] = -ni / q
    return False, w, deg
