"""The picture of a world: free space, walls, clutter, roadmap, start, obstacles and tour.

``plot_world(world, *, tour=None, ax=None) -> Axes``; ``render_world_png`` and
``save_world_png`` give it as PNG. matplotlib is imported inside each function, so this
module imports without it (the optional ``viz`` extra).
"""

from __future__ import annotations

import math
import os
from typing import TYPE_CHECKING, Any

import numpy as np

from albot2d.atomic import atomic_write_bytes
from albot2d.viz._figure import figure_of, line_segments, new_figure, png_bytes

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from worldgen.world import Tour, World

__all__ = ["plot_world", "render_world_png", "save_world_png"]

FREE_SPACE_COLOR = "#f4f1e8"
WALL_COLOR = "#1a1a1a"
CLUTTER_COLOR = "#8c8c8c"
ROADMAP_COLOR = "#6fa8dc"
TOUR_COLOR = "#e06c00"
START_COLOR = "#2e7d32"
BOX_COLOR = "#a0522d"
PERSON_COLOR = "#7b1fa2"
DEFAULT_DPI = 120
# Figure size in inches along the world's longer side; the other side follows its aspect.
FIGURE_LONG_SIDE_IN = 9.0
FIGURE_SHORT_SIDE_MIN_IN = 3.5
PLOT_MARGIN_FRACTION = 0.02
DETAIL_SIZE_M = 80.0  # worlds larger than this get proportionally thinner lines


def _new_axes(world: World) -> Axes:
    w, h = max(world.width_m, 1e-9), max(world.height_m, 1e-9)
    scale = FIGURE_LONG_SIDE_IN / max(w, h)
    size = (max(w * scale, FIGURE_SHORT_SIDE_MIN_IN), max(h * scale, FIGURE_SHORT_SIDE_MIN_IN))
    return new_figure(size[0], size[1] + 1.0).add_subplot()


def _polygon_path(polygon: Any) -> Any:
    """A matplotlib Path of a shapely polygon with its holes left unfilled."""
    from matplotlib.path import Path
    from shapely.geometry.polygon import orient

    # Holes wind opposite to the exterior, so the nonzero fill rule leaves them empty.
    polygon = orient(polygon, sign=1.0)
    vertices, codes = [], []
    for ring in [polygon.exterior, *polygon.interiors]:
        coords = np.asarray(ring.coords, dtype=np.float64)
        vertices.append(coords)
        ring_codes = np.full(len(coords), Path.LINETO, dtype=Path.code_type)
        ring_codes[0], ring_codes[-1] = Path.MOVETO, Path.CLOSEPOLY
        codes.append(ring_codes)
    return Path(np.vstack(vertices), np.concatenate(codes))


def _nice_length(span_m: float) -> float:
    """A round scale-bar length (1, 2 or 5 × 10^k) near a fifth of ``span_m``."""
    target = span_m / 5.0
    power = 10.0 ** math.floor(math.log10(target))
    return max(m * power for m in (1.0, 2.0, 5.0) if m * power <= target)


def _draw_scale_bar(ax: Axes, world: World) -> None:
    from mpl_toolkits.axes_grid1.anchored_artists import AnchoredSizeBar

    length = _nice_length(world.width_m)
    label = f"{length:g} m"
    bar = AnchoredSizeBar(
        ax.transData, length, label, loc="lower right", pad=0.4, borderpad=0.6,
        sep=3, frameon=True, size_vertical=world.height_m / 200.0,
    )  # fmt: skip
    bar.patch.set_alpha(0.8)
    ax.add_artist(bar)


def _draw_obstacles(ax: Axes, world: World) -> None:
    from matplotlib.patches import Polygon as PolygonPatch

    for ob in world.dynamic_obstacles:
        outline = ob.pose.transform_points(ob.shape)
        color = BOX_COLOR if ob.kind == "box" else PERSON_COLOR
        ax.add_patch(PolygonPatch(outline, closed=True, facecolor=color, alpha=0.8, zorder=4))
        if len(ob.path) > 1:
            ax.plot(*ob.path.T, color=color, lw=1.0, ls="--", zorder=4)


def plot_world(
    world: World,
    *,
    tour: Tour | None = None,
    ax: Axes | None = None,
    show_roadmap: bool = True,
) -> Axes:
    """Draw ``world`` (free space, walls, clutter, roadmap, start, obstacles, ``tour``) on ``ax``.

    With no ``ax`` a new Agg figure is made (reach it as ``ax.figure``). The plot has equal
    aspect, a scale bar and a title with kind, seed and size.
    """
    from matplotlib.collections import LineCollection, PathCollection

    if ax is None:
        ax = _new_axes(world)
    ax.add_collection(
        PathCollection(
            [_polygon_path(world.free_space)],
            facecolors=FREE_SPACE_COLOR, edgecolors="none", zorder=0,
        )
    )  # fmt: skip
    if world.clutter:
        ax.add_collection(
            PathCollection(
                [_polygon_path(p) for p in world.clutter],
                facecolors=CLUTTER_COLOR, edgecolors="#555555", linewidths=0.5, zorder=2,
            )
        )  # fmt: skip
    # Thinner lines and smaller dots in big worlds, so detail does not drown in ink.
    thin = min(1.0, DETAIL_SIZE_M / max(world.width_m, world.height_m))
    walls = line_segments(world.walls)
    ax.add_collection(
        LineCollection(walls, colors=WALL_COLOR, linewidths=max(0.4, 1.2 * thin), zorder=3)
    )
    if show_roadmap and len(world.roadmap.nodes):
        nodes = world.roadmap.nodes
        edges = line_segments(nodes[world.roadmap.edges])
        ax.add_collection(
            LineCollection(edges, colors=ROADMAP_COLOR, linewidths=0.6 * thin, alpha=0.7, zorder=1)
        )
        ax.plot(*nodes.T, ".", color=ROADMAP_COLOR, ms=2.5 * thin, zorder=1)
    _draw_obstacles(ax, world)
    if tour is not None and len(tour.waypoints):
        ax.plot(*tour.waypoints.T, "-", color=TOUR_COLOR, lw=1.6, zorder=5, label="tour")
        ax.plot(*tour.waypoints[-1], "s", color=TOUR_COLOR, ms=5, zorder=5)
    _draw_start(ax, world)
    # A small margin keeps walls on the world's bounds clear of the axes frame.
    margin = PLOT_MARGIN_FRACTION * max(world.width_m, world.height_m)
    ax.set_xlim(world.bounds[0] - margin, world.bounds[2] + margin)
    ax.set_ylim(world.bounds[1] - margin, world.bounds[3] + margin)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    _draw_scale_bar(ax, world)
    _draw_legend(ax, world, tour, show_roadmap)
    seed = "none" if world.seed is None else str(world.seed)
    title = f"{world.kind}  seed {seed}  {world.width_m:.1f} × {world.height_m:.1f} m"
    if tour is not None:
        title += f"  tour {tour.kind} {tour.length_m:.0f} m"
    ax.set_title(title)
    return ax


def _draw_start(ax: Axes, world: World) -> None:
    from matplotlib.patches import Circle, FancyArrow

    start = world.start
    # The arrow spans a few robot radii but stays visible in large worlds.
    length = max(4.0 * world.robot_radius_m, max(world.width_m, world.height_m) / 30.0)
    ax.add_patch(
        Circle((start.x, start.y), world.robot_radius_m, color=START_COLOR, alpha=0.5, zorder=6)
    )
    ax.add_patch(
        FancyArrow(
            start.x, start.y, length * math.cos(start.theta), length * math.sin(start.theta),
            width=length / 12.0, head_width=length / 3.0, head_length=length / 3.0,
            length_includes_head=True, color=START_COLOR, zorder=6,
        )
    )  # fmt: skip


def _draw_legend(ax: Axes, world: World, tour: Tour | None, show_roadmap: bool) -> None:
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    handles = [
        Patch(facecolor=FREE_SPACE_COLOR, edgecolor="#bbbbbb", label="free space"),
        Line2D([], [], color=WALL_COLOR, lw=1.2, label="walls"),
    ]
    if world.clutter:
        handles.append(Patch(facecolor=CLUTTER_COLOR, label="clutter"))
    if show_roadmap and len(world.roadmap.nodes):
        handles.append(Line2D([], [], color=ROADMAP_COLOR, marker=".", label="roadmap"))
    kinds = {ob.kind for ob in world.dynamic_obstacles}
    if "box" in kinds:
        handles.append(Patch(facecolor=BOX_COLOR, label="movable box"))
    if "person" in kinds:
        handles.append(Line2D([], [], color=PERSON_COLOR, ls="--", marker="s", label="person"))
    if tour is not None:
        handles.append(Line2D([], [], color=TOUR_COLOR, lw=1.6, label="tour"))
    handles.append(Line2D([], [], color=START_COLOR, marker=">", ls="", label="start"))
    ax.legend(
        handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.12),
        ncol=min(len(handles), 8), fontsize=8, frameon=False,
    )  # fmt: skip


def render_world_png(world: World, *, tour: Tour | None = None, dpi: int = DEFAULT_DPI) -> bytes:
    """The world picture (see ``plot_world``) as PNG bytes, made in memory."""
    ax = plot_world(world, tour=tour)
    return png_bytes(figure_of(ax), dpi)


def save_world_png(
    world: World,
    path: str | os.PathLike[str],
    *,
    tour: Tour | None = None,
    dpi: int = DEFAULT_DPI,
) -> None:
    """Write the world picture to ``path`` as PNG, atomically (no partial file on failure)."""
    atomic_write_bytes(path, render_world_png(world, tour=tour, dpi=dpi))
