"""A run's paths over its world: the true path, odometry, collisions and direction arrows.

``plot_paths(world, *, true_xy, odom_xy, collided=None, ax=None) -> Axes`` draws them over
``plot_world``; ``render_paths_png`` gives the picture as PNG bytes;
``draw_direction_arrows`` puts arrow heads along any path (used by the map figures too).
matplotlib is imported inside each function (the optional ``viz`` extra).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from albot2d.viz._figure import figure_of, png_bytes
from albot2d.viz.world import DEFAULT_DPI, PLOT_MARGIN_FRACTION, plot_world

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.typing import ColorType

    from worldgen.world import World

__all__ = ["draw_direction_arrows", "plot_paths", "render_paths_png"]

TRUE_PATH_COLOR = "#1565c0"
ODOM_PATH_COLOR = "#d32f2f"
COLLISION_COLOR = "#ff6f00"


def _xy(points: Any) -> np.ndarray:
    arr = np.asarray(points, dtype=np.float64)
    return arr[:, :2] if arr.ndim == 2 and arr.shape[1] >= 2 else arr.reshape(0, 2)


def draw_direction_arrows(
    ax: Axes, points: Any, *, color: ColorType, count: int = 10, size: float = 11.0, zorder: int = 8
) -> None:
    """Arrow heads at ``count`` evenly spaced places along a path (``(N, 2+)`` points),
    pointing the way it was driven."""
    xy = _xy(points)
    if len(xy) < 2:
        return
    along = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))])
    total = float(along[-1])
    if total <= 0.0:
        return
    at = (np.arange(count) + 0.5) * total / count
    back = np.maximum(at - total / (8.0 * count), 0.0)
    heads = np.column_stack([np.interp(at, along, xy[:, 0]), np.interp(at, along, xy[:, 1])])
    tails = np.column_stack([np.interp(back, along, xy[:, 0]), np.interp(back, along, xy[:, 1])])
    for head, tail in zip(heads, tails, strict=True):
        if np.allclose(head, tail):
            continue
        ax.annotate(
            "",
            xy=tuple(head),
            xytext=tuple(tail),
            zorder=zorder,
            annotation_clip=True,
            arrowprops={
                "arrowstyle": "-|>",
                "color": color,
                "lw": 0.0,
                "mutation_scale": size,
                "shrinkA": 0.0,
                "shrinkB": 0.0,
            },
        )


def plot_paths(
    world: World,
    *,
    true_xy: Any,
    odom_xy: Any,
    collided: Any = None,
    title: str | None = None,
    ax: Axes | None = None,
) -> Axes:
    """Draw ``world`` with a run's true path and odometry path (``(N, 2)`` or ``(N, 3)``
    arrays; only x, y are used). ``collided`` (``(N,)`` bool) marks frames whose motion was
    blocked. The world's own legend entries are kept and the paths added to them."""
    from matplotlib.lines import Line2D

    true_xy, odom_xy = _xy(true_xy), _xy(odom_xy)
    ax = plot_world(world, ax=ax, show_roadmap=False)
    old = ax.get_legend()
    handles = list(old.legend_handles) if old is not None else []
    if len(true_xy):
        ax.plot(*true_xy.T, "-", color=TRUE_PATH_COLOR, lw=1.4, zorder=7)
        ax.plot(*true_xy[-1], "o", color=TRUE_PATH_COLOR, ms=5, zorder=7)
        draw_direction_arrows(ax, true_xy, color=TRUE_PATH_COLOR)
    if len(odom_xy):
        ax.plot(*odom_xy.T, "--", color=ODOM_PATH_COLOR, lw=1.2, zorder=7)
        ax.plot(*odom_xy[-1], "o", color=ODOM_PATH_COLOR, ms=5, zorder=7)
        draw_direction_arrows(ax, odom_xy, color=ODOM_PATH_COLOR)
    handles.append(
        Line2D(
            [],
            [],
            color=TRUE_PATH_COLOR,
            lw=1.4,
            marker=">",
            label="true path (→ direction, ● end)",
        )
    )
    handles.append(
        Line2D([], [], color=ODOM_PATH_COLOR, lw=1.2, ls="--", marker=">", label="odometry")
    )
    if collided is not None and len(true_xy):
        hits = true_xy[np.asarray(collided, dtype=bool)]
        if len(hits):
            ax.plot(*hits.T, "x", color=COLLISION_COLOR, ms=5, zorder=8)
            handles.append(
                Line2D([], [], color=COLLISION_COLOR, marker="x", ls="", label="collision")
            )
    # Odometry may drift outside the world: widen the view to keep it in the picture.
    both = np.vstack([true_xy, odom_xy]) if len(true_xy) + len(odom_xy) else np.zeros((0, 2))
    if len(both):
        (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
        margin = PLOT_MARGIN_FRACTION * max(world.width_m, world.height_m)
        ax.set_xlim(min(x0, both[:, 0].min() - margin), max(x1, both[:, 0].max() + margin))
        ax.set_ylim(min(y0, both[:, 1].min() - margin), max(y1, both[:, 1].max() + margin))
    ax.legend(
        handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.12),
        ncol=min(len(handles), 8), fontsize=8, frameon=False,
    )  # fmt: skip
    if title is not None:
        ax.set_title(title)
    return ax


def render_paths_png(
    world: World,
    *,
    true_xy: Any,
    odom_xy: Any,
    collided: Any = None,
    title: str | None = None,
    dpi: int = DEFAULT_DPI,
) -> bytes:
    """The paths picture (see ``plot_paths``) as PNG bytes, made in memory."""
    ax = plot_paths(world, true_xy=true_xy, odom_xy=odom_xy, collided=collided, title=title)
    return png_bytes(figure_of(ax), dpi)
