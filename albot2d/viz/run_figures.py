"""The figures of an experiment (``albot2d run``/``replay``) (the optional ``viz`` extra).

- ``plot_homing(stops, *, fig=None) -> Figure``: homing errors (or, on real logs,
  estimates) at each stop; a figure-level composite (two panels).
- ``plot_estimated_paths(result, *, ax=None) -> Axes``: raw odometry and every mapper's
  estimated path in the first pose's frame (logs without ground truth).
- ``plot_errors_vs_distance(result, *, fig=None) -> Figure``: heading and position error of
  every mapper and of raw odometry against the distance travelled (simulation); a
  figure-level composite (two panels).
- ``render_experiment_figures``: every PNG of ``albot2d run``/``replay``, made in memory,
  from these and the map pictures of ``albot2d.viz.maps``.

Paths carry arrow heads in the direction driven; maps a colour bar (view id, old → new)
and a legend.

matplotlib is imported inside the functions; figures use the Agg canvas directly.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from albot2d.geometry import transform_segments
from albot2d.mapping.protocol import ViewBasedMapper
from albot2d.viz._figure import figure_batch, new_figure, png_bytes
from albot2d.viz.furniture import (
    LABEL_PT,
    TITLE_PT,
    axes_colorbar,
    count_text,
    draw_map_furniture,
    legend_below,
    set_figure_counts,
)
from albot2d.viz.maps import (
    PANEL_IN,
    START_COLOR,
    Extent,
    anchor_path,
    anchor_segments,
    extent_of,
    map_surfaces,
    plot_map,
    plot_route,
    set_extent,
)

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.collections import LineCollection
    from matplotlib.figure import Figure

    from albot2d.evaluation.run.experiment import ExperimentResult
    from albot2d.evaluation.run.results import HomingStop

__all__ = [
    "error_curves",
    "mapper_extent",
    "plot_errors_vs_distance",
    "plot_estimated_paths",
    "plot_homing",
    "render_experiment_figures",
]

FloatArray = NDArray[np.float64]
ODOM_COLOR = "#9e9e9e"
DEFAULT_DPI = 100
# The paper's Table 1: Albot1 oriented within ±7° and ±3 m after about 100 m.
PAPER_BEARING_DEG = 7.0
PAPER_DISTANCE_M = 3.0


def plot_homing(stops: Mapping[str, Sequence[HomingStop]], *, fig: Figure | None = None) -> Figure:
    """Homing at each stop against odometer distance: errors when the truth is known
    (with the paper's ±7° / ±3 m band), else each mapper's estimates. Two panels on
    ``fig`` (a new figure when None); returns the figure."""
    if fig is None:
        fig = new_figure(11.0, 4.5)
    entries = {name: list(rows) for name, rows in stops.items()}
    with_truth = any(e and e[0].homing.bearing_error_deg is not None for e in entries.values())
    ax_b, ax_d = fig.subplots(1, 2)
    if with_truth:
        keys = ("bearing_error_deg", "distance_error_m")
        labels = ("bearing error to start (deg, + = too far left)", "distance error to start (m)")
        for ax, band, unit in ((ax_b, PAPER_BEARING_DEG, "°"), (ax_d, PAPER_DISTANCE_M, " m")):
            ax.axhspan(
                -band,
                band,
                color="#c8e6c9",
                alpha=0.6,
                zorder=0,
                label=f"paper's Albot₁ (±{band:g}{unit})",
            )
            ax.axhline(0.0, color="#616161", lw=0.8)
    else:
        keys = ("bearing_est_deg", "distance_est_m")
        labels = ("estimated bearing to start (deg, + = left)", "estimated distance to start (m)")
    for name, rows in entries.items():
        if not rows:
            continue
        x = [r.travelled_m for r in rows]
        for ax, key in zip((ax_b, ax_d), keys, strict=True):
            ax.plot(x, [getattr(r.homing, key) for r in rows], "o-", ms=4, lw=1.2, label=name)
    for ax, label in zip((ax_b, ax_d), labels, strict=True):
        ax.set_xlabel("distance travelled (odometer, m)")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=8)
    if not any(entries.values()):
        ax_b.set_title("no homing stops (the run never got far from its start)", fontsize=10)
    fig.suptitle(
        "Orientation to the start at each stop: error against the truth (paper Table 1)"
        if with_truth
        else "Orientation to the start at each stop: estimates (no ground truth)"
    )
    return fig


def plot_estimated_paths(result: ExperimentResult, *, ax: Axes | None = None) -> Axes:
    """Raw odometry and every mapper's estimated path, all in the first pose's frame
    (for logs without ground truth), on ``ax`` (a new figure when None); returns the axes."""
    from matplotlib import colormaps

    from albot2d.geometry import between_arrays
    from albot2d.viz.paths import draw_direction_arrows

    if ax is None:
        ax = new_figure(8.0, 7.0).add_subplot()

    trace = result.trace
    odom = between_arrays(trace.odom_poses[0], trace.odom_poses)
    # Odometry is drawn wide and light underneath: a mapper that follows it (naive
    # integration does exactly) is drawn on top and said to be identical.
    ax.plot(
        *odom[:, :2].T, "-", color=ODOM_COLOR, lw=4.0, alpha=0.6, zorder=2, label="raw odometry"
    )
    parts = [odom[:, :2]]
    tab10 = colormaps["tab10"]  # 10 listed colours: tab10(k) is the k-th
    styles = ["-", "--", "-.", ":"]
    for k, (name, mapper) in enumerate(trace.mappers.items()):
        est = np.asarray(mapper.trajectory(), np.float64).reshape(-1, 3)
        same = est.shape == odom.shape and np.allclose(est[:, :2], odom[:, :2], atol=1e-6)
        color = tab10(k % tab10.N)
        ax.plot(
            *est[:, :2].T,
            styles[k % len(styles)],
            color=color,
            lw=1.2,
            zorder=3 + k,
            label=f"{name} (= odometry)" if same else name,
        )
        draw_direction_arrows(ax, est, color=color, count=8, size=9.0, zorder=3 + k)
        parts.append(est[:, :2])
    ax.plot(0.0, 0.0, "*", color=START_COLOR, ms=12, zorder=10, label="start")
    set_extent(ax, extent_of(parts))
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.legend(fontsize=8, loc="best", framealpha=0.8)
    ax.set_title(f"{result.title}\nestimated paths (→ direction; first pose's frame)", fontsize=10)
    return ax


# -- the figures of a run --------------------------------------------------------------
def _grid(n: int) -> tuple[int, int]:
    cols = n if n <= 3 else 2 if n == 4 else 3
    return (n + cols - 1) // cols, cols


def _panel_size(result: ExperimentResult, extent: Extent | None) -> tuple[float, float]:
    if extent is None:
        return PANEL_IN, PANEL_IN
    w, h = extent[2] - extent[0], extent[3] - extent[1]
    aspect = min(max(h / max(w, 1e-9), 0.4), 2.5)
    return PANEL_IN, PANEL_IN * aspect + 0.6


def _map_panel(
    ax: Axes,
    result: ExperimentResult,
    name: str,
    row: int | None = None,
    update: int | None = None,
    extent: Extent | None = None,
    title: str | None = None,
    id_range: tuple[int, int] | None = None,
) -> LineCollection:
    trace = result.trace
    mapper = trace.mappers[name]
    if update is None:
        snap = mapper.global_map()
    elif isinstance(mapper, ViewBasedMapper):  # the history panels: mappers with a route map
        snap = mapper.global_map(at_update=update)
    else:
        raise TypeError(f"mapper {name!r} keeps no map history (asked for update {update})")
    end = trace.n_frames if row is None else row + 1
    est = np.asarray(mapper.trajectory(), np.float64).reshape(-1, 3)[:end]
    start = None if trace.true_poses is None else trace.true_poses[0]
    true_path = None if trace.true_poses is None else trace.true_poses[:end]
    counts = {
        "views": end,
        "local_maps": int(mapper.counts().local_maps if update is None else update),
        "surfaces": len(snap.segments),
        "local_maps_in_map": len(np.unique(snap.map_ids)),
    }
    fig = ax.get_figure(root=True)
    if fig is not None:
        set_figure_counts(fig, name if update is None else f"{name}@{end - 1}", counts)
    default = f"{name}: " + map_count_text(counts)
    plot_map(
        snap.segments,
        map_ids=snap.map_ids,
        ax=ax,
        world=result.world,
        start_pose=start,
        est_path=est,
        true_path=true_path,
        extent=extent,
        title=title or default,
        id_range=id_range,
    )
    ax.set_title(ax.get_title(), fontsize=TITLE_PT)
    draw_map_furniture(ax, _drawn_points(ax))
    return map_surfaces(ax)


def map_count_text(counts: dict[str, int]) -> str:
    """A map's counts in words (the terms of ``albot2d.viz.furniture``), two lines."""
    return (
        f"{count_text(counts['views'], 'views')} → "
        f"{count_text(counts['local_maps'], 'local_maps')}\n"
        f"global map: {count_text(counts['surfaces'], 'surfaces')} from "
        f"{counts['local_maps_in_map']} of its local maps"
    )


def _drawn_points(ax: Axes) -> FloatArray:
    """Vertices of the lines drawn on ``ax`` (to find an empty corner)."""
    parts = [np.asarray(line.get_xydata(), np.float64).reshape(-1, 2) for line in ax.lines]
    for coll in ax.collections:
        for path in coll.get_paths()[:2000]:
            parts.append(np.asarray(path.vertices, np.float64)[::4])
    return np.vstack(parts) if parts else np.zeros((0, 2))


def _paths_panel(ax: Axes, result: ExperimentResult, extent: Extent | None) -> None:
    trace = result.trace
    if result.world is not None and trace.true_poses is not None:
        from albot2d.viz.paths import plot_paths

        plot_paths(
            result.world,
            true_xy=trace.true_poses,
            odom_xy=trace.odom_poses,
            collided=trace.collided,
            ax=ax,
        )
        legend = ax.get_legend()
        assert legend is not None  # plot_paths always draws one
        keep = [
            h
            for h in legend.legend_handles
            if h is not None
            and str(h.get_label())
            in ("walls", "true path (→ direction, ● end)", "odometry", "collision", "start")
        ]
        legend.remove()
        ax.set_title("world, true path and odometry", fontsize=TITLE_PT)
        set_extent(ax, extent)
        for artist in list(ax.artists):  # plot_world's scale bar: drawn again below
            artist.remove()
        draw_map_furniture(ax, _drawn_points(ax))
        ax.__dict__["_albot2d_legend"] = keep
    else:
        plot_estimated_paths(result, ax=ax)
        ax.set_title("odometry and estimated paths (first pose's frame)", fontsize=10)


def mapper_extent(result: ExperimentResult, name: str) -> Extent | None:
    """The extent that holds everything of mapper ``name`` over the run: its estimated
    path, final map, every remembered view, the true path and the world."""
    from albot2d.evaluation.run.scoring import route_of

    trace, mapper = result.trace, result.trace.mappers[name]
    start = None if trace.true_poses is None else trace.true_poses[0]
    est = anchor_path(start, np.asarray(mapper.trajectory(), np.float64).reshape(-1, 3))
    parts = [est[:, :2], anchor_segments(start, mapper.global_map().segments).reshape(-1, 2)]
    route = route_of(mapper)
    if route is not None and len(route):
        # Every remembered view, so the history panels (earlier maps) fit too.
        chain = anchor_path(start, route.compose_chain())
        parts.append(chain[:, :2])
        parts += [
            transform_segments(p, m.view.segments).reshape(-1, 2)
            for p, m in zip(chain, route, strict=True)
        ]
    if trace.true_poses is not None:
        parts.append(trace.true_poses[:, :2])
    if result.world is not None:
        b = result.world.bounds
        parts.append(np.array([[b[0], b[1]], [b[2], b[3]]]))
    return extent_of(parts)


COLOUR_LABEL = "local map it came from (old → new)"


def _colorbar(fig: Figure, lines: LineCollection, ax: Axes) -> None:
    if lines.get_array() is not None:
        axes_colorbar(fig, lines, ax, COLOUR_LABEL)


def _legend_handles(*axes: Axes) -> list[Any]:
    """The legend entries of ``axes`` (and the paths panel's kept ones), one per label."""
    seen: dict[str, Any] = {}
    for ax in axes:
        handles = ax.__dict__.get("_albot2d_legend") or ax.get_legend_handles_labels()[0]
        for h in handles:
            label = str(h.get_label())
            if label and not label.startswith("_"):
                seen.setdefault(label, h)
    return list(seen.values())


def _stored(fig: Figure, name: str, row: int) -> dict[str, Any]:
    from albot2d.viz.furniture import figure_counts

    return dict(figure_counts(fig).get(f"{name}@{row}", {}))


def error_curves(result: ExperimentResult) -> dict[str, tuple[FloatArray, FloatArray]]:
    """Per mapper and ``odometry``: (position error m, heading error deg) at every view,
    each trajectory anchored at the true start pose (needs the truth)."""
    from albot2d.evaluation.metrics.alignment import in_world_frame
    from albot2d.geometry import between_arrays, wrap_angle

    trace = result.trace
    truth = trace.true_poses
    assert truth is not None
    odom = between_arrays(trace.odom_poses[0], trace.odom_poses)
    paths = {"odometry": odom}
    for name, mapper in trace.mappers.items():
        paths[name] = np.asarray(mapper.trajectory(), np.float64).reshape(-1, 3)
    out = {}
    for name, poses in paths.items():
        world = in_world_frame(poses, truth[0])
        position = np.hypot(*(world[:, :2] - truth[:, :2]).T)
        heading = np.degrees(np.asarray(wrap_angle(world[:, 2] - truth[:, 2])))
        out[name] = (position, heading)
    return out


def plot_errors_vs_distance(result: ExperimentResult, *, fig: Figure | None = None) -> Figure:
    """Heading error and position error of every mapper and raw odometry against the
    true distance travelled, each trajectory anchored at the true start (simulation).
    Two panels on ``fig`` (a new figure when None); returns the figure."""
    if fig is None:
        fig = new_figure(11.0, 7.5)
    trace = result.trace
    truth = trace.true_poses
    assert truth is not None
    travelled = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(truth[:, :2], axis=0).T))])
    ax_h, ax_p = fig.subplots(2, 1, sharex=True)
    curves = error_curves(result)
    odometry = curves["odometry"]
    for name, (position, heading) in curves.items():
        if name == "odometry":  # wide and light underneath, so a mapper equal to it shows
            style: dict[str, Any] = {"color": ODOM_COLOR, "lw": 4.0, "alpha": 0.6, "zorder": 2}
            label = "raw odometry"
        else:
            style = {"lw": 1.2, "zorder": 3}
            same = np.allclose(position, odometry[0], atol=1e-6)
            label = f"{name} (= odometry)" if same else name
        ax_h.plot(travelled, heading, label=label, **style)
        ax_p.plot(travelled, position, label=label, **style)
    ax_h.axhline(0.0, color="#616161", lw=0.8)
    ax_h.set_ylabel("heading error (deg, + = turned too far left)")
    ax_p.set_ylabel("position error (m)")
    ax_p.set_xlabel("distance travelled (true, m)")
    for ax in (ax_h, ax_p):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper left")
    fig.suptitle(
        f"{result.title}\nerror of each pose estimate against the truth (every "
        "trajectory starts at the true start pose, no alignment)",
        fontsize=9,
    )
    return fig


def render_experiment_figures(
    result: ExperimentResult, *, dpi: int = DEFAULT_DPI
) -> dict[str, bytes]:
    """Every figure of a run or replay, as ``{file name: PNG bytes}``."""
    with figure_batch():
        return _render_all(result, dpi)


def _render_all(result: ExperimentResult, dpi: int) -> dict[str, bytes]:
    from albot2d.evaluation.run.scoring import route_of

    out: dict[str, bytes] = {}
    trace, names = result.trace, list(result.trace.mappers)
    if result.world is not None and trace.true_poses is not None:
        from albot2d.viz.paths import render_paths_png

        out["paths.png"] = render_paths_png(
            result.world,
            true_xy=trace.true_poses,
            odom_xy=trace.odom_poses,
            collided=trace.collided,
            title=result.title,
        )
    else:
        fig = new_figure(8.0, 7.0)
        plot_estimated_paths(result, ax=fig.subplots())
        out["paths.png"] = png_bytes(fig, dpi)
    # Overview: the paths, then every mapper's final map, side by side on one scale.
    rows, cols = _grid(len(names) + 1)
    extents = [mapper_extent(result, n) for n in names]
    extent = extent_of([np.array([[e[0], e[1]], [e[2], e[3]]]) for e in extents if e])
    pw, ph = _panel_size(result, extent)
    fig = new_figure(pw * cols, ph * rows + 0.5, layout="compressed")
    axes = np.atleast_1d(fig.subplots(rows, cols)).ravel()
    _paths_panel(axes[0], result, extent)
    for ax, name in zip(axes[1:], names, strict=False):
        _colorbar(fig, _map_panel(ax, result, name, extent=extent), ax)
    for ax in axes[len(names) + 1 :]:
        ax.set_visible(False)
    legend_below(fig, _legend_handles(*axes[: len(names) + 1]))
    fig.suptitle(result.title, fontsize=TITLE_PT + 1)
    out["maps.png"] = png_bytes(fig, dpi)
    if trace.true_poses is not None:
        fig = plot_errors_vs_distance(result, fig=new_figure(11.0, 7.5))
        out["errors.png"] = png_bytes(fig, dpi)
    for name, ext in zip(names, extents, strict=True):
        pw, ph = _panel_size(result, ext)
        fig = new_figure(pw * 1.6, ph * 1.6)
        ax = fig.subplots()
        _colorbar(fig, _map_panel(ax, result, name, extent=ext), ax)
        legend_below(fig, _legend_handles(ax))
        fig.suptitle(result.title, fontsize=TITLE_PT)
        out[f"{name}_map.png"] = png_bytes(fig, dpi)
        route = route_of(trace.mappers[name])
        if route is None:
            continue
        snaps = result.scores.mappers[name].snapshots or ()
        rows, cols = _grid(len(snaps))
        fig = new_figure(pw * cols, ph * rows + 0.5, layout="compressed")
        axes = np.atleast_1d(fig.subplots(rows, cols)).ravel()
        id_range = (0, max(len(route) - 1, 1))
        lines = None
        for ax, snap in zip(axes, snaps, strict=False):
            counts = {"views": snap.row + 1, "local_maps": snap.update,
                      "surfaces": snap.surfaces}  # fmt: skip
            title = (
                f"view {snap.view}, {snap.travelled_m:.0f} m driven\n"
                f"{count_text(snap.update, 'local_maps')}, "
                f"{count_text(snap.surfaces, 'surfaces')} in the map"
            )
            lines = _map_panel(
                ax, result, name, row=snap.row, update=snap.update, extent=ext, title=title,
                id_range=id_range,
            )  # fmt: skip
            set_figure_counts(fig, f"{name}@{snap.row}", counts | _stored(fig, name, snap.row))
        for ax in axes[len(snaps) :]:
            ax.set_visible(False)
        if lines is not None and lines.get_array() is not None:
            bar = fig.colorbar(lines, ax=list(axes[: len(snaps)]), location="right",
                               shrink=0.6, aspect=30)  # fmt: skip
            bar.set_label(COLOUR_LABEL, fontsize=LABEL_PT)
        legend_below(fig, _legend_handles(*axes[: len(snaps)]))
        fig.suptitle(
            f"{name}'s global map as it evolves (transient: surfaces of old local maps are "
            "deleted)", fontsize=TITLE_PT + 1,
        )  # fmt: skip
        out[f"{name}_history.png"] = png_bytes(fig, dpi)
        fig = new_figure(pw * 1.6, ph * 1.6)
        start = None if trace.true_poses is None else trace.true_poses[0]
        plot_route(
            route,
            ax=fig.subplots(),
            world=result.world,
            start_pose=start,
            true_path=trace.true_poses,
            title=f"{name}'s route map: {count_text(len(route), 'local_maps')} "
            f"(remembered views) of {count_text(trace.n_frames, 'views')}",
        )
        set_figure_counts(fig, name, {"views": trace.n_frames, "local_maps": len(route)})
        out[f"{name}_route.png"] = png_bytes(fig, dpi)
    homing = {name: scores.homing for name, scores in result.scores.mappers.items()}
    fig = plot_homing(homing, fig=new_figure(11.0, 4.5))
    out["homing.png"] = png_bytes(fig, dpi)
    return out
