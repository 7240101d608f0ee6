"""A uniform-grid spatial index of line segments for the raycaster: ``SegmentGrid``.

Segments are cut where they cross grid lines, so each piece lies in exactly one cell, and
the pieces are stored cell by cell in row-major order: the pieces under any axis-aligned
box are one contiguous run per grid row, copied with a few slices and no per-cell loop.
Pieces are kept as a field-major ``(3, N)`` complex table (endpoint a, endpoint b,
conjugated unit normal), the layout the kernel in ``raycast_kernel`` reads fastest.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from albot2d.arrays import readonly
from albot2d.errors import InputError
from albot2d.geometry import as_segments
from albot2d.validation import check_coordinates

__all__ = ["MIN_SEGMENT_LENGTH_M", "SegmentGrid", "clean_segments", "piece_table"]

FloatArray = NDArray[np.float64]

#: Segments shorter than this are numerically zero-length and dropped.
MIN_SEGMENT_LENGTH_M = 1e-12
#: Aim for about this many pieces per grid cell when the cell size is chosen automatically.
_AUTO_PIECES_PER_CELL = 8.0
#: Never allocate more grid cells than this many per segment (sparse, sprawling worlds).
_MAX_CELLS_PER_SEGMENT = 16
#: Cuts closer than this to an end or to the previous cut are skipped, so no piece is a
#: sliver; a piece then pokes at most this far into a neighbouring cell (queries pad more).
_MIN_PIECE_M = 1e-10
#: Up to this many grid rows, a query copies row runs by slicing instead of fancy indexing.
_MAX_SLICED_ROWS = 64
#: A query returns one view of the table instead of copying its row runs when that adds at
#: most this many pieces per grid row (about the cost of copying one run).
_SPAN_SLACK_PER_ROW = 16


def clean_segments(segments: ArrayLike, what: str = "segments") -> FloatArray:
    """``segments`` as a finite float64 ``(N, 4)`` array without zero-length segments.

    Coordinates beyond ``albot2d.validation.COORDINATE_LIMIT_M`` raise ``InputError``."""
    try:
        segs = as_segments(segments)
    except ValueError as exc:
        raise InputError(f"{what}: {exc}") from None
    if not np.isfinite(segs).all():
        bad = int(np.flatnonzero(~np.isfinite(segs).all(axis=1))[0])
        raise InputError(f"{what}[{bad}] is not finite: {segs[bad].tolist()}")
    # Beyond the coordinate limit the grid's cell indices overflow; refuse, naming the row.
    check_coordinates(segs, what)
    keep = np.hypot(segs[:, 2] - segs[:, 0], segs[:, 3] - segs[:, 1]) >= MIN_SEGMENT_LENGTH_M
    return np.ascontiguousarray(segs[keep])


def piece_table(segs: FloatArray) -> NDArray[np.complex128]:
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
) -> tuple[FloatArray, NDArray[np.intp], NDArray[np.intp], NDArray[np.intp]]:
    """Cut segments where they cross grid lines: pieces ``(P, 4)``, their cell (ix, iy) and
    the index of the segment each piece was cut from.

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
    return pieces, ix, iy, sid.astype(np.intp)


class SegmentGrid:
    """Pieces of ``segments`` binned in square cells of ``cell_size_m`` (auto: ~8 per cell)."""

    def __init__(self, segments: ArrayLike, cell_size_m: float | None = None) -> None:
        segs = clean_segments(segments)
        self.segments: FloatArray = readonly(segs, copy=False)
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
        pieces, ix, iy, parent = _split_at_grid(segs, self._x0, self._y0, cell)
        cell_id = np.clip(iy, 0, self._ny - 1) * self._nx + np.clip(ix, 0, self._nx - 1)
        order = np.argsort(cell_id, kind="stable")
        self.n_pieces = len(pieces)
        self._table = readonly(piece_table(pieces[order]), copy=False)  # (3, n_pieces)
        self._piece_segment = readonly(parent[order], copy=False)
        counts = np.bincount(cell_id, minlength=self._nx * self._ny)
        starts = np.concatenate([[0], np.cumsum(counts)]).astype(np.intp)
        self._cell_start = readonly(starts, copy=False)

    @property
    def table(self) -> np.ndarray:
        """All pieces, ``(3, n_pieces)`` complex, cell by cell in row-major cell order."""
        return self._table

    @property
    def piece_segment(self) -> NDArray[np.intp]:
        """``(n_pieces,)``: the index in ``segments`` of the segment each table column is
        cut from."""
        return self._piece_segment

    def cells_near(self, x: FloatArray, y: FloatArray, eps: float) -> NDArray[np.intp]:
        """``(P, 4)`` ids of the cells the squares ``(x, y) ± eps`` touch (repeated when
        fewer than four): a piece lies in its own cell but for a sliver, so the piece
        through a point is in one of them."""
        c, nx, ny = self.cell_size_m, self._nx, self._ny
        ix = np.clip(np.floor((np.stack([x - eps, x + eps]) - self._x0) / c), 0, nx - 1)
        iy = np.clip(np.floor((np.stack([y - eps, y + eps]) - self._y0) / c), 0, ny - 1)
        ix, iy = ix.astype(np.intp), iy.astype(np.intp)
        return np.stack([iy[0] * nx + ix[0], iy[0] * nx + ix[1],
                         iy[1] * nx + ix[0], iy[1] * nx + ix[1]], axis=1)  # fmt: skip

    @property
    def cell_start(self) -> NDArray[np.intp]:
        """``(nx * ny + 1,)``: cell ``i = iy * nx + ix`` holds columns ``start[i]:start[i + 1]``."""
        return self._cell_start

    @property
    def layout(self) -> FloatArray:
        """``[x0, y0, cell_size_m, nx, ny]``: cell (ix, iy) spans x0 + ix * cell onwards."""
        return readonly([self._x0, self._y0, self.cell_size_m, self._nx, self._ny], np.float64)

    def runs(
        self, xmin: float, ymin: float, xmax: float, ymax: float
    ) -> tuple[list[int], list[int]]:
        """Per grid row under the box, the ``[start, end)`` run of its pieces in the table."""
        c, nx = self.cell_size_m, self._nx
        ix0 = max(math.floor((xmin - self._x0) / c), 0)
        iy0 = max(math.floor((ymin - self._y0) / c), 0)
        ix1 = min(math.floor((xmax - self._x0) / c), nx - 1)
        iy1 = min(math.floor((ymax - self._y0) / c), self._ny - 1)
        if ix1 < ix0 or iy1 < iy0:
            return [], []
        starts = self._cell_start[iy0 * nx + ix0 : iy1 * nx + ix0 + 1 : nx].tolist()
        ends = self._cell_start[iy0 * nx + ix1 + 1 : iy1 * nx + ix1 + 2 : nx].tolist()
        return starts, ends

    def count(self, xmin: float, ymin: float, xmax: float, ymax: float) -> int:
        """How many pieces ``pieces_in_box`` would return, without copying them."""
        starts, ends = self.runs(xmin, ymin, xmax, ymax)
        return sum(ends) - sum(starts)

    def pieces_in_box(self, xmin: float, ymin: float, xmax: float, ymax: float) -> np.ndarray:
        """Table columns ``(3, K)`` of every piece in a grid cell the box touches."""
        return self.gather(*self.runs(xmin, ymin, xmax, ymax))

    def gather(self, starts: list[int], ends: list[int]) -> np.ndarray:
        """Table columns ``(3, K)`` of the pieces in the runs ``[starts[i], ends[i])``."""
        table = self._table
        if not starts:
            return table[:, :0]
        # One view of the whole span when the pieces between the runs are few: casting
        # against them (beyond the box, they are harmless) is cheaper than copying runs.
        if ends[-1] - starts[0] <= sum(ends) - sum(starts) + _SPAN_SLACK_PER_ROW * len(starts):
            return table[:, starts[0] : ends[-1]]
        if len(starts) <= _MAX_SLICED_ROWS:
            # A few contiguous copies beat building and applying a fancy index.
            parts = [table[:, a:b] for a, b in zip(starts, ends, strict=True)]
            return parts[0] if len(parts) == 1 else np.concatenate(parts, axis=1)
        counts = np.subtract(ends, starts)
        cum = np.cumsum(counts)
        rows = np.arange(int(cum[-1])) + np.repeat(np.subtract(starts, cum) + counts, counts)
        return table[:, rows]
