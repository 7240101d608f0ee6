"""The ``corridors`` kind: a corridor network on an irregular grid of junctions.

Grid lines get random spacings and each line one width in [1.5, 3] m. A random spanning
tree (built around one forced grid cell, so there is always a loop) is pruned at its leaves
and given a few extra links: junctions, corners, dead ends and loops. Corridors are carved
out of solid ground; a little clutter (benches, cabinets) stands against the walls.
"""

from __future__ import annotations

import numpy as np

from worldgen.kinds import WorldKind
from worldgen.kinds._clutter import furnish_rects
from worldgen.kinds._plan import (
    Layout,
    boxes,
    centreline_links,
    partition_1d,
    random_tree_mask,
)
from worldgen.params import CorridorsParams

__all__ = ["layout_corridors"]

_JUNCTION_CLEAR_M = 1.0  # no clutter this close to a junction


def _grid_edges(nx_: int, ny_: int) -> np.ndarray:
    idx = np.arange(nx_ * ny_).reshape(ny_, nx_)
    horiz = np.column_stack([idx[:, :-1].ravel(), idx[:, 1:].ravel()])
    vert = np.column_stack([idx[:-1, :].ravel(), idx[1:, :].ravel()])
    return np.vstack([horiz, vert]).astype(np.int64)


def _select_edges(
    n: int, edges: np.ndarray, nx_: int, ny_: int, p: CorridorsParams, rng: np.random.Generator
) -> np.ndarray:
    """Boolean mask of grid edges that become corridors."""
    ci, cj = int(rng.integers(nx_ - 1)), int(rng.integers(ny_ - 1))
    cell = {cj * nx_ + ci, cj * nx_ + ci + 1, (cj + 1) * nx_ + ci, (cj + 1) * nx_ + ci + 1}
    in_cell = np.array([a in cell and b in cell for a, b in edges])
    # Kruskal visits the forced cell's edges first: three join the tree, the fourth closes
    # the guaranteed loop.
    order = np.concatenate([np.flatnonzero(in_cell), np.flatnonzero(~in_cell)])
    tree_sub = random_tree_mask(n, edges[order, 0], edges[order, 1], rng)
    tree = np.zeros(len(edges), dtype=bool)
    tree[order] = tree_sub
    chosen = tree | in_cell
    protected = np.zeros(n, dtype=bool)
    protected[list(cell)] = True
    for _ in range(2):
        deg = np.bincount(edges[chosen].ravel(), minlength=n)
        leaf = (deg == 1) & ~protected
        drop = chosen & (leaf[edges[:, 0]] | leaf[edges[:, 1]])
        drop &= rng.random(len(edges)) < p.prune_fraction
        if (deg == 1).sum() - drop.sum() >= 2:
            chosen &= ~drop
    deg = np.bincount(edges[chosen].ravel(), minlength=n)
    leaves = np.flatnonzero(deg == 1)
    keep_leaf = np.zeros(n, dtype=bool)
    if len(leaves):
        keep_leaf[leaves[int(rng.integers(len(leaves)))]] = True
    live = deg > 0
    extra = ~chosen & live[edges[:, 0]] & live[edges[:, 1]]
    extra &= ~(keep_leaf[edges[:, 0]] | keep_leaf[edges[:, 1]])
    extra &= rng.random(len(edges)) < p.extra_link_fraction
    return chosen | extra


def _stub(
    centre: np.ndarray,
    width: np.ndarray,
    xs: np.ndarray,
    ys: np.ndarray,
    wcol: np.ndarray,
    wrow: np.ndarray,
    rng: np.random.Generator,
) -> tuple[np.ndarray, list]:
    """A dead-end branch from the middle of a random corridor into the adjacent grid cell.

    Returns ``[rect(4), centre line(4), width]`` and the dead end ``[x, y, ux, uy, reach]``."""
    e = int(rng.integers(len(centre)))
    ax, ay, bx, by = centre[e]
    mx, my = 0.5 * (ax + bx), 0.5 * (ay + by)
    w = float(width.min())
    if ay == by:  # horizontal corridor: branch up or down, whichever grid line exists
        j = int(np.flatnonzero(ys == ay)[0])
        k = j + 1 if j + 1 < len(ys) else j - 1
        sign = np.sign(ys[k] - ay)
        gap = abs(ys[k] - ay) - 0.5 * (wrow[j] + wrow[k])
        tip = ay + sign * (0.5 * wrow[j] + 0.5 * gap)
        rect = [mx - 0.5 * w, min(ay, tip), mx + 0.5 * w, max(ay, tip)]
        line = [mx, ay, mx, tip - sign * 0.5 * w]
        end = [mx, line[3], 0.0, float(sign), 0.5 * w]
    else:
        i = int(np.flatnonzero(xs == ax)[0])
        k = i + 1 if i + 1 < len(xs) else i - 1
        sign = np.sign(xs[k] - ax)
        gap = abs(xs[k] - ax) - 0.5 * (wcol[i] + wcol[k])
        tip = ax + sign * (0.5 * wcol[i] + 0.5 * gap)
        rect = [min(ax, tip), my - 0.5 * w, max(ax, tip), my + 0.5 * w]
        line = [ax, my, tip - sign * 0.5 * w, my]
        end = [line[2], my, float(sign), 0.0, 0.5 * w]
    return np.array([*rect, *line, w]), end


def layout_corridors(rect: np.ndarray, p: CorridorsParams, rng: np.random.Generator) -> Layout:
    x0, y0, x1, y1 = np.asarray(rect, float)
    margin = 0.5 * p.corridor_width_max_m + p.wall_thickness_m
    xs = partition_1d(
        x0 + margin, x1 - margin, rng, p.junction_spacing_min_m, p.junction_spacing_max_m
    )
    ys = partition_1d(
        y0 + margin, y1 - margin, rng, p.junction_spacing_min_m, p.junction_spacing_max_m
    )
    nx_, ny_ = len(xs), len(ys)
    wcol = rng.uniform(p.corridor_width_min_m, p.corridor_width_max_m, nx_)
    wrow = rng.uniform(p.corridor_width_min_m, p.corridor_width_max_m, ny_)
    n = nx_ * ny_
    edges = _grid_edges(nx_, ny_)
    chosen = _select_edges(n, edges, nx_, ny_, p, rng)
    sel = edges[chosen]
    gi, gj = np.arange(n) % nx_, np.arange(n) // nx_
    px, py = xs[gi], ys[gj]
    a, b = sel[:, 0], sel[:, 1]
    horizontal = gj[a] == gj[b]
    width = np.where(horizontal, wrow[gj[a]], wcol[gi[a]])
    # Each corridor reaches half the crossing corridor's width past its end nodes.
    ext_a = np.where(horizontal, 0.5 * wcol[gi[a]], 0.5 * wrow[gj[a]])
    ext_b = np.where(horizontal, 0.5 * wcol[gi[b]], 0.5 * wrow[gj[b]])
    hw = 0.5 * width
    rects = np.where(
        horizontal[:, None],
        np.column_stack([px[a] - ext_a, py[a] - hw, px[b] + ext_b, py[a] + hw]),
        np.column_stack([px[a] - hw, py[a] - ext_a, px[a] + hw, py[b] + ext_b]),
    )
    centre = np.column_stack([px[a], py[a], px[b], py[b]])

    deg = np.bincount(sel.ravel(), minlength=n)
    leaf = np.flatnonzero(deg == 1)
    dead_ends = []
    if len(leaf) == 0:
        stub, end = _stub(centre, width, xs, ys, wcol, wrow, rng)
        rects = np.vstack([rects, stub[:4]])
        dead_ends.append(end)
        centre = np.vstack([centre, stub[4:8]])
        width = np.append(width, stub[8])
    for k in leaf:
        e = int(np.flatnonzero((a == k) | (b == k))[0])
        other = b[e] if a[e] == k else a[e]
        u = np.array([px[k] - px[other], py[k] - py[other]])
        u /= np.hypot(*u)
        reach = ext_a[e] if a[e] == k else ext_b[e]
        dead_ends.append([px[k], py[k], u[0], u[1], reach])
    corners = 0
    for k in np.flatnonzero(deg == 2):
        inc = (a == k) | (b == k)
        corners += int(horizontal[inc].sum() == 1)

    # Clutter stands along the long walls, clear of junctions.
    clear = np.column_stack([ext_a, ext_b]) + _JUNCTION_CLEAR_M
    along = np.where(
        horizontal[:, None],
        np.column_stack([px[a] + clear[:, 0], py[a] - hw, px[b] - clear[:, 1], py[a] + hw]),
        np.column_stack([px[a] - hw, py[a] + clear[:, 0], px[a] + hw, py[b] - clear[:, 1]]),
    )
    real = (along[:, 2] > along[:, 0]) & (along[:, 3] > along[:, 1])
    # wall items never reach the lane along the centre line that carries the roadmap
    cap = hw[real] - p.lane_half_width_m
    clutter = furnish_rects(
        along[real],
        rng,
        per_10m2=p.clutter_per_10m2,
        passage_m=p.passage_m,
        zones=np.zeros((0, 4)),
        wall_share=1.0,
        walls_along_x=horizontal[real],
        max_wall_depth_m=cap,
    )
    nodes_used = int((deg > 0).sum())
    layout = Layout(floor=list(boxes(rects)), clutter=clutter, links=[centreline_links(centre)])
    layout.features.update(
        corridor_segments=centre.tolist(),
        corridor_widths_m=width.tolist(),
        corridor_width_m=[float(width.min()), float(width.max())],
        dead_ends=dead_ends,
        junctions=int((deg >= 3).sum()),
        corners=corners,
        corridor_loops=int(len(sel) - nodes_used + 1),
    )
    return layout


KIND = WorldKind(
    name="corridors",
    params=CorridorsParams,
    layout=layout_corridors,
    summary="a corridor network on an irregular grid of junctions",
)
