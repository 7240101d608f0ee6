"""Floor-plan building blocks shared by the kinds: cells, partitions, adjacency and doors.

Rectangles are ``(N, 4)`` float arrays ``[x0, y0, x1, y1]``. A floor plan is a partition of
the plane into *cells* whose shared edges are wall centre lines; each cell's free interior
is the cell shrunk by half the wall thickness, and a door is a rectangle bridging the wall
between two interiors. Everything a kind produces is collected in a ``Layout``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import shapely
from numpy.typing import NDArray

__all__ = [
    "JAMB_M",
    "Adjacency",
    "Layout",
    "adjacency",
    "boxes",
    "bsp_cells",
    "cell_centrelines",
    "centreline_links",
    "door_approaches",
    "door_rects",
    "foot_on_segments",
    "lanes_to_hubs",
    "partition_1d",
    "random_tree_mask",
    "shrink",
]

FloatArray = NDArray[np.float64]
JAMB_M = 0.3  # shortest piece of wall kept between a door and a corner
_EPS = 1e-9
_ON_LINE_TOL_M = 1e-7
_ADJ_FIELDS = ("i", "j", "axis", "coord", "lo", "hi", "sign")


@dataclass
class Layout:
    """What a kind generator produced, before assembly into a World.

    ``links`` are planned straight roadmap edges ``(M, 4)``; ``None`` asks for the generic
    medial-axis roadmap instead."""

    floor: list[shapely.Geometry] = field(default_factory=list)
    clutter: list[shapely.Polygon] = field(default_factory=list)
    features: dict[str, Any] = field(default_factory=dict)
    seed_points: list[FloatArray] = field(default_factory=list)
    doorways: list[FloatArray] = field(default_factory=list)
    links: list[FloatArray] | None = field(default_factory=list)

    def link_array(self) -> FloatArray | None:
        if self.links is None:
            return None
        if not self.links:
            return np.zeros((0, 4))
        return np.vstack([np.asarray(k, float).reshape(-1, 4) for k in self.links])

    def floor_geometry(self) -> shapely.Geometry:
        return shapely.union_all(np.asarray(self.floor, dtype=object))

    def seeds(self) -> FloatArray:
        if not self.seed_points:
            return np.zeros((0, 2))
        return np.vstack([np.asarray(s, float).reshape(-1, 2) for s in self.seed_points])

    def doorway_array(self) -> FloatArray:
        if not self.doorways:
            return np.zeros((0, 4))
        return np.vstack([np.asarray(d, float).reshape(-1, 4) for d in self.doorways])


def boxes(rects: FloatArray) -> NDArray[np.object_]:
    r = np.asarray(rects, dtype=np.float64).reshape(-1, 4)
    return shapely.box(r[:, 0], r[:, 1], r[:, 2], r[:, 3])


def shrink(rects: FloatArray, d: float) -> FloatArray:
    r = np.asarray(rects, dtype=np.float64).reshape(-1, 4)
    return r + np.array([d, d, -d, -d])


def partition_1d(
    lo: float, hi: float, rng: np.random.Generator, min_m: float, max_m: float
) -> FloatArray:
    """Cut ``[lo, hi]`` into pieces of about ``[min_m, max_m]`` each; returns the cut points
    including both ends. Pieces are never shorter than ``min_m`` unless the span is."""
    span = hi - lo
    n_lo = max(1, int(np.ceil(span / max_m - _EPS)))
    n_hi = max(1, int(np.floor(span / min_m + _EPS)))
    n = int(rng.integers(min(n_lo, n_hi), max(n_lo, n_hi) + 1))
    spare = max(0.0, span - n * min_m)
    weights = rng.uniform(0.2, 1.0, n)
    sizes = np.full(n, span / n) if spare == 0.0 else min_m + spare * weights / weights.sum()
    sizes *= span / sizes.sum()
    cuts = lo + np.concatenate([[0.0], np.cumsum(sizes)])
    cuts[-1] = hi
    return cuts


def bsp_cells(
    rect: FloatArray,
    rng: np.random.Generator,
    min_m: float,
    max_m: float,
    stop_prob: float = 0.3,
    split_root: bool = True,
) -> FloatArray:
    """Binary space partition of ``rect`` into cells with sides in about ``[min_m, max_m]``.

    A cell wider than ``max_m`` is always split; one between ``2 min_m`` and ``max_m`` is
    split with probability ``1 - stop_prob``, so room sizes vary. With ``split_root`` the
    whole rectangle is always split when it can be (so there are at least two cells).
    """
    todo = [np.asarray(rect, dtype=np.float64)]
    done: list[FloatArray] = []
    first = split_root
    while todo:
        x0, y0, x1, y1 = cell = todo.pop()
        w, h = x1 - x0, y1 - y0
        axis = 0 if w >= h else 1
        length = w if axis == 0 else h
        must = length > max_m
        can = length >= 2.0 * min_m
        stop = not must and not first and rng.random() < stop_prob
        first = False
        if not can or stop:
            done.append(cell)
            continue
        start = (x0, y0)[axis]
        cut = start + rng.uniform(min_m, length - min_m)
        a, b = cell.copy(), cell.copy()
        a[2 + axis] = cut
        b[axis] = cut
        todo.extend([b, a])
    return np.array(done).reshape(-1, 4)


@dataclass(frozen=True)
class Adjacency:
    """Pairs of cells sharing a wall: ``i`` in the first set, ``j`` in the second.

    ``axis`` 0 means a vertical wall at ``x = coord``, 1 a horizontal wall at ``y = coord``;
    ``lo``/``hi`` bound the shared stretch along the wall; ``sign`` is +1 when cell ``j``
    lies on the side of larger x (or y), -1 otherwise.
    """

    i: NDArray[np.int64]
    j: NDArray[np.int64]
    axis: NDArray[np.int64]
    coord: FloatArray
    lo: FloatArray
    hi: FloatArray
    sign: FloatArray

    def __len__(self) -> int:
        return len(self.i)

    def take(self, mask: NDArray[np.bool_] | NDArray[np.int64]) -> Adjacency:
        return Adjacency(
            self.i[mask],
            self.j[mask],
            self.axis[mask],
            self.coord[mask],
            self.lo[mask],
            self.hi[mask],
            self.sign[mask],
        )

    def swapped(self) -> Adjacency:
        """The same walls seen from the other side (``i`` and ``j`` exchanged)."""
        return Adjacency(self.j, self.i, self.axis, self.coord, self.lo, self.hi, -self.sign)

    @staticmethod
    def concat(parts: list[Adjacency]) -> Adjacency:
        return Adjacency(*(np.concatenate([getattr(p, f) for p in parts]) for f in _ADJ_FIELDS))


def _touching(a_vals: FloatArray, b_vals: FloatArray) -> tuple[NDArray[np.int64], ...]:
    """All index pairs (i, j) with ``a_vals[i]`` equal to ``b_vals[j]`` (within 1e-7)."""
    order = np.argsort(b_vals, kind="stable")
    sorted_b = b_vals[order]
    lo = np.searchsorted(sorted_b, a_vals - 1e-7, side="left")
    hi = np.searchsorted(sorted_b, a_vals + 1e-7, side="right")
    count = hi - lo
    ii = np.repeat(np.arange(len(a_vals)), count)
    k = np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)
    jj = order[np.repeat(lo, count) + k]
    return ii.astype(np.int64), jj.astype(np.int64)


def adjacency(
    a: FloatArray, b: FloatArray | None = None, *, min_overlap_m: float = 0.0
) -> Adjacency:
    """All pairs of rectangles (from ``a`` and ``b``, or within ``a``) that share a wall
    stretch at least ``min_overlap_m`` long. Matches edges by sorting, not all pairs."""
    same = b is None
    A = np.asarray(a, float).reshape(-1, 4)
    B = A if same else np.asarray(b, float).reshape(-1, 4)
    parts = []
    for axis in (0, 1):
        o = 1 - axis
        for (a_side, b_side), sign in (((2 + axis, axis), 1.0), ((axis, 2 + axis), -1.0)):
            ii, jj = _touching(A[:, a_side], B[:, b_side])
            lo = np.maximum(A[ii, o], B[jj, o])
            hi = np.minimum(A[ii, 2 + o], B[jj, 2 + o])
            ok = hi - lo >= min_overlap_m
            if same:
                ok &= ii < jj
            ii, jj, lo, hi = ii[ok], jj[ok], lo[ok], hi[ok]
            parts.append(
                (ii, jj, np.full(len(ii), axis), A[ii, a_side], lo, hi, np.full(len(ii), sign))
            )
    cat = [np.concatenate([p[k] for p in parts]) for k in range(7)]
    order = np.lexsort((cat[1], cat[0]))
    return Adjacency(
        cat[0][order].astype(np.int64),
        cat[1][order].astype(np.int64),
        cat[2][order].astype(np.int64),
        cat[3][order],
        cat[4][order],
        cat[5][order],
        cat[6][order],
    )


def door_rects(
    adj: Adjacency,
    rng: np.random.Generator,
    *,
    width_min_m: float,
    width_max_m: float,
    wall_thickness_m: float,
    zone_depth_m: float,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """One door per adjacency: (door rectangles, doorway segments, clear zones).

    The door rectangle spans the wall thickness so it joins the two interiors; the doorway
    segment runs across the opening on the wall centre line; the zone is the door widened by
    a little and extended ``zone_depth_m`` into both rooms, to be kept free of clutter.
    """
    n = len(adj)
    half_t = 0.5 * wall_thickness_m
    room = adj.hi - adj.lo - 2.0 * (half_t + JAMB_M)
    width = np.minimum(rng.uniform(width_min_m, width_max_m, n), np.maximum(room, width_min_m))
    free = np.maximum(room - width, 0.0)
    centre = adj.lo + half_t + JAMB_M + 0.5 * width + rng.random(n) * free
    a0, a1 = centre - 0.5 * width, centre + 0.5 * width
    c = adj.coord
    vertical = adj.axis == 0
    rect = np.where(
        vertical[:, None],
        np.column_stack([c - half_t, a0, c + half_t, a1]),
        np.column_stack([a0, c - half_t, a1, c + half_t]),
    )
    seg = np.where(
        vertical[:, None],
        np.column_stack([c, a0, c, a1]),
        np.column_stack([a0, c, a1, c]),
    )
    pad = half_t + zone_depth_m
    zone = np.where(
        vertical[:, None],
        np.column_stack([c - pad, a0 - 0.2, c + pad, a1 + 0.2]),
        np.column_stack([a0 - 0.2, c - pad, a1 + 0.2, c + pad]),
    )
    return rect, seg, zone


def random_tree_mask(
    n_nodes: int, i: NDArray[np.int64], j: NDArray[np.int64], rng: np.random.Generator
) -> NDArray[np.bool_]:
    """A random spanning forest (Kruskal on random weights): which pairs are tree edges."""
    parent = list(range(n_nodes))

    def find(k: int) -> int:
        while parent[k] != k:
            parent[k] = parent[parent[k]]
            k = parent[k]
        return k

    mask = np.zeros(len(i), dtype=bool)
    for e in np.argsort(rng.random(len(i)), kind="stable"):
        ra, rb = find(int(i[e])), find(int(j[e]))
        if ra != rb:
            parent[ra] = rb
            mask[e] = True
    return mask


def door_approaches(
    rects: FloatArray, adj: Adjacency, offset_m: float
) -> tuple[FloatArray, FloatArray]:
    """Points ``offset_m`` in front of each door on the ``i`` side and on the ``j`` side.

    The link between them crosses the door along its axis, so it keeps half the door width
    from the jambs."""
    centre = 0.5 * (rects[:, :2] + rects[:, 2:])
    normal = np.where(adj.axis[:, None] == 0, [[1.0, 0.0]], [[0.0, 1.0]]) * adj.sign[:, None]
    half = 0.5 * np.where(adj.axis == 0, rects[:, 2] - rects[:, 0], rects[:, 3] - rects[:, 1])
    reach = (half + offset_m)[:, None]
    return centre - normal * reach, centre + normal * reach


def lanes_to_hubs(
    interiors: FloatArray,
    room: NDArray[np.int64],
    approach: FloatArray,
    axis: NDArray[np.int64],
    half_width_m: float,
) -> tuple[FloatArray, FloatArray]:
    """L-shaped lanes from door approach points to their room's centre (the hub).

    A lane leaves the door straight into the room, then turns once towards the hub, so it
    stays clear of the room's corners. Returns the links ``(2K, 4)`` and the rectangles
    ``(2K, 4)`` (lanes widened by ``half_width_m``) to keep free of clutter."""
    r = interiors[room]
    hub = 0.5 * (r[:, :2] + r[:, 2:])
    # door in a vertical wall (axis 0): go along x to the hub's x first
    corner = np.where(
        axis[:, None] == 0,
        np.column_stack([hub[:, 0], approach[:, 1]]),
        np.column_stack([approach[:, 0], hub[:, 1]]),
    )
    links = np.vstack([np.hstack([approach, corner]), np.hstack([corner, hub])])
    lo = np.minimum(links[:, :2], links[:, 2:]) - half_width_m
    hi = np.maximum(links[:, :2], links[:, 2:]) + half_width_m
    return links, np.hstack([lo, hi])


def foot_on_segments(points: FloatArray, lines: FloatArray, which: NDArray[np.int64]) -> FloatArray:
    """Closest point of segment ``lines[which[k]]`` to ``points[k]``."""
    a, b = lines[which, :2], lines[which, 2:]
    d = b - a
    len2 = np.einsum("ij,ij->i", d, d)
    t = np.clip(np.einsum("ij,ij->i", points - a, d) / np.where(len2 > 0, len2, 1.0), 0.0, 1.0)
    foot = a + t[:, None] * d
    # keep the fixed coordinate of axis-aligned lines bit-exact, so feet lie on their line
    foot[:, 0] = np.where(d[:, 0] == 0.0, a[:, 0], foot[:, 0])
    foot[:, 1] = np.where(d[:, 1] == 0.0, a[:, 1], foot[:, 1])
    return foot


def centreline_links(lines: FloatArray, points: FloatArray | None = None) -> FloatArray:
    """Split centre lines at every crossing with another line and at every given point on
    them, and return the pieces as links. Crossings of axis-aligned lines are exact."""
    L = np.asarray(lines, float).reshape(-1, 4)
    extra = np.zeros((0, 2)) if points is None else np.asarray(points, float).reshape(-1, 2)
    vert = L[:, 0] == L[:, 2]
    horiz = L[:, 1] == L[:, 3]
    V, H = L[vert], L[horiz]
    cross_x = np.broadcast_to(V[:, None, 0], (len(V), len(H)))
    cross_y = np.broadcast_to(H[None, :, 1], (len(V), len(H)))
    tol = _ON_LINE_TOL_M
    inside = (
        (cross_x >= np.minimum(H[None, :, 0], H[None, :, 2]) - tol)
        & (cross_x <= np.maximum(H[None, :, 0], H[None, :, 2]) + tol)
        & (cross_y >= np.minimum(V[:, None, 1], V[:, None, 3]) - tol)
        & (cross_y <= np.maximum(V[:, None, 1], V[:, None, 3]) + tol)
    )
    crossings = np.column_stack([cross_x[inside], cross_y[inside]])
    cand = np.vstack([L[:, :2], L[:, 2:], extra, crossings])
    out = []
    for a0, a1, b0, b1 in L:
        d = np.array([b0 - a0, b1 - a1])
        length = float(np.hypot(*d))
        if length == 0.0:
            continue
        rel = cand - [a0, a1]
        t = rel @ d / length**2
        off = np.abs(rel[:, 0] * d[1] - rel[:, 1] * d[0]) / length
        on = (off <= tol) & (t >= -tol / length) & (t <= 1 + tol / length)
        pts, ts = cand[on], t[on]
        order = np.argsort(ts, kind="stable")
        pts = pts[order]
        keep = np.ones(len(pts), dtype=bool)
        keep[1:] = np.any(pts[1:] != pts[:-1], axis=1)
        pts = pts[keep]
        if len(pts) >= 2:
            out.append(np.hstack([pts[:-1], pts[1:]]))
    return np.vstack(out) if out else np.zeros((0, 4))


def cell_centrelines(cells: FloatArray) -> FloatArray:
    """The long centre line of each corridor cell, ending half a width from its ends."""
    x0, y0, x1, y1 = np.asarray(cells, float).reshape(-1, 4).T
    wide = (x1 - x0) >= (y1 - y0)
    mx, my = 0.5 * (x0 + x1), 0.5 * (y0 + y1)
    hw, hh = 0.5 * (y1 - y0), 0.5 * (x1 - x0)
    return np.where(
        wide[:, None],
        np.column_stack([x0 + hw, my, x1 - hw, my]),
        np.column_stack([mx, y0 + hh, mx, y1 - hh]),
    )
