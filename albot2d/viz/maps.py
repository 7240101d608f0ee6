"""Pictures of a mapper's maps: a global map and Albot1's route map (the ``viz`` extra).

- ``plot_map(segments, *, map_ids=None, ax=None, ...) -> Axes``: a global map, surfaces
  coloured by the local map (view) they came from, with the mapper's estimated path; in
  simulation drawn over the faint true walls, anchored at the true start pose (as the paper
  plots S in its original position), so drift shows. ``map_surfaces(ax)`` gives back the
  surfaces' LineCollection (for a colour bar).
- ``plot_route(route, *, ax=None, ...) -> Axes``: Albot1's route map as its chain of
  remembered views (viewpoints coloured by how each was localised, the views' surfaces
  faint).

The frame helpers (``anchor_segments``, ``anchor_path``, ``extent_of``, ``set_extent``)
are shared with the run figures and the animation. matplotlib is imported inside the
functions; figures use the Agg canvas directly.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from albot2d.geometry import compose_arrays, transform_segments
from albot2d.viz._figure import colour_buckets, line_segments, nan_lines, new_figure

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.collections import LineCollection

    from albot2d.mapping.albot1.route_map import RouteMap
    from worldgen.world import World

__all__ = [
    "Extent",
    "anchor_path",
    "anchor_segments",
    "extent_of",
    "map_surfaces",
    "plot_map",
    "plot_route",
    "set_extent",
]

FloatArray = NDArray[np.float64]
Extent = tuple[float, float, float, float]
"""``(x_min, y_min, x_max, y_max)`` of a panel, in metres."""
WORLD_COLOR = "#d0d0d0"
EST_PATH_COLOR = "#d32f2f"
TRUE_PATH_COLOR = "#1565c0"
START_COLOR = "#2e7d32"
VIEW_COLOR = "#9575cd"
METHOD_COLORS = {"start": START_COLOR, "triangulation": "#1565c0", "path_integration": "#e65100"}
MAP_CMAP = "viridis"
MAP_SURFACES_LABEL = "map surfaces"
PANEL_IN = 5.0
_MARGIN_FRACTION = 0.04


def anchor_segments(start_pose: FloatArray | None, segments: FloatArray) -> FloatArray:
    return segments if start_pose is None else transform_segments(start_pose, segments)


def anchor_path(start_pose: FloatArray | None, path: FloatArray) -> FloatArray:
    return path if start_pose is None or not len(path) else compose_arrays(start_pose, path)


def extent_of(parts: Sequence[FloatArray]) -> Extent | None:
    pts = [np.asarray(p, np.float64).reshape(-1, 2) for p in parts if np.size(p)]
    if not pts:
        return None
    allp = np.vstack(pts)
    allp = allp[np.all(np.isfinite(allp), axis=1)]
    if not len(allp):
        return None
    (x0, y0), (x1, y1) = allp.min(axis=0), allp.max(axis=0)
    m = _MARGIN_FRACTION * max(x1 - x0, y1 - y0, 1.0)
    return x0 - m, y0 - m, x1 + m, y1 + m


def set_extent(ax: Axes, extent: Extent | None) -> None:
    if extent is not None:
        ax.set_xlim(extent[0], extent[2])
        ax.set_ylim(extent[1], extent[3])
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")


def _draw_world(ax: Axes, world: World | None) -> None:
    from matplotlib.collections import LineCollection

    if world is not None and len(world.obstacle_segments):
        ax.add_collection(
            _unsimplified(
                LineCollection(
                    nan_lines(world.obstacle_segments), colors=WORLD_COLOR, linewidths=0.8, zorder=1
                )
            )
        )


def _unsimplified(lines: LineCollection) -> LineCollection:
    # Long NaN-separated paths would be simplified by matplotlib (sub-pixel segments
    # merged); keep every segment's stroke as if it were drawn alone.
    for path in lines.get_paths():
        path.should_simplify = False
    return lines


def _surface_lines(
    segs: FloatArray, map_ids: NDArray[np.int64] | None, id_range: tuple[int, int] | None
) -> LineCollection:
    """The surfaces as one LineCollection of a few NaN-separated lines per colour of the
    map (memory ~ the vertices, not a Path object per surface; see ``nan_lines``)."""
    from matplotlib import colormaps
    from matplotlib.collections import LineCollection

    style = {"linewidths": 1.6, "zorder": 3, "label": MAP_SURFACES_LABEL}
    if map_ids is None or not len(segs):
        lines = LineCollection(nan_lines(segs), colors="#212121")
        lines.set(**style)
        return _unsimplified(lines)
    ids = np.asarray(map_ids)
    lo, hi = id_range if id_range is not None else (int(np.min(ids)), int(np.max(ids)))
    hi = max(hi, lo + 1)
    cmap = colormaps[MAP_CMAP]
    order, starts, value = colour_buckets(ids, (lo, hi), cmap.N)
    paths: list[FloatArray] = []
    values: list[float] = []
    for g, v in enumerate(value):
        group = nan_lines(segs[order[starts[g] : starts[g + 1]]])
        paths += group
        values += [float(v)] * len(group)
    lines = LineCollection(paths, cmap=cmap)
    lines.set(**style)
    lines.set_array(np.asarray(values, dtype=np.float64))
    lines.set_clim(lo, hi)
    return _unsimplified(lines)


def plot_map(
    segments: FloatArray,
    *,
    map_ids: NDArray[np.int64] | None = None,
    ax: Axes | None = None,
    world: World | None = None,
    start_pose: FloatArray | None = None,
    est_path: FloatArray | None = None,
    true_path: FloatArray | None = None,
    id_range: tuple[int, int] | None = None,
    extent: Extent | None = None,
    title: str | None = None,
) -> Axes:
    """Draw one global map (``(N, 4)`` surfaces) on ``ax`` (a new figure when None); returns
    the axes. ``map_ids`` colour each surface by its view (over ``id_range``, default the
    ids' own range); ``map_surfaces(ax)`` gives the surfaces' LineCollection (for a colour
    bar). The surfaces are drawn as a few NaN-separated lines per colour of the map, so a
    map of a million surfaces costs its vertices, not a Path object each; the collection's
    colour limits are fixed when drawn (pass ``id_range`` rather than ``set_clim`` after).

    ``segments``/``est_path`` are in the mapper's frame and are moved into the world by
    ``start_pose`` when given; ``true_path`` and ``world`` are in the world frame.
    """
    if ax is None:
        ax = new_figure(PANEL_IN * 1.6, PANEL_IN * 1.6).add_subplot()
    _draw_world(ax, world)
    segs = anchor_segments(start_pose, np.asarray(segments, np.float64).reshape(-1, 4))
    ax.add_collection(_surface_lines(segs, map_ids, id_range))
    parts: list[FloatArray] = [segs.reshape(-1, 2)]
    if world is not None and len(world.obstacle_segments):
        ax.plot([], [], "-", color=WORLD_COLOR, lw=0.8, label="true walls")
    if true_path is not None and len(true_path):
        ax.plot(
            *true_path[:, :2].T,
            "-",
            color=TRUE_PATH_COLOR,
            lw=0.8,
            alpha=0.5,
            zorder=2,
            label="true path",
        )
        parts.append(true_path[:, :2])
    if est_path is not None and len(est_path):
        from albot2d.viz.paths import draw_direction_arrows

        path = anchor_path(start_pose, np.asarray(est_path, np.float64).reshape(-1, 3))
        ax.plot(
            *path[:, :2].T, "-", color=EST_PATH_COLOR, lw=1.0, zorder=4, label="estimated path (→)"
        )
        draw_direction_arrows(ax, path, color=EST_PATH_COLOR, count=8, size=9.0, zorder=4)
        ax.plot(*path[0, :2], "*", color=START_COLOR, ms=12, zorder=5, label="start")
        ax.plot(*path[-1, :2], "o", color=EST_PATH_COLOR, ms=6, zorder=5, label="robot")
        parts.append(path[:, :2])
    if world is not None:
        b = world.bounds
        parts.append(np.array([[b[0], b[1]], [b[2], b[3]]]))
    set_extent(ax, extent if extent is not None else extent_of(parts))
    if title:
        ax.set_title(title, fontsize=10)
    return ax


def map_surfaces(ax: Axes) -> LineCollection:
    """The surfaces' LineCollection that ``plot_map`` drew last on ``ax``."""
    from matplotlib.collections import LineCollection

    drawn = [
        c
        for c in ax.collections
        if isinstance(c, LineCollection) and c.get_label() == MAP_SURFACES_LABEL
    ]
    if not drawn:
        raise ValueError("ax: plot_map has not drawn a map on these axes")
    return drawn[-1]


def plot_route(
    route: RouteMap,
    *,
    ax: Axes | None = None,
    world: World | None = None,
    start_pose: FloatArray | None = None,
    true_path: FloatArray | None = None,
    title: str | None = None,
) -> Axes:
    """Draw a route map on ``ax`` (a new figure when None): each remembered view's surfaces
    (faint) and its viewpoint, the viewpoints chained in order and coloured by how they
    were localised. Returns the axes."""
    from matplotlib.collections import LineCollection
    from matplotlib.lines import Line2D

    if ax is None:
        ax = new_figure(PANEL_IN * 1.6, PANEL_IN * 1.6).add_subplot()
    _draw_world(ax, world)
    poses = anchor_path(start_pose, route.compose_chain()) if len(route) else np.zeros((0, 3))
    views = [transform_segments(p, m.view.segments) for p, m in zip(poses, route, strict=True)]
    segs = np.vstack(views) if views else np.zeros((0, 4))
    # One line per surface here (not ``nan_lines``): with alpha, overlapping views darken,
    # which shows where many remembered views overlap; one path per colour would not.
    ax.add_collection(
        LineCollection(line_segments(segs), colors=VIEW_COLOR, linewidths=0.5, alpha=0.5, zorder=2)
    )
    if true_path is not None and len(true_path):
        ax.plot(*true_path[:, :2].T, "-", color=TRUE_PATH_COLOR, lw=0.8, alpha=0.4, zorder=2)
    handles = []
    if len(poses):
        ax.plot(*poses[:, :2].T, "-", color="#424242", lw=0.8, zorder=3)
        methods = np.array(route.methods())
        for method, color in METHOD_COLORS.items():
            sel = methods == method
            if sel.any():
                ax.plot(*poses[sel, :2].T, "o", color=color, ms=3, zorder=4)
                handles.append(
                    Line2D(
                        [],
                        [],
                        color=color,
                        marker="o",
                        ls="",
                        label=f"{method.replace('_', ' ')} ({int(sel.sum())})",
                    )
                )
    if len(poses):
        ax.plot(*poses[0, :2], "*", color=START_COLOR, ms=12, zorder=5)
    handles.append(Line2D([], [], color=VIEW_COLOR, lw=1, label="local maps' surfaces"))
    handles.append(Line2D([], [], color=START_COLOR, marker="*", ls="", ms=10, label="start"))
    parts = [segs.reshape(-1, 2), poses[:, :2]]
    if world is not None:
        b = world.bounds
        parts.append(np.array([[b[0], b[1]], [b[2], b[3]]]))
    set_extent(ax, extent_of(parts))
    from albot2d.viz.furniture import LEGEND_PT, TITLE_PT, draw_map_furniture

    draw_map_furniture(ax, np.vstack([segs.reshape(-1, 2), poses[:, :2]]))
    # below the axes, off the map (upper center of the box under it)
    ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.09),
              ncols=min(len(handles), 5), fontsize=LEGEND_PT, frameon=False)  # fmt: skip
    if title:
        ax.set_title(title, fontsize=TITLE_PT)
    return ax
