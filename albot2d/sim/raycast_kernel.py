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

from albot2d.errors import InputError

__all__ = ["BeamFan", "cast_pieces"]

FloatArray = NDArray[np.float64]

_TWO_PI = 2.0 * math.pi


def _readonly(arr: np.ndarray) -> np.ndarray:
    arr.flags.writeable = False
    return arr


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
            angles=_readonly(a.copy()),
            order=order,
            mid_rad=mid,
            half_span_rad=half,
            ext_rel=_readonly(np.concatenate([centred - _TWO_PI, centred, centred + _TWO_PI])),
            ext_dir=_readonly(np.concatenate([directions, directions, directions])),
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
                    angles=_readonly(self.angles + offsets),
                    order=None,
                    mid_rad=self.mid_rad,
                    half_span_rad=widest,
                    ext_rel=_readonly(ext_rel),
                    ext_dir=_readonly(ext_dir),
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


def cast_pieces(
    table: np.ndarray,
    ox: float,
    oy: float,
    mid: float,
    heading: float,
    fan: BeamFan,
    r_max: float,
    tol: float,
) -> FloatArray:
    """The vectorised kernel: ranges of every beam of ``fan`` against the pieces ``table``.

    ``table`` is ``(3, K)`` complex: rows endpoint a, endpoint b, conj(unit normal). The
    calls are ufuncs and array methods on purpose: at a few hundred pieces a scan is
    dominated by per-call overhead, not arithmetic.
    """
    n_beams = fan.n_beams
    if table.shape[1] == 0:
        return np.full(n_beams, np.inf)
    conj_n = table[2]
    x = table[0:2].real - ox  # (2, K) endpoint coordinates relative to the origin
    y = table[0:2].imag - oy
    s = x[0] * conj_n.real - y[0] * conj_n.imag  # signed distance origin → line
    # w = 1 / (foot of the perpendicular), so a beam of world direction d meets the line at
    # 1 / Re(d * w). Turning w by the heading lets the fan's own directions stand in for d.
    turn = complex(math.cos(heading), math.sin(heading))
    edge_on = None
    if abs(s).min() <= tol:
        inside, w, edge_on = _degenerate(x, y, s, conj_n, tol)
        if inside:
            return np.zeros(n_beams)
        w *= turn
    else:
        w = (conj_n * turn) * (1.0 / s)
    ang = np.arctan2(y, x)  # endpoint directions...
    ang -= mid  # ...relative to the fan centre, in (-2 pi, 2 pi)
    # Beams from each endpoint's direction on; ext_rel repeats the fan at ±2 pi, so moving
    # a direction by 2 pi moves its index by exactly n_beams. Intervals are half-open,
    # [first, last): of two walls meeting at a vertex, exactly one owns a ray through it.
    idx = fan.ext_rel.searchsorted(ang)
    if edge_on is not None:  # a point-like target: close its interval to catch the ray
        idx[1, edge_on] = fan.ext_rel.searchsorted(ang[1, edge_on], side="right")
    first = np.minimum(idx[0], idx[1])
    span = abs(idx[1] - idx[0])
    # A piece subtends less than pi; a larger gap means it spans the ±pi seam, and its
    # beams run from the larger index to the smaller one one turn later.
    wrap = abs(ang[1] - ang[0]) > math.pi
    first += wrap * span
    counts = span + wrap * (n_beams - 2 * span)
    cum = counts.cumsum()
    n_pairs = int(cum[-1])
    # 1 / range per beam; no pair leaves 2 * r_max, beyond range like any hit past r_max.
    den = np.empty(3 * n_beams)
    den.fill(0.5 / r_max)
    if n_pairs:
        pos = (first + counts - cum).repeat(counts)
        pos += _arange(n_pairs)
        np.maximum.at(den, pos, (fan.ext_dir[pos] * w.repeat(counts)).real)
    ranges = 1.0 / den.reshape(3, n_beams).max(axis=0)
    ranges[ranges > r_max] = np.inf
    if fan.order is not None:
        unsorted = np.empty_like(ranges)
        unsorted[fan.order] = ranges
        return unsorted
    return ranges


def _degenerate(
    x: FloatArray, y: FloatArray, s: FloatArray, conj_n: np.ndarray, tol: float
) -> tuple[bool, np.ndarray, NDArray[np.bool_]]:
    """Pieces whose line passes within ``tol`` of the origin; returns (inside, w, edge_on).

    ``inside`` when the origin is on a piece. A piece seen edge-on collapses (in place, in
    ``x`` and ``y``) to its near endpoint, hit only by the ray that points straight at it.
    """
    deg = abs(s) <= tol
    za = x[0, deg] + 1j * y[0, deg]
    zb = x[1, deg] + 1j * y[1, deg]
    e = zb - za
    length = np.abs(e)
    t = -(za * np.conj(e)).real / (length * length)
    slack = tol / length
    if ((t >= -slack) & (t <= 1.0 + slack)).any():
        return True, conj_n, deg
    near = np.where(np.abs(za) <= np.abs(zb), za, zb)
    x[:, deg] = near.real
    y[:, deg] = near.imag
    w = conj_n / np.where(deg, 1.0, s)
    w[deg] = 1.0 / near
    return False, w, deg
