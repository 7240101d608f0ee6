"""Exact, vectorised 2D raycasting against line segments, with a uniform-grid spatial index.

``RayCaster(segments)`` is built once per world. It cuts every segment at the boundaries of
a uniform grid, so each piece lies in exactly one cell, and stores the pieces cell by cell
(row-major), so the pieces under any axis-aligned box are one contiguous run per grid row.

A cast of ``B`` beams from one origin then costs a fixed number of numpy calls:

1. the pieces under the bounding box of the beams (the fan of rays out to ``max_range``),
   found by slicing the per-cell offsets row by row (no per-cell Python loop);
2. for each piece, the closed interval of directions it subtends from the origin; a binary
   search over the sorted beam directions turns it into the run of beams that cross it;
3. for each (beam, piece) pair in those runs the exact distance to the piece's line,
   ``s / (d · n)``, reduced per beam with ``np.maximum.at`` on its reciprocal.

Only pieces in range are touched, so a scan's cost follows the walls near the laser, not
the size of the world. Results are exact segment intersections, not grid approximations.

Numerical conventions (all tested):

- A ray through a vertex shared by two walls is never lost: direction intervals are
  half-open and both walls compare the ray against the very same computed vertex angle.
- A ray parallel to a wall never hits it, except a wall seen exactly edge-on (the origin on
  its line, within ``contact_tolerance_m``) whose near end is hit by the ray pointing at it.
- An origin within ``contact_tolerance_m`` of a wall is inside it: every range is 0.
- Zero-length segments (shorter than ``MIN_SEGMENT_LENGTH_M``) are dropped.
- No hit within ``max_range``: the range is ``inf``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from albot2d.errors import InputError
from albot2d.geometry import as_segments, point_segment_distance

__all__ = ["MIN_SEGMENT_LENGTH_M", "BeamFan", "RayCaster", "cast_brute_force"]

FloatArray = NDArray[np.float64]

_TWO_PI = 2.0 * math.pi
_HALF_PI = 0.5 * math.pi
#: Aim for about this many pieces per grid cell when the cell size is chosen automatically.
_AUTO_PIECES_PER_CELL = 8.0
#: Never allocate more grid cells than this many per segment (sparse, sprawling worlds).
_MAX_CELLS_PER_SEGMENT = 16
#: Segments shorter than this are numerically zero-length and dropped.
MIN_SEGMENT_LENGTH_M = 1e-12
#: Cuts closer than this to an end or to the previous cut are skipped, so no piece is a
#: sliver; a piece then pokes at most this far into a neighbouring cell (queries pad more).
_MIN_PIECE_M = 1e-10
#: Up to this many grid rows, a query copies row runs by slicing instead of fancy indexing.
_MAX_SLICED_ROWS = 64


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


def _clean_segments(segments: ArrayLike, what: str = "segments") -> FloatArray:
    try:
        segs = as_segments(segments)
    except ValueError as exc:
        raise InputError(f"{what}: {exc}") from None
    if not np.isfinite(segs).all():
        bad = int(np.flatnonzero(~np.isfinite(segs).all(axis=1))[0])
        raise InputError(f"{what}[{bad}] is not finite: {segs[bad].tolist()}")
    keep = np.hypot(segs[:, 2] - segs[:, 0], segs[:, 3] - segs[:, 1]) >= MIN_SEGMENT_LENGTH_M
    return np.ascontiguousarray(segs[keep])


def _piece_table(segs: FloatArray) -> NDArray[np.complex128]:
    """``(3, N)`` complex rows: endpoints a, b and the conjugated unit normal.

    Field-major so a query's pieces are three contiguous rows. With n = -i e / |e|,
    Re(z * conj(n)) is the dot product z · n.
    """
    a = segs[:, 0] + 1j * segs[:, 1]
    b = segs[:, 2] + 1j * segs[:, 3]
    e = b - a
    conj_n = np.conj(-1j * e / np.abs(e))
    return np.ascontiguousarray(np.vstack([a, b, conj_n]))


def _split_at_grid(
    segs: FloatArray, x0: float, y0: float, cell: float
) -> tuple[FloatArray, NDArray[np.intp], NDArray[np.intp]]:
    """Cut segments where they cross grid lines: pieces ``(P, 4)`` and their cell (ix, iy).

    Original endpoints are kept bit-exact and a cut point is shared by the two pieces it
    joins, so no ray can slip between pieces.
    """
    n = len(segs)
    gx1, gy1 = (segs[:, 0] - x0) / cell, (segs[:, 1] - y0) / cell
    gx2, gy2 = (segs[:, 2] - x0) / cell, (segs[:, 3] - y0) / cell
    cuts_t = [np.zeros(n), np.ones(n)]
    cuts_id = [np.arange(n), np.arange(n)]
    for g1, g2 in ((gx1, gx2), (gy1, gy2)):
        lo, hi = np.minimum(g1, g2), np.maximum(g1, g2)
        first = np.floor(lo).astype(np.int64) + 1
        count = np.maximum(np.ceil(hi).astype(np.int64) - first, 0)
        ids = np.repeat(np.arange(n), count)
        k = first[ids] + (np.arange(len(ids)) - np.repeat(np.cumsum(count) - count, count))
        with np.errstate(invalid="ignore", divide="ignore"):
            t = (k - g1[ids]) / (g2[ids] - g1[ids])
        cuts_t.append(np.clip(t, 0.0, 1.0))
        cuts_id.append(ids)
    t_all, id_all = np.concatenate(cuts_t), np.concatenate(cuts_id)
    order = np.lexsort((t_all, id_all))
    t_all, id_all = t_all[order], id_all[order]
    # Drop interior cuts too close (in metres) to the previous point or to the segment end.
    length = np.hypot(segs[:, 2] - segs[:, 0], segs[:, 3] - segs[:, 1])[id_all]
    gap_prev = np.diff(t_all, prepend=-1.0) * length
    end_gap = (1.0 - t_all) * length
    interior = (t_all > 0.0) & (t_all < 1.0)
    skip = interior & ((gap_prev < _MIN_PIECE_M) | (end_gap < _MIN_PIECE_M))
    t_all, id_all = t_all[~skip], id_all[~skip]
    start = np.flatnonzero((id_all[:-1] == id_all[1:]) & (t_all[:-1] < t_all[1:]))
    sid, t0, t1 = id_all[start], t_all[start], t_all[start + 1]
    a, b = segs[sid, :2], segs[sid, 2:]
    p0 = np.where((t0 == 0.0)[:, None], a, a + t0[:, None] * (b - a))
    p1 = np.where((t1 == 1.0)[:, None], b, a + t1[:, None] * (b - a))
    pieces = np.hstack([p0, p1])
    mid = 0.5 * (pieces[:, :2] + pieces[:, 2:])
    ix = np.floor((mid[:, 0] - x0) / cell).astype(np.intp)
    iy = np.floor((mid[:, 1] - y0) / cell).astype(np.intp)
    return pieces, ix, iy


class RayCaster:
    """Exact raycasting against fixed segments (``(N, 4)`` ``[x1, y1, x2, y2]``, metres).

    ``cell_size_m`` is the grid pitch of the spatial index (default: chosen from the
    segment density, about eight pieces per cell). ``contact_tolerance_m`` is how close the
    origin must be to a wall's line to count as on it (see the module docstring).
    A RayCaster is immutable after construction and safe to share between threads.
    """

    def __init__(
        self,
        segments: ArrayLike,
        *,
        cell_size_m: float | None = None,
        contact_tolerance_m: float = 1e-9,
    ) -> None:
        segs = _clean_segments(segments)
        if not (math.isfinite(contact_tolerance_m) and contact_tolerance_m >= 0.0):
            raise InputError(f"contact_tolerance_m must be >= 0, got {contact_tolerance_m!r}")
        self.segments: FloatArray = _readonly(segs)
        self.contact_tolerance_m = float(contact_tolerance_m)
        if len(segs):
            xmin = float(min(segs[:, 0].min(), segs[:, 2].min()))
            ymin = float(min(segs[:, 1].min(), segs[:, 3].min()))
            xmax = float(max(segs[:, 0].max(), segs[:, 2].max()))
            ymax = float(max(segs[:, 1].max(), segs[:, 3].max()))
        else:
            xmin = ymin = 0.0
            xmax = ymax = 1.0
        width, height = max(xmax - xmin, 1e-6), max(ymax - ymin, 1e-6)
        if cell_size_m is None:
            cell = math.sqrt(_AUTO_PIECES_PER_CELL * width * height / max(len(segs), 1))
        else:
            if not (math.isfinite(cell_size_m) and cell_size_m > 0.0):
                raise InputError(f"cell_size_m must be > 0, got {cell_size_m!r}")
            cell = float(cell_size_m)
        max_cells = _MAX_CELLS_PER_SEGMENT * max(len(segs), 1) + 1024
        cell = max(cell, math.sqrt(width * height / max_cells), 1e-6 * max(width, height))
        self.cell_size_m = cell
        # One spare cell of margin on each side keeps every piece's cell index in range.
        self._x0, self._y0 = xmin - cell, ymin - cell
        self._nx = math.ceil((xmax - self._x0) / cell) + 2
        self._ny = math.ceil((ymax - self._y0) / cell) + 2
        pieces, ix, iy = _split_at_grid(segs, self._x0, self._y0, cell)
        cell_id = np.clip(iy, 0, self._ny - 1) * self._nx + np.clip(ix, 0, self._nx - 1)
        order = np.argsort(cell_id, kind="stable")
        self.n_pieces = len(pieces)
        self._table = _readonly(_piece_table(pieces[order]))  # (3, n_pieces)
        counts = np.bincount(cell_id, minlength=self._nx * self._ny)
        self._cell_start = _readonly(np.concatenate([[0], np.cumsum(counts)]).astype(np.intp))

    @property
    def n_segments(self) -> int:
        return len(self.segments)

    def pieces_in_box(self, xmin: float, ymin: float, xmax: float, ymax: float) -> np.ndarray:
        """Table columns ``(3, K)`` of every piece in a grid cell the box touches."""
        c, nx = self.cell_size_m, self._nx
        ix0 = max(math.floor((xmin - self._x0) / c), 0)
        iy0 = max(math.floor((ymin - self._y0) / c), 0)
        ix1 = min(math.floor((xmax - self._x0) / c), nx - 1)
        iy1 = min(math.floor((ymax - self._y0) / c), self._ny - 1)
        if ix1 < ix0 or iy1 < iy0:
            return self._table[:, :0]
        starts = self._cell_start[iy0 * nx + ix0 : iy1 * nx + ix0 + 1 : nx]
        ends = self._cell_start[iy0 * nx + ix1 + 1 : iy1 * nx + ix1 + 2 : nx]
        table = self._table
        if len(starts) <= _MAX_SLICED_ROWS:
            # A few contiguous copies beat building and applying a fancy index.
            runs = [table[:, a:b] for a, b in zip(starts.tolist(), ends.tolist(), strict=True)]
            return runs[0] if len(runs) == 1 else np.concatenate(runs, axis=1)
        counts = ends - starts
        cum = np.cumsum(counts)
        total = int(cum[-1])
        rows = np.arange(total) + np.repeat(starts - cum + counts, counts)
        return table[:, rows]

    def cast(
        self,
        origin: ArrayLike,
        angles: ArrayLike | BeamFan,
        max_range: float,
        *,
        heading: float = 0.0,
        extra_segments: ArrayLike | None = None,
    ) -> FloatArray:
        """Distance along each beam to the first segment hit; ``inf`` when none within range.

        ``angles`` are beam directions (radians) in the world frame, rotated by ``heading``;
        pass a prepared ``BeamFan`` to save re-sorting them on every call. ``extra_segments``
        (``(M, 4)``, world frame, e.g. moving obstacles) are hit together with the index.
        Returns ``(B,)`` float64 in the order of ``angles``.
        """
        fan = angles if isinstance(angles, BeamFan) else BeamFan.from_angles(angles)
        try:
            x, y = origin  # type: ignore[misc]
            ox, oy = float(x), float(y)
        except (TypeError, ValueError):
            raise InputError(f"ray origin must be two numbers (x, y), got {origin!r}") from None
        r_max = float(max_range)
        if not (math.isfinite(ox) and math.isfinite(oy)):
            raise InputError(f"ray origin must be finite, got ({ox}, {oy})")
        if not r_max > 0.0:
            raise InputError(f"max_range must be > 0, got {max_range!r}")
        mid = fan.mid_rad + float(heading)
        box = _fan_box(ox, oy, mid, fan.half_span_rad, r_max)
        table = self.pieces_in_box(*box)
        if extra_segments is not None:
            extra = _clean_segments(extra_segments, "extra_segments")
            if len(extra):
                table = np.concatenate([table, _piece_table(extra)], axis=1)
        return _cast_pieces(table, ox, oy, mid, heading, fan, r_max, self.contact_tolerance_m)


def _fan_box(
    ox: float, oy: float, mid: float, half: float, r: float
) -> tuple[float, float, float, float]:
    """Axis-aligned bounding box of the rays ``origin + [0, r] * e^{i a}``, a in mid ± half."""
    if half >= math.pi - 1e-12:
        return ox - r, oy - r, ox + r, oy + r
    lo, hi = mid - half, mid + half
    xs = [ox, ox + r * math.cos(lo), ox + r * math.cos(hi)]
    ys = [oy, oy + r * math.sin(lo), oy + r * math.sin(hi)]
    k = math.ceil(lo / _HALF_PI)
    while k * _HALF_PI <= hi:
        quadrant = k % 4
        if quadrant == 0:
            xs.append(ox + r)
        elif quadrant == 1:
            ys.append(oy + r)
        elif quadrant == 2:
            xs.append(ox - r)
        else:
            ys.append(oy - r)
        k += 1
    # Pad by a hair: the bounding box is also rounded, and a piece may touch the boundary.
    pad = 1e-9 * (1.0 + r + abs(ox) + abs(oy))
    return min(xs) - pad, min(ys) - pad, max(xs) + pad, max(ys) + pad


_ARANGE = np.arange(1 << 12)


def _arange(n: int) -> NDArray[np.intp]:
    """``np.arange(n)`` as a view of a cached, grow-only array (saves an allocation a scan)."""
    global _ARANGE
    if n > len(_ARANGE):
        _ARANGE = np.arange(max(n, 2 * len(_ARANGE)))
    return _ARANGE[:n]


def _cast_pieces(
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


def cast_brute_force(
    segments: ArrayLike,
    origin: ArrayLike,
    angles: ArrayLike,
    max_range: float,
    *,
    contact_tolerance_m: float = 1e-9,
) -> FloatArray:
    """Reference: every beam against every segment, textbook ray/segment intersection.

    O(B·N) time and memory; for tests and small inputs. Same conventions as ``RayCaster``:
    a segment seen exactly edge-on is hit at its near end, an origin within
    ``contact_tolerance_m`` of a segment gives all-zero ranges, ``inf`` means no hit.
    """
    segs = _clean_segments(segments)
    o = np.asarray(origin, dtype=np.float64).reshape(2)
    a = np.asarray(angles, dtype=np.float64).reshape(-1)
    if len(segs) == 0:
        return np.full(len(a), np.inf)
    if point_segment_distance(o[None, :], segs).min() <= contact_tolerance_m:
        return np.zeros(len(a))
    d = np.column_stack([np.cos(a), np.sin(a)])[:, None, :]  # (B, 1, 2)
    p, q = segs[None, :, :2] - o, segs[None, :, 2:] - o  # (1, N, 2)
    e = q - p
    cross_de = d[..., 0] * e[..., 1] - d[..., 1] * e[..., 0]
    cross_pd = p[..., 0] * d[..., 1] - p[..., 1] * d[..., 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (p[..., 0] * e[..., 1] - p[..., 1] * e[..., 0]) / cross_de
        u = cross_pd / cross_de
    hit = (cross_de != 0.0) & (t >= 0.0) & (u >= 0.0) & (u <= 1.0)
    # Collinear: the ray runs along the segment's line; it meets the segment's near end.
    tp, tq = (p * d).sum(axis=-1), (q * d).sum(axis=-1)
    along = (cross_de == 0.0) & (cross_pd == 0.0) & (np.maximum(tp, tq) >= 0.0)
    t = np.where(along, np.maximum(np.minimum(tp, tq), 0.0), t)
    t = np.where(hit | along, t, np.inf).min(axis=1, initial=np.inf)
    return np.where(t <= max_range, t, np.inf)
