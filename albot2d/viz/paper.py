"""Figures of ``albot2d experiments`` (the paper's Figs. 7, 10–16, Table 1 and the counts).

Each function draws the plain data an experiment produced (``albot2d.evaluation.paper``):
single-panel plots are ``plot_x(data, *, ax=None) -> Axes`` (``plot_bars``,
``plot_homing``); multi-panel plots are figure-level composites
``plot_x(data, *, fig=None) -> Figure`` (``plot_maps``, ``plot_updates``,
``plot_sequence``). ``save_figure(spec, path)`` draws one figure spec
(``{"plot", "data", ...}``) to a PNG. matplotlib is imported lazily (``viz`` extra); the
figures use the Agg canvas directly (no pyplot, no global backend switch).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from albot2d.viz._figure import line_segments, new_figure
from albot2d.viz.furniture import LABEL_PT, LEGEND_PT, TICK_PT, TITLE_PT

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = [
    "PLOTS",
    "plot_bars",
    "plot_homing",
    "plot_maps",
    "plot_sequence",
    "plot_updates",
    "save_figure",
]

_REGION_COLOURS = {"corridor": "tab:blue", "hall": "tab:orange", "room": "tab:green",
                   "outside": "tab:grey"}  # fmt: skip
_METHOD_COLOURS = {"triangulation": "tab:blue", "path_integration": "tab:red", "": "0.5"}


def _panels(
    fig: Figure | None, n: int, ncols: int | None = None, size: float = 4.5
) -> tuple[Figure, list[Axes]]:  # (the map panels make their own compressed figure)
    """``n`` panels on ``fig`` (a new figure of ``size``-inch panels when None)."""
    ncols = ncols or n
    nrows = int(np.ceil(n / ncols))
    if fig is None:
        fig = new_figure(size * ncols, size * 0.75 * nrows, layout=None)
    return fig, list(np.ravel(fig.subplots(nrows, ncols, squeeze=False)))


def _axes(ax: Axes | None, size: float) -> Axes:
    return ax if ax is not None else new_figure(size, size * 0.75, layout=None).add_subplot()


def _tight(ax: Axes) -> None:
    fig = ax.get_figure(root=True)
    if fig is not None:
        fig.tight_layout()


def _segments(ax: Axes, segs: Any, **kw: Any) -> None:
    from matplotlib.collections import LineCollection

    s = np.asarray(segs, dtype=float).reshape(-1, 4)
    if len(s):
        ax.add_collection(LineCollection(line_segments(s), **kw))


def plot_maps(data: dict[str, Any], *, fig: Figure | None = None) -> Figure:
    """Map panels: faint true walls, the map (black), deleted surfaces (red), the true path
    so far (blue) and the named waypoints; a scale bar and the frame's axes on each, one
    legend below them all. Each panel's surface count is stored with the figure."""
    from matplotlib.lines import Line2D

    from albot2d.viz.furniture import (
        TITLE_PT,
        draw_map_furniture,
        legend_below,
        set_figure_counts,
    )

    panels = data["panels"]
    ncols = data.get("ncols") or max(1, len(panels))
    nrows = int(np.ceil(max(1, len(panels)) / ncols))
    if fig is None:
        fig = new_figure(4.6 * ncols, 3.7 * nrows + 0.5, layout="compressed")
    fig, axes = _panels(fig, max(1, len(panels)), ncols)
    deleted_any = False
    for a, p in zip(axes, panels, strict=False):
        _segments(a, p["walls"], colors="0.8", linewidths=0.6)
        if p.get("deleted") is not None:
            _segments(a, p["deleted"], colors="tab:red", linewidths=1.2)
            deleted_any = deleted_any or bool(np.size(p["deleted"]))
        _segments(a, p["segments"], colors="k", linewidths=0.8)
        path = np.asarray(p["path"], float).reshape(-1, 2)
        if len(path):
            a.plot(path[:, 0], path[:, 1], color="tab:blue", lw=0.8, alpha=0.6)
            a.plot(*path[-1], "o", color="tab:blue", ms=5)
        for name, (x, y) in (p.get("marks") or {}).items():
            if name != "X":
                a.annotate(name, (x, y), fontsize=7, color="tab:purple")
        walls = np.asarray(p["walls"], float).reshape(-1, 2)
        a.set_xlim(walls[:, 0].min() - 1, walls[:, 0].max() + 1)
        a.set_ylim(walls[:, 1].min() - 1, walls[:, 1].max() + 1)
        a.set_title(p["title"], fontsize=TITLE_PT - 1)
        segs = np.asarray(p["segments"], float).reshape(-1, 4)
        set_figure_counts(fig, p["title"], {"surfaces": len(segs)})
        walls = np.asarray(p["walls"], float).reshape(-1, 2)
        draw_map_furniture(a, np.vstack([segs.reshape(-1, 2), path, walls]))
    for a in axes[len(panels) :]:
        a.axis("off")
    handles = [
        Line2D([], [], color="0.8", lw=1.0, label="true walls"),
        Line2D([], [], color="k", lw=1.0, label="map surfaces (anchored at the true start)"),
        Line2D([], [], color="tab:blue", lw=1.0, marker="o", ms=4, label="true path, robot"),
    ]
    if deleted_any:
        handles.append(Line2D([], [], color="tab:red", lw=1.2, label="deleted surfaces"))
    legend_below(fig, handles)
    return fig


def plot_bars(data: dict[str, Any], *, ax: Axes | None = None) -> Axes:
    """Ours (mean ± sd) beside the paper's value, one pair of bars per label."""
    a = _axes(ax, size=6.0)
    bars = data["bars"]
    x = np.arange(len(bars))
    ours = [b["ours"] if b["ours"] is not None else np.nan for b in bars]
    sd = [b["sd"] or 0.0 for b in bars]
    paper = [b["paper"] if b["paper"] is not None else np.nan for b in bars]
    a.bar(x - 0.2, ours, 0.4, yerr=sd, label="albot2d", color="tab:blue", capsize=3)
    a.bar(x + 0.2, paper, 0.4, label="paper", color="white", edgecolor="k", hatch="//")
    a.set_xticks(x, [str(b["label"]).replace("_", " ") for b in bars], fontsize=TICK_PT)
    a.tick_params(axis="y", labelsize=TICK_PT)
    a.set_ylabel(data.get("ylabel", ""), fontsize=LABEL_PT)
    a.grid(True, axis="y", alpha=0.3)
    a.set_axisbelow(True)
    a.legend(handles=a.get_legend_handles_labels()[0],
             labels=["albot2d (mean, ± sd)", "paper"], fontsize=LEGEND_PT,
             loc="upper left", framealpha=0.9)  # fmt: skip
    _tight(a)
    return a


def plot_homing(data: dict[str, Any], *, ax: Axes | None = None) -> Axes:
    """Bearing error against distance error per stop, the bound as a box."""
    from matplotlib.patches import Rectangle

    a = _axes(ax, size=5.5)
    b_max, d_max = data["bound"]
    a.add_patch(Rectangle((-d_max, -b_max), 2 * d_max, 2 * b_max, fill=False, ls="--",
                          color="tab:green", label=f"±{b_max:g}° / ±{d_max:g} m"))  # fmt: skip
    d = np.asarray(data["distance_error_m"], float)
    b = np.asarray(data["bearing_error_deg"], float)
    direction = np.asarray(data["direction"])
    for name, marker in (("clockwise", "o"), ("anticlockwise", "^")):
        sel = direction == name
        if sel.any():
            a.plot(d[sel], b[sel], marker, ms=4, alpha=0.7, label=name)
    lim_d = max(d_max * 1.5, float(np.abs(d).max(initial=0.0)) * 1.1)
    lim_b = max(b_max * 1.5, float(np.abs(b).max(initial=0.0)) * 1.1)
    a.set_xlim(-lim_d, lim_d)
    a.set_ylim(-lim_b, lim_b)
    a.axhline(0.0, color="0.6", lw=0.6, zorder=0)
    a.axvline(0.0, color="0.6", lw=0.6, zorder=0)
    a.set_xlabel("distance error to S (m, + = too far)", fontsize=LABEL_PT)
    a.set_ylabel("bearing error to S (°, + = too far left)", fontsize=LABEL_PT)
    a.tick_params(labelsize=TICK_PT)
    a.set_title(f"{len(d)} stops; the box is the paper's bound", fontsize=TITLE_PT)
    a.legend(fontsize=LEGEND_PT, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncols=3,
             frameon=False)  # fmt: skip
    _tight(a)
    return a


def plot_updates(data: dict[str, Any], *, fig: Figure | None = None) -> Figure:
    """The route with every view, updates coloured by region kind, and moves per update."""
    from albot2d.viz.furniture import draw_map_furniture

    if fig is None:
        fig = new_figure(12.0, 4.8, layout="constrained")
    fig, axes = _panels(fig, 2, size=6.0)
    a, h = axes[0], axes[1]
    _segments(a, data["walls"], colors="0.8", linewidths=0.6)
    xy = np.asarray(data["xy"], float)
    flags = np.asarray(data["flags"], bool)
    regions = np.asarray(data["regions"])
    a.plot(xy[:, 0], xy[:, 1], ".", color="0.5", ms=3)
    for kind, colour in _REGION_COLOURS.items():
        sel = flags & (regions == kind)
        if sel.any():
            a.plot(xy[sel, 0], xy[sel, 1], "o", color=colour, ms=5, label=f"update in {kind}")
    a.plot([], [], ".", color="0.5", ms=3, label="view, no update")
    walls = np.asarray(data["walls"], float).reshape(-1, 2)
    a.set_xlim(walls[:, 0].min() - 1, walls[:, 0].max() + 1)
    a.set_ylim(walls[:, 1].min() - 1, walls[:, 1].max() + 1)
    draw_map_furniture(a, np.vstack([xy, walls]))
    a.legend(fontsize=LEGEND_PT, loc="upper center", bbox_to_anchor=(0.5, -0.14),
             ncols=4, frameon=False)  # fmt: skip
    a.set_title("every view (dot) and every global-map update, by region", fontsize=TITLE_PT)
    moved = np.r_[False, np.hypot(*np.diff(xy, axis=0).T) > 1e-6]
    last = 0
    per_kind: dict[str, list[int]] = {}
    for row in np.flatnonzero(flags):
        if row == 0:
            continue
        per_kind.setdefault(str(regions[row]), []).append(int(moved[last + 1 : row + 1].sum()))
        last = int(row)
    kinds = sorted(per_kind)
    bins = (np.arange(0, max((max(v) for v in per_kind.values()), default=1) + 2) - 0.5).tolist()
    h.hist([per_kind[k] for k in kinds], bins=bins, label=kinds,
           color=[_REGION_COLOURS.get(k, "k") for k in kinds])  # fmt: skip
    h.set_xlabel("moves (move or turn steps) since the previous update", fontsize=LABEL_PT)
    h.set_ylabel("updates", fontsize=LABEL_PT)
    from matplotlib.ticker import MaxNLocator

    h.xaxis.set_major_locator(MaxNLocator(integer=True))
    h.tick_params(labelsize=TICK_PT)
    h.set_title("moves per update, by region", fontsize=TITLE_PT)
    h.grid(True, axis="y", alpha=0.3)
    h.set_axisbelow(True)
    h.legend(fontsize=LEGEND_PT, loc="best")
    return fig


def plot_sequence(data: dict[str, Any], *, fig: Figure | None = None) -> Figure:
    """One panel per view of a sequence and the update method there. With ``views`` and
    ``maps`` (Fig. 15): top row the view's surfaces (robot at the origin facing +x),
    bottom row Albot₁'s global map after it (arrow: its pose in the map); otherwise the
    walls around the robot's true pose."""
    poses = np.asarray(data["poses"], float)
    n = len(poses)
    two_rows = data.get("views") is not None and data.get("maps") is not None
    if fig is None:
        fig = new_figure(2.6 * n + 0.6, (5.6 if two_rows else 3.0), layout="constrained")
    fig, panels = _panels(fig, 2 * n if two_rows else n, ncols=n, size=3.2)
    top, bottom = panels[:n], panels[n:]
    for k, (a, pose, row, method, tracked) in enumerate(zip(
        top, poses, data["rows"], data["methods"], data["tracked"], strict=False
    )):  # fmt: skip
        colour = _METHOD_COLOURS.get(method, "k")
        label = method.replace("_", " ") if method else "no update"
        if two_rows:
            _segments(a, data["views"][k], colors="k", linewidths=1.0)
            a.plot([0.0], [0.0], marker=">", color=colour, markersize=9)
            a.set_xlim(-4, 8)
            a.set_ylim(-6, 6)
        else:
            _segments(a, data["walls"], colors="0.6", linewidths=0.7)
            a.arrow(pose[0], pose[1], 0.8 * np.cos(pose[2]), 0.8 * np.sin(pose[2]),
                    width=0.08, color=colour)  # fmt: skip
            a.set_xlim(pose[0] - 6, pose[0] + 6)
            a.set_ylim(pose[1] - 6, pose[1] + 6)
        a.set_aspect("equal")
        a.set_title(f"view {row}: {label}\n{tracked} tracked surfaces", fontsize=TITLE_PT - 1,
                    color=colour)  # fmt: skip
        a.tick_params(labelsize=TICK_PT - 1)
        if k == 0:
            a.set_ylabel("the view, robot frame:\ny (m)" if two_rows else "y (m)",
                         fontsize=LABEL_PT)  # fmt: skip
        a.set_xlabel("x (m)", fontsize=LABEL_PT - 1)
    for k, a in enumerate(bottom):
        segs = np.asarray(data["maps"][k], float).reshape(-1, 4)
        mp = np.asarray(data["map_poses"][k], float)
        _segments(a, segs, colors="k", linewidths=0.8)
        a.arrow(mp[0], mp[1], 0.8 * np.cos(mp[2]), 0.8 * np.sin(mp[2]), width=0.08,
                color=_METHOD_COLOURS.get(data["methods"][k], "k"))  # fmt: skip
        a.set_xlim(mp[0] - 8, mp[0] + 8)
        a.set_ylim(mp[1] - 8, mp[1] + 8)
        a.set_aspect("equal")
        a.set_title(f"global map after view {data['rows'][k]}", fontsize=TITLE_PT - 1)
        a.tick_params(labelsize=TICK_PT - 1)
        if k == 0:
            a.set_ylabel("Albot₁'s global map,\nmap frame: y (m)", fontsize=LABEL_PT)
        a.set_xlabel("x (m)", fontsize=LABEL_PT - 1)
    return fig


PLOTS: dict[str, Callable[[dict[str, Any]], Axes | Figure]] = {
    "maps": plot_maps, "bars": plot_bars, "homing": plot_homing,
    "updates": plot_updates, "sequence": plot_sequence,
}  # fmt: skip


def save_figure(spec: dict[str, Any], path: Path, *, dpi: float = 110) -> None:
    """Draw the figure ``spec`` (``{"plot", "data"}``) to the PNG ``path``."""
    from matplotlib.figure import Figure

    drawn = PLOTS[spec["plot"]](spec["data"])
    fig = drawn if isinstance(drawn, Figure) else drawn.get_figure(root=True)
    assert fig is not None  # the axes were made on a new figure above
    from albot2d.viz.furniture import png_metadata

    fig.savefig(path, dpi=dpi, metadata=png_metadata(fig), bbox_inches="tight",
                pad_inches=0.08)  # fmt: skip
