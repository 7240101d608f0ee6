"""Shortest paths on a grid: ``nearest_goal_path``, ``dilate``, ``simplify_path``.

``nearest_goal_path`` runs Dijkstra over an 8-connected grid of per-cell costs (``inf``:
impassable; a diagonal step costs √2 × the mean of its two cells, and never cuts the
corner of an impassable cell) from one or more seed cells, stopping at the first goal cell
it settles: the nearest goal by path cost and the path to it. The search is one compiled
call (``grid_search_numba``, the same function compiled) unless the compiled kernels are off
(``albot2d.compiled``), when the same Python function runs as it is (same path, slower).

``dilate`` grows a mask by a disc (vectorised: one shifted OR per offset in the disc);
``simplify_path`` drops the cells a straight line over passable cells can skip (greedy:
from each kept cell, a far later cell in sight, found by backing off from the last).
"""

from __future__ import annotations

import heapq
import math

import numpy as np
from numpy.typing import NDArray

from albot2d.compiled import compiled_kernel

__all__ = ["dilate", "nearest_goal_path", "segment_clear", "simplify_path"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

_SQRT2 = math.sqrt(2.0)


def dijkstra_to_goal(
    cost: FloatArray, goal: BoolArray, seeds: IntArray, seed_dist: FloatArray, nx: int
) -> tuple[int, IntArray, FloatArray]:
    """Dijkstra over flat ``cost`` (row-major, ``nx`` columns) from ``seeds`` (at
    ``seed_dist``) to the first settled ``goal`` cell; returns ``(goal index or -1,
    parent, dist)``. Plain Python that numba also compiles (keep it to numba's subset)."""
    n = cost.size
    ny = n // nx
    dist = np.full(n, np.inf)
    parent = np.full(n, -1, dtype=np.int64)
    done = np.zeros(n, dtype=np.bool_)
    heap = [(0.0, np.int64(0))]
    heap.pop()
    for k in range(seeds.size):
        s = seeds[k]
        if seed_dist[k] < dist[s]:
            dist[s] = seed_dist[k]
            heapq.heappush(heap, (seed_dist[k], np.int64(s)))
    while len(heap) > 0:
        d, i = heapq.heappop(heap)
        if done[i]:
            continue
        done[i] = True
        if goal[i]:
            return int(i), parent, dist
        iy = i // nx
        ix = i - iy * nx
        ci = cost[i]
        for dy in range(-1, 2):
            y = iy + dy
            if y < 0 or y >= ny:
                continue
            for dx in range(-1, 2):
                if dx == 0 and dy == 0:
                    continue
                x = ix + dx
                if x < 0 or x >= nx:
                    continue
                j = y * nx + x
                cj = cost[j]
                if done[j] or not cj < np.inf:
                    continue
                if dx != 0 and dy != 0:
                    if not (cost[iy * nx + x] < np.inf and cost[y * nx + ix] < np.inf):
                        continue  # never cut an impassable cell's corner
                    step = 1.4142135623730951 * 0.5 * (ci + cj)
                else:
                    step = 0.5 * (ci + cj)
                nd = d + step
                if nd < dist[j]:
                    dist[j] = nd
                    parent[j] = i
                    heapq.heappush(heap, (nd, np.int64(j)))
    return -1, parent, dist


def nearest_goal_path(
    cost: FloatArray, goal: BoolArray, seeds: IntArray, seed_dist: FloatArray
) -> tuple[IntArray, float] | None:
    """The path ``(K, 2)`` of ``(iy, ix)`` cells from a seed to the nearest goal cell and
    its cost (in cells), or None when no goal is reachable. ``cost``/``goal`` are 2-D."""
    nx = cost.shape[1]
    kernel = compiled_kernel("albot2d.control.grid_search_numba", "dijkstra_to_goal")
    search = kernel if kernel is not None else dijkstra_to_goal
    found, parent, dist = search(
        np.ascontiguousarray(cost, dtype=np.float64).reshape(-1),
        np.ascontiguousarray(goal, dtype=np.bool_).reshape(-1),
        np.asarray(seeds, dtype=np.int64),
        np.asarray(seed_dist, dtype=np.float64),
        nx,
    )
    if found < 0:
        return None
    chain = [int(found)]
    while parent[chain[-1]] >= 0:
        chain.append(int(parent[chain[-1]]))
    flat = np.array(chain[::-1], dtype=np.int64)
    return np.column_stack([flat // nx, flat % nx]), float(dist[found])


def dilate(mask: BoolArray, radius_cells: float) -> BoolArray:
    """``mask`` grown by a disc of ``radius_cells`` (cells whose centre lies within it).

    Separable: each row offset ``dy`` of the disc is a horizontal run of half-width
    ``floor(sqrt(R² - dy²))``, so the mask is first grown horizontally once per distinct
    half-width (a running sum along rows) and those rows are then OR-ed in shifted.
    """
    k = math.floor(radius_cells)
    if k <= 0:
        return mask.copy()
    ny, nx = mask.shape
    runs = np.zeros((ny, nx + 1), dtype=np.int32)
    np.cumsum(mask, axis=1, out=runs[:, 1:])
    grown: dict[int, BoolArray] = {}
    out = np.zeros_like(mask)
    for dy in range(-k, k + 1):
        w = math.floor(math.sqrt(max(radius_cells * radius_cells - dy * dy, 0.0)))
        if w not in grown:
            lo = np.clip(np.arange(nx) - w, 0, nx)
            hi = np.clip(np.arange(nx) + w + 1, 0, nx)
            grown[w] = (runs[:, hi] - runs[:, lo]) > 0
        row = grown[w]
        out[max(dy, 0) : ny - max(-dy, 0)] |= row[max(-dy, 0) : ny - max(dy, 0)]
    return out


def segment_clear(passable: BoolArray, a: FloatArray, b: FloatArray) -> bool:
    """Whether every cell the straight line between cell coordinates ``a`` and ``b`` (iy,
    ix, in cells) passes through is passable (sampled every quarter cell)."""
    n = max(2, math.ceil(4.0 * float(np.hypot(*(b - a)))) + 1)
    t = np.linspace(0.0, 1.0, n)[:, None]
    pts = np.rint(a[None, :] + t * (b - a)[None, :]).astype(np.intp)
    return bool(passable[pts[:, 0], pts[:, 1]].all())


def simplify_path(cells: IntArray, passable: BoolArray) -> IntArray:
    """The path's cells reduced to corners: from each kept cell, the farthest later cell
    reachable in a straight line over ``passable`` cells (the first and last are kept)."""
    if len(cells) <= 2:
        return cells
    pts = cells.astype(np.float64)
    kept = [0]
    i = 0
    last = len(cells) - 1
    while i < last:
        j = last
        while j > i + 1 and not segment_clear(passable, pts[i], pts[j]):
            # back off geometrically, then linearly, so long paths stay cheap
            j = max(i + 1, j - max(1, (j - i) // 4))
        kept.append(j)
        i = j
    return cells[kept]
