"""Occupancy grids: the ``nav_msgs/OccupancyGrid`` value and segment rasterisation.

``OccupancyGrid`` holds ``int8`` cells as ROS does: −1 unknown, 0 free, 100 occupied;
``cells[row, col]`` is the cell whose lower-left corner is ``col`` cells along the grid's
x axis and ``row`` cells along its y axis from ``origin`` (the pose of the lower-left
corner of cell ``(0, 0)`` in the map frame, REP-103; row 0 is the lowest y, as in the
message's row-major ``data``).

``rasterise_segments`` marks every cell an ``(N, 4)`` segment passes through (its exact
supercover, vectorised over all segments: each segment is cut where it crosses a grid
line, and each piece lies in one cell); ``free_space`` optionally marks the cells whose
centre lies in a region (e.g. a world's free space) free where no segment passes.
``grid_for_segments`` builds a grid covering segments (and points) with a margin, its
origin on a multiple of the resolution so grids of the same resolution line up.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from albot2d.errors import InputError

__all__ = [
    "FREE",
    "OCCUPIED",
    "UNKNOWN",
    "OccupancyGrid",
    "grid_for_segments",
    "rasterise_segments",
    "supercover_cells",
]

UNKNOWN = -1
FREE = 0
OCCUPIED = 100
# Cells of a grid at most: a 2 km square at 5 cm (1.6e9 bytes) is not what anyone means.
MAX_CELLS = 400_000_000


@dataclass(frozen=True, eq=False)
class OccupancyGrid:
    """A 2D occupancy grid (see the module docstring); fields are read-only.

    - ``cells``: ``(rows, cols)`` ``int8``: −1 unknown, 0 free, 100 occupied.
    - ``resolution_m``: cell side (m).
    - ``origin_x_m`` / ``origin_y_m`` / ``origin_yaw_rad``: pose of cell (0, 0)'s lower-left
      corner in the map frame.
    """

    cells: NDArray[np.int8]
    resolution_m: float
    origin_x_m: float = 0.0
    origin_y_m: float = 0.0
    origin_yaw_rad: float = 0.0

    def __post_init__(self) -> None:
        cells = np.asarray(self.cells)
        if cells.ndim != 2 or cells.dtype != np.int8:
            raise InputError(
                f"OccupancyGrid.cells must be a 2D int8 array, got {cells.dtype} {cells.shape}"
            )
        res = float(self.resolution_m)
        if not (math.isfinite(res) and res > 0):
            raise InputError(f"OccupancyGrid.resolution_m must be positive, got {res!r}")
        for name in ("origin_x_m", "origin_y_m", "origin_yaw_rad"):
            if not math.isfinite(float(getattr(self, name))):
                raise InputError(
                    f"OccupancyGrid.{name} must be finite, got {getattr(self, name)!r}"
                )
        cells = cells.copy()
        cells.flags.writeable = False
        object.__setattr__(self, "cells", cells)
        object.__setattr__(self, "resolution_m", res)

    def __repr__(self) -> str:
        counts = self.counts()
        return (
            f"OccupancyGrid({self.width}x{self.height} cells at {self.resolution_m:g} m, "
            f"origin=({self.origin_x_m:.6g}, {self.origin_y_m:.6g}, {self.origin_yaw_rad:.6g}), "
            f"occupied={counts['occupied']}, free={counts['free']}, unknown={counts['unknown']})"
        )

    @property
    def width(self) -> int:
        """Cells along the grid's x axis (columns)."""
        return int(self.cells.shape[1])

    @property
    def height(self) -> int:
        """Cells along the grid's y axis (rows)."""
        return int(self.cells.shape[0])

    def counts(self) -> dict[str, int]:
        """How many cells are occupied, free and unknown."""
        c = self.cells
        return {
            "occupied": int(np.count_nonzero(c == OCCUPIED)),
            "free": int(np.count_nonzero(c == FREE)),
            "unknown": int(np.count_nonzero(c == UNKNOWN)),
        }

    def to_grid(self, points: ArrayLike) -> NDArray[np.float64]:
        """``(N, 2)`` map-frame points in grid units (cell (c, r) spans [c, c+1) × [r, r+1))."""
        p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        c, s = math.cos(self.origin_yaw_rad), math.sin(self.origin_yaw_rad)
        dx, dy = p[:, 0] - self.origin_x_m, p[:, 1] - self.origin_y_m
        return np.column_stack([c * dx + s * dy, -s * dx + c * dy]) / self.resolution_m

    def cell_centres(self, rows: ArrayLike, cols: ArrayLike) -> NDArray[np.float64]:
        """Map-frame ``(N, 2)`` centres of the cells ``(rows[k], cols[k])``."""
        r = np.asarray(rows, dtype=np.float64).reshape(-1)
        q = np.asarray(cols, dtype=np.float64).reshape(-1)
        u, v = (q + 0.5) * self.resolution_m, (r + 0.5) * self.resolution_m
        c, s = math.cos(self.origin_yaw_rad), math.sin(self.origin_yaw_rad)
        return np.column_stack([self.origin_x_m + c * u - s * v, self.origin_y_m + s * u + c * v])

    def occupied_centres(self) -> NDArray[np.float64]:
        """Map-frame centres of every occupied cell, ``(K, 2)``."""
        rows, cols = np.nonzero(self.cells == OCCUPIED)
        return self.cell_centres(rows, cols)

    def lookup(self, points: ArrayLike) -> NDArray[np.int8]:
        """The cell value at each ``(N, 2)`` map-frame point (−1 outside the grid)."""
        g = np.floor(self.to_grid(points)).astype(np.int64)
        inside = (g[:, 0] >= 0) & (g[:, 0] < self.width) & (g[:, 1] >= 0) & (g[:, 1] < self.height)
        out = np.full(len(g), UNKNOWN, dtype=np.int8)
        out[inside] = self.cells[g[inside, 1], g[inside, 0]]
        return out


def supercover_cells(
    segments_grid: ArrayLike,
) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.int64]]:
    """Every cell each ``(N, 4)`` segment (in grid units) passes through.

    Returns ``(segment, col, row)`` arrays, one entry per (segment, cell) piece: each
    segment is cut at its crossings of the lines x = k and y = k, and each piece of
    positive length lies in exactly one cell (the one holding its midpoint); a segment of
    zero length gives the cell of its point."""
    s = np.asarray(segments_grid, dtype=np.float64).reshape(-1, 4)
    n = len(s)
    x1, y1, x2, y2 = s.T
    pieces_t = [np.zeros(n), np.ones(n)]
    owners = [np.arange(n), np.arange(n)]
    for a, b in ((x1, x2), (y1, y2)):
        lo = np.floor(np.minimum(a, b))
        crossings = (np.ceil(np.maximum(a, b)) - 1 - lo).clip(min=0).astype(np.int64)
        # the grid lines strictly between the ends: k = floor(min)+1 .. ceil(max)-1
        total = int(crossings.sum())
        if total == 0:
            continue
        owner = np.repeat(np.arange(n), crossings)
        first = np.repeat(np.cumsum(crossings) - crossings, crossings)
        k = lo[owner] + 1 + (np.arange(total) - first)
        span = (b - a)[owner]
        pieces_t.append((k - a[owner]) / span)
        owners.append(owner)
    t = np.concatenate(pieces_t)
    owner = np.concatenate(owners)
    order = np.lexsort((t, owner))
    t, owner = t[order], owner[order]
    same = owner[1:] == owner[:-1]
    mid = 0.5 * (t[1:] + t[:-1])
    keep = same & (t[1:] > t[:-1])  # a zero-length segment keeps its one piece [0, 1]
    seg, mid = owner[1:][keep], mid[keep]
    px = x1[seg] + mid * (x2 - x1)[seg]
    py = y1[seg] + mid * (y2 - y1)[seg]
    return seg, np.floor(px).astype(np.int64), np.floor(py).astype(np.int64)


def rasterise_segments(
    grid: OccupancyGrid,
    segments: ArrayLike,
    *,
    free_space: Any = None,
) -> OccupancyGrid:
    """``grid`` with every cell the ``(N, 4)`` map-frame segments pass through occupied.

    ``free_space`` (a shapely geometry in the map frame, e.g. a world's free space): cells
    whose centre lies in it and that no segment passes through are marked free; without
    it the other cells keep their value."""
    s = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
    if not np.all(np.isfinite(s)):
        raise InputError("rasterise_segments: segments must be finite")
    cells = np.array(grid.cells)
    if free_space is not None:
        import shapely

        rows, cols = np.indices(cells.shape)
        centres = grid.cell_centres(rows.ravel(), cols.ravel())
        inside = shapely.contains_xy(free_space, centres[:, 0], centres[:, 1])
        cells.reshape(-1)[inside] = FREE
    if len(s):
        ends = grid.to_grid(s.reshape(-1, 2)).reshape(-1, 4)
        _, col, row = supercover_cells(ends)
        inside = (col >= 0) & (col < grid.width) & (row >= 0) & (row < grid.height)
        cells[row[inside], col[inside]] = OCCUPIED
    return OccupancyGrid(cells, grid.resolution_m, grid.origin_x_m, grid.origin_y_m,
                         grid.origin_yaw_rad)  # fmt: skip


def grid_for_segments(
    segments: ArrayLike,
    resolution_m: float,
    *,
    points: ArrayLike | None = None,
    margin_cells: int = 2,
    fill: int = UNKNOWN,
) -> OccupancyGrid:
    """An empty (``fill``) axis-aligned grid covering ``(N, 4)`` segments and ``(K, 2)``
    points with ``margin_cells`` to spare, its origin on a multiple of ``resolution_m``."""
    res = float(resolution_m)
    if not (math.isfinite(res) and res > 0):
        raise InputError(
            f"map resolution must be a positive number of metres, got {resolution_m!r}"
        )
    xy = np.asarray(segments, dtype=np.float64).reshape(-1, 2)
    if points is not None:
        xy = np.vstack([xy, np.asarray(points, dtype=np.float64).reshape(-1, 2)])
    xy = xy[np.all(np.isfinite(xy), axis=1)]
    if not len(xy):
        xy = np.zeros((1, 2))
    lo = np.floor(xy.min(axis=0) / res) - margin_cells
    hi = np.floor(xy.max(axis=0) / res) + 1 + margin_cells
    cols, rows = (int(v) for v in hi - lo)
    if rows * cols > MAX_CELLS:
        raise InputError(
            f"a {cols}x{rows} grid at {res:g} m is too large ({rows * cols} cells > "
            f"{MAX_CELLS}); give a coarser map resolution"
        )
    cells = np.full((rows, cols), fill, dtype=np.int8)
    return OccupancyGrid(cells, res, float(lo[0] * res), float(lo[1] * res))
