"""The optional compiled grid index (numba): the kernels of ``CompiledGridIndex``.

Importing this module needs numba (a default dependency). The index keeps the
same cells as ``SegmentGridIndex`` (cell ``(floor(x / cell), floor(y / cell))`` for every
cell a segment's bounding box covers) in flat arrays: an open-addressing table of cell keys
whose entries head singly linked lists of ``(id, next)`` nodes in a pool. A query reads a
few contiguous arrays instead of a dict of lists of Python ints, whose objects lie spread
over the heap of a big map (a 100k-surface map's query cost 3× a 1k map's from cache
misses alone), and each operation is one call instead of a Python loop per cell.

Layout: ``keys``/``heads`` (table, capacity a power of two; key ``_EMPTY`` is a free slot,
head -1 an emptied cell), ``node_id``/``node_next`` (pool), ``meta`` = [slots used, free
node list head, nodes used]. ``insert_kernel`` first checks capacity and returns a negative
code (changing nothing) when the caller must grow the pool or the table.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["insert_kernel", "query_kernel", "rehash_kernel", "remove_kernel"]

_EMPTY = np.int64(-(2**63))
_MASK = np.int64(0xFFFFFFFF)


@njit(cache=True, nogil=True, inline="always")
def _key(ix, iy):
    return (np.int64(ix) << np.int64(32)) | (np.int64(iy) & _MASK)


@njit(cache=True, nogil=True, inline="always")
def _hash(key, mask):
    h = np.uint64(key) * np.uint64(0x9E3779B97F4A7C15)
    return np.int64(h >> np.uint64(17)) & mask


@njit(cache=True, nogil=True)
def _find(keys, key):
    """Slot of ``key``, or -(free slot) - 1 where it would go."""
    mask = np.int64(len(keys) - 1)
    i = _hash(key, mask)
    while True:
        k = keys[i]
        if k == key:
            return i
        if k == _EMPTY:
            return -i - 1
        i = (i + 1) & mask


@njit(cache=True, nogil=True)
def _ranges(segs, cell_m):
    n = segs.shape[0]
    out = np.empty((n, 4), np.int64)
    for i in range(n):
        x0, y0, x1, y1 = segs[i, 0], segs[i, 1], segs[i, 2], segs[i, 3]
        out[i, 0] = np.int64(np.floor(min(x0, x1) / cell_m))
        out[i, 1] = np.int64(np.floor(min(y0, y1) / cell_m))
        out[i, 2] = np.int64(np.floor(max(x0, x1) / cell_m))
        out[i, 3] = np.int64(np.floor(max(y0, y1) / cell_m))
    return out


@njit(cache=True, nogil=True)
def insert_kernel(ids, segs, cell_m, keys, heads, node_id, node_next, meta):
    """Index ``segs`` under ``ids``; returns the (id, cell) pairs added, or -1 (grow the
    node pool first) or -2 - pairs (grow the table first)."""
    r = _ranges(segs, cell_m)
    pairs = 0
    for i in range(len(ids)):
        pairs += (r[i, 2] - r[i, 0] + 1) * (r[i, 3] - r[i, 1] + 1)
    free_nodes = len(node_id) - meta[2]
    f = meta[1]
    while f >= 0 and free_nodes < pairs:
        free_nodes += 1
        f = node_next[f]
    if free_nodes < pairs:
        return -1
    if 2 * (meta[0] + pairs) > len(keys):
        return -2 - pairs
    for i in range(len(ids)):
        for ix in range(r[i, 0], r[i, 2] + 1):
            for iy in range(r[i, 1], r[i, 3] + 1):
                key = _key(ix, iy)
                s = _find(keys, key)
                if s < 0:
                    s = -s - 1
                    keys[s] = key
                    heads[s] = -1
                    meta[0] += 1
                if meta[1] >= 0:
                    node = meta[1]
                    meta[1] = node_next[node]
                else:
                    node = meta[2]
                    meta[2] += 1
                node_id[node] = ids[i]
                node_next[node] = heads[s]
                heads[s] = node
    return pairs


@njit(cache=True, nogil=True)
def remove_kernel(ids, segs, cell_m, keys, heads, node_id, node_next, meta):
    """Forget ``ids`` indexed with ``segs`` (ids not indexed in a cell are ignored)."""
    r = _ranges(segs, cell_m)
    removed = 0
    for i in range(len(ids)):
        for ix in range(r[i, 0], r[i, 2] + 1):
            for iy in range(r[i, 1], r[i, 3] + 1):
                s = _find(keys, _key(ix, iy))
                if s < 0:
                    continue
                prev = -1
                node = heads[s]
                while node >= 0 and node_id[node] != ids[i]:
                    prev = node
                    node = node_next[node]
                if node < 0:
                    continue
                if prev < 0:
                    heads[s] = node_next[node]
                else:
                    node_next[prev] = node_next[node]
                node_next[node] = meta[1]
                meta[1] = node
                removed += 1
    return removed


@njit(cache=True, nogil=True, inline="always")
def _walk_cell(node, node_id, node_next, out, j, write):
    """Counts a cell's list from ``node`` on, writing its ids to ``out[j:]`` if ``write``."""
    while node >= 0:
        if write:
            out[j] = node_id[node]
        j += 1
        node = node_next[node]
    return j


@njit(cache=True, nogil=True)
def _walk_box(x0, y0, x1, y1, keys, heads, node_id, node_next, meta, out, write):
    """Counts the ids indexed in the cells ``x0…x1`` × ``y0…y1`` (with repeats), writing
    them to ``out`` if ``write``: one walk to size ``out``, the same walk to fill it."""
    j = 0
    if (x1 - x0 + 1) * (y1 - y0 + 1) > meta[0]:  # a box wider than the map: scan the table
        for s in range(len(keys)):
            k = keys[s]
            if k == _EMPTY:
                continue
            ix = k >> np.int64(32)
            iy = np.int64(np.int32(k & _MASK))
            if x0 <= ix <= x1 and y0 <= iy <= y1:
                j = _walk_cell(heads[s], node_id, node_next, out, j, write)
    else:
        for ix in range(x0, x1 + 1):
            for iy in range(y0, y1 + 1):
                s = _find(keys, _key(ix, iy))
                if s >= 0:
                    j = _walk_cell(heads[s], node_id, node_next, out, j, write)
    return j


@njit(cache=True, nogil=True)
def query_kernel(x0, y0, x1, y1, keys, heads, node_id, node_next, meta):
    """Sorted distinct ids indexed in the cells ``x0…x1`` × ``y0…y1``."""
    none = np.empty(0, np.int64)
    count = _walk_box(x0, y0, x1, y1, keys, heads, node_id, node_next, meta, none, False)
    out = np.empty(count, np.int64)
    _walk_box(x0, y0, x1, y1, keys, heads, node_id, node_next, meta, out, True)
    out.sort()
    m = 0
    for i in range(count):
        if i == 0 or out[i] != out[i - 1]:
            out[m] = out[i]
            m += 1
    return out[:m]


@njit(cache=True, nogil=True)
def rehash_kernel(keys, heads, new_keys, new_heads):
    """Move the non-empty cells of one table into an empty bigger one; returns them."""
    used = 0
    for s in range(len(keys)):
        if keys[s] != _EMPTY and heads[s] >= 0:
            t = -_find(new_keys, keys[s]) - 1
            new_keys[t] = keys[s]
            new_heads[t] = heads[s]
            used += 1
    return used
