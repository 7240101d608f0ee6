"""The optional compiled raycasting kernel (numba): ``cast_beams``, a per-beam grid walk.

Importing this module needs numba (a default dependency); ``RayCaster`` loads it
only when that backend is selected. Each beam walks the cells of ``SegmentGrid`` along its
ray, nearest first, and tests the pieces there; it stops at the first cell that ends
beyond the nearest hit so far, so a scan costs what the beams pass, not what the fan's
box holds, at any range.

It gives the numpy kernel's ranges (``raycast_kernel.cast_pieces``) bit for bit wherever
a beam does not graze a piece end: the contact and edge-on conventions are the same, and a
hit's distance is ``1 / Re(d * conj(n) / s)`` in the same float operations. Only which
piece owns a beam through a shared end differs (here the sign of a cross product decides,
half-open the same way for both pieces, so no beam slips between them either).

Pieces poke up to ``_MIN_PIECE_M`` past their cell, and rounding may place a ray a hair
off its cell, so the walk also looks into a neighbouring cell the ray passes within
``pad`` of (rare: only near cell edges and corners).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["cast_beams", "depth_edges"]

#: Distinct pieces seen edge-on a scan keeps track of; beyond this, all are checked.
_EDGE_ON_SLOTS = 32


@njit(cache=True, nogil=True, inline="always")
def _touches(table, j, ox, oy, tol):
    """Whether the origin lies on piece ``j`` (its line within ``tol``, beside the piece)."""
    a, b, cn = table[0, j], table[1, j], table[2, j]
    ar, ai = a.real - ox, a.imag - oy
    s = ar * cn.real - ai * cn.imag
    if abs(s) > tol:
        return False
    er, ei = (b.real - ox) - ar, (b.imag - oy) - ai
    length = math.hypot(er, ei)
    t = -(ar * er + ai * ei) / (length * length)
    slack = tol / length
    return t >= -slack and t <= 1.0 + slack


@njit(cache=True, nogil=True, inline="always")
def _hits(table, lo, hi, ox, oy, dr, di, tol, best, edges):
    """``best`` raised to 1 / distance of the nearest of pieces ``[lo, hi)`` the beam crosses.

    Pieces seen edge-on are only noted in ``edges`` (see ``_note_edge_on``): handling them
    here (an ``atan2``) would slow this, the hot loop, severalfold.
    """
    for j in range(lo, hi):
        a, cn = table[0, j], table[2, j]
        ar, ai = a.real - ox, a.imag - oy
        s = ar * cn.real - ai * cn.imag
        b = table[1, j]
        br, bi = b.real - ox, b.imag - oy
        if abs(s) <= tol:
            _note_edge_on(edges, j)
        # Half-open like the numpy kernel's beam runs: of two pieces sharing an end,
        # exactly one is crossed by a beam through that end.
        elif (dr * ai - di * ar > 0.0) != (dr * bi - di * br > 0.0):
            inv = 1.0 / s
            best = max(best, dr * (cn.real * inv) - di * (cn.imag * inv))
    return best


@njit(cache=True, nogil=True, inline="always")
def _note_edge_on(edges, j):
    """Add piece ``j`` to the set ``edges[1 : edges[0] + 1]``; ``edges[0] = -1`` once full."""
    count = edges[0]
    if count < 0:
        return
    for i in range(1, count + 1):
        if edges[i] == j:
            return
    if count + 1 < edges.size:
        edges[count + 1] = j
        edges[0] = count + 1
    else:
        edges[0] = -1


@njit(cache=True, nogil=True)
def _edge_on_hits(table, j, ox, oy, tol, directions, ext_rel, mid, dens):
    """If piece ``j`` is seen edge-on, the beam pointing exactly at its near end hits it."""
    a, cn, b = table[0, j], table[2, j], table[1, j]
    ar, ai = a.real - ox, a.imag - oy
    if abs(ar * cn.real - ai * cn.imag) > tol:
        return
    br, bi = b.real - ox, b.imag - oy
    qa, qb = ar * ar + ai * ai, br * br + bi * bi
    if qa <= qb:
        nr, ni, q = ar, ai, qa
    else:
        nr, ni, q = br, bi, qb
    ang = math.atan2(ni, nr) - mid
    n = dens.size
    for k in range(n):
        if ang == ext_rel[k] or ang == ext_rel[n + k] or ang == ext_rel[2 * n + k]:
            dr, di = directions[k].real, directions[k].imag
            dens[k] = max(dens[k], dr * (nr / q) - di * (-ni / q))


@njit(cache=True, nogil=True, inline="always")
def _cell_of(v, v0, c, n):
    return min(max(math.floor((v - v0) / c), 0), n - 1)


@njit(cache=True, nogil=True)
def _origin_on_a_piece(table, cell_start, layout, extra, ox, oy, tol, pad):
    """Contact: whether a piece near the origin (or an extra one) passes through it."""
    x0, y0, c = layout[0], layout[1], layout[2]
    nx, ny = int(layout[3]), int(layout[4])
    reach = 2.0 * tol + pad
    for iy in range(_cell_of(oy - reach, y0, c, ny), _cell_of(oy + reach, y0, c, ny) + 1):
        for ix in range(_cell_of(ox - reach, x0, c, nx), _cell_of(ox + reach, x0, c, nx) + 1):
            cid = iy * nx + ix
            for j in range(cell_start[cid], cell_start[cid + 1]):
                if _touches(table, j, ox, oy, tol):
                    return True
    for j in range(extra.shape[1]):  # noqa: SIM110 (numba compiles loops, not generators)
        if _touches(extra, j, ox, oy, tol):
            return True
    return False


@njit(cache=True, nogil=True, inline="always")
def _walk(table, cell_start, layout, ox, oy, dr, di, r_max, tol, pad, best, edges):
    """``best`` raised by the pieces along the ray ``origin + t (dr, di)``, cell by cell
    from the origin on (Amanatides & Woo), until a cell ends beyond the nearest hit."""
    x0, y0, c = layout[0], layout[1], layout[2]
    nx, ny = int(layout[3]), int(layout[4])
    # The part of the ray inside the grid, [t_in, t_hi].
    t_in, t_hi = 0.0, r_max
    if dr != 0.0:
        t1, t2 = (x0 - ox) / dr, (x0 + nx * c - ox) / dr
        t_in, t_hi = max(t_in, min(t1, t2)), min(t_hi, max(t1, t2))
    elif not x0 <= ox <= x0 + nx * c:
        return best
    if di != 0.0:
        t1, t2 = (y0 - oy) / di, (y0 + ny * c - oy) / di
        t_in, t_hi = max(t_in, min(t1, t2)), min(t_hi, max(t1, t2))
    elif not y0 <= oy <= y0 + ny * c:
        return best
    if t_in > t_hi:
        return best
    ix = _cell_of(ox + t_in * dr, x0, c, nx)
    iy = _cell_of(oy + t_in * di, y0, c, ny)
    # Ray parameter at the next x and y grid lines, and from one grid line to the next.
    step_x, tx, dtx = 0, math.inf, math.inf
    if dr != 0.0:
        step_x = 1 if dr > 0.0 else -1
        tx = (x0 + (ix + (step_x > 0)) * c - ox) / dr
        dtx = c / abs(dr)
    step_y, ty, dty = 0, math.inf, math.inf
    if di != 0.0:
        step_y = 1 if di > 0.0 else -1
        ty = (y0 + (iy + (step_y > 0)) * c - oy) / di
        dty = c / abs(di)
    prev = -1
    t_best = 1.0 / best
    while True:
        cid = iy * nx + ix
        seen = best
        best = _hits(table, cell_start[cid], cell_start[cid + 1], ox, oy, dr, di, tol, best, edges)
        if best != seen:
            t_best = 1.0 / best
        # Where the ray leaves this cell, and the cell it enters there.
        if tx <= ty:
            t_out, nix, niy = tx, ix + step_x, iy
        else:
            t_out, nix, niy = ty, ix, iy + step_y
        done = t_best <= t_out or t_out >= t_hi
        # Neighbours the ray passes within pad of, other than where it came from and
        # where it goes next (unless it stops here).
        t_end = min(t_out, t_best, t_hi)
        xa, xb = ox + t_in * dr, ox + t_end * dr
        ya, yb = oy + t_in * di, oy + t_end * di
        xl, yl = x0 + ix * c, y0 + iy * c
        near_l = ix > 0 and min(xa, xb) < xl + pad
        near_r = ix < nx - 1 and max(xa, xb) > xl + c - pad
        near_b = iy > 0 and min(ya, yb) < yl + pad
        near_t = iy < ny - 1 and max(ya, yb) > yl + c - pad
        if near_l or near_r or near_b or near_t:
            nxt = niy * nx + nix
            seen = best
            for ddy in range(-1, 2):
                if (ddy < 0 and not near_b) or (ddy > 0 and not near_t):
                    continue
                for ddx in range(-1, 2):
                    if (ddx < 0 and not near_l) or (ddx > 0 and not near_r):
                        continue
                    ncid = cid + ddy * nx + ddx
                    if ncid == cid or ncid == prev or (ncid == nxt and not done):  # noqa: SIM109
                        continue
                    lo, hi = cell_start[ncid], cell_start[ncid + 1]
                    best = _hits(table, lo, hi, ox, oy, dr, di, tol, best, edges)
            if best != seen:
                t_best = 1.0 / best
        if done or not (0 <= nix < nx and 0 <= niy < ny):
            return best
        if tx <= ty:
            tx += dtx
        else:
            ty += dty
        prev, ix, iy, t_in = cid, nix, niy, t_out


@njit(cache=True, nogil=True)
def cast_beams(table, cell_start, layout, extra, directions, ext_rel, scan, out):
    """Fill ``out`` (``(B,)``, beams in sorted order) with ranges; ``inf`` for no hit.

    ``table``/``cell_start``/``layout`` (``[x0, y0, cell, nx, ny]``) are the grid's,
    ``extra`` more ``(3, M)`` pieces every beam tests, ``directions`` the beams' world
    directions (``beam_directions``), ``ext_rel`` the fan's, and ``scan`` holds
    ``[ox, oy, mid, r_max, tol, pad]``.
    """
    ox, oy, mid, r_max, tol, pad = scan[0], scan[1], scan[2], scan[3], scan[4], scan[5]
    if _origin_on_a_piece(table, cell_start, layout, extra, ox, oy, tol, pad):
        out[:] = 0.0  # inside a wall
        return
    floor_den = 0.5 / r_max  # as in the numpy kernel: a range beyond r_max either way
    edges = np.zeros(_EDGE_ON_SLOTS + 1, dtype=np.intp)
    extra_edges = np.zeros(1, dtype=np.intp)  # a sink: every extra is checked below
    for k in range(out.size):
        dr, di = directions[k].real, directions[k].imag
        best = _hits(extra, 0, extra.shape[1], ox, oy, dr, di, tol, floor_den, extra_edges)
        out[k] = _walk(table, cell_start, layout, ox, oy, dr, di, r_max, tol, pad, best, edges)
    # Pieces seen edge-on: only those some beam walked past can matter (a beam pointing
    # at one walks past it unless it stops nearer first).
    if edges[0] < 0:
        for j in range(table.shape[1]):  # more than _EDGE_ON_SLOTS: look at them all
            _edge_on_hits(table, j, ox, oy, tol, directions, ext_rel, mid, out)
    else:
        for i in range(1, edges[0] + 1):
            _edge_on_hits(table, edges[i], ox, oy, tol, directions, ext_rel, mid, out)
    for j in range(extra.shape[1]):
        _edge_on_hits(extra, j, ox, oy, tol, directions, ext_rel, mid, out)
    for k in range(out.size):
        r = 1.0 / out[k]
        out[k] = r if r <= r_max else math.inf


#: Segments through one point the surface kernel keeps (walls meet in twos; overlaps are rare).
_THROUGH_SLOTS = 16


@njit(cache=True, nogil=True)
def _corners_through(x, y, table, piece_segment, cell_start, layout, vertex, extra,
                     extra_vertex, tol, out):  # fmt: skip
    """Fill ``out`` with the corner ids of the segments within ``tol`` of ``(x, y)`` (the
    pieces of the grid cells the square ``(x, y) ± tol`` touches, then every extra
    segment); returns how many were written."""
    x0, y0, c = layout[0], layout[1], layout[2]
    nx, ny = int(layout[3]), int(layout[4])
    ix0 = min(max(math.floor((x - tol - x0) / c), 0), nx - 1)
    ix1 = min(max(math.floor((x + tol - x0) / c), 0), nx - 1)
    iy0 = min(max(math.floor((y - tol - y0) / c), 0), ny - 1)
    iy1 = min(max(math.floor((y + tol - y0) / c), 0), ny - 1)
    m = 0
    for iy in range(iy0, iy1 + 1):
        for ix in range(ix0, ix1 + 1):
            cell = iy * nx + ix
            for j in range(cell_start[cell], cell_start[cell + 1]):
                if m + 2 <= len(out) and _distance(x, y, table[0, j], table[1, j]) <= tol:
                    s = piece_segment[j]
                    out[m] = vertex[s, 0]
                    out[m + 1] = vertex[s, 1]
                    m += 2
    for j in range(extra.shape[1]):
        if m + 2 <= len(out) and _distance(x, y, extra[0, j], extra[1, j]) <= tol:
            out[m] = extra_vertex[j, 0]
            out[m + 1] = extra_vertex[j, 1]
            m += 2
    return m


@njit(cache=True, nogil=True, inline="always")
def _distance(x, y, a, b):
    """Distance from ``(x, y)`` to the segment ``a → b`` (complex ends)."""
    er, ei = b.real - a.real, b.imag - a.imag
    zr, zi = x - a.real, y - a.imag
    t = (er * zr + ei * zi) / max(er * er + ei * ei, 1e-300)
    t = min(max(t, 0.0), 1.0)
    return math.hypot(zr - t * er, zi - t * ei)


@njit(cache=True, nogil=True)
def depth_edges(ox, oy, angles, r, hit, min_jump, table, piece_segment, cell_start, layout,
                vertex, extra, extra_vertex, tol, out):  # fmt: skip
    """``out[i]``: whether beams ``i`` and ``i + 1`` straddle an occluding edge
    (``RayCaster.depth_edges``' numpy path, with ``RayCaster.same_surface``'s test inline:
    some segment through each hit is the same or shares a corner id with the other's)."""
    cp = np.empty(2 * _THROUGH_SLOTS, np.intp)
    cq = np.empty(2 * _THROUGH_SLOTS, np.intp)
    for i in range(len(out)):
        edge = hit[i] and hit[i + 1] and abs(r[i + 1] - r[i]) > min_jump
        if edge:
            px, py = ox + r[i] * math.cos(angles[i]), oy + r[i] * math.sin(angles[i])
            qx = ox + r[i + 1] * math.cos(angles[i + 1])
            qy = oy + r[i + 1] * math.sin(angles[i + 1])
            mp = _corners_through(px, py, table, piece_segment, cell_start, layout, vertex,
                                  extra, extra_vertex, tol, cp)  # fmt: skip
            mq = _corners_through(qx, qy, table, piece_segment, cell_start, layout, vertex,
                                  extra, extra_vertex, tol, cq)  # fmt: skip
            for a in range(mp):
                for b in range(mq):
                    if cp[a] == cq[b]:
                        edge = False
        out[i] = edge
