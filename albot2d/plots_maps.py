"""Pictures of mappers' maps and of the experiment's results (the optional ``viz`` extra).

- ``plot_map``: a global map, surfaces coloured by the local map (view) they came from,
  with the mapper's estimated path; in simulation drawn over the faint true walls, anchored
  at the true start pose (as the paper plots S in its original position), so drift shows.
- ``plot_route``: Albot1's route map as its chain of remembered views (viewpoints coloured
  by how each was localised, the views' surfaces faint).
- ``plot_homing``: homing errors (or, on real logs, estimates) at each stop.
- ``plot_errors_vs_distance``: heading and position error of every mapper and of raw
  odometry against the distance travelled (simulation).
- ``render_experiment_figures``: every PNG of ``albot2d run``/``replay``, made in memory.

Paths carry arrow heads in the direction driven; maps a colour bar (view id, old → new)
and a legend.

matplotlib is imported inside the functions; figures use the Agg canvas directly.
"""

from __future__ import annotations

import io
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from albot2d.geometry import compose_arrays, transform_segments

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from albot2d.evaluation.experiment import ExperimentResult
    from albot2d.mapping.route_map import RouteMap
    from worldgen.world import World

__all__ = [
    "plot_errors_vs_distance",
    "plot_estimated_paths",
    "plot_homing",
    "plot_map",
    "plot_route",
    "render_experiment_figures",
]

FloatArray = NDArray[np.float64]
WORLD_COLOR = "#d0d0d0"
EST_PATH_COLOR = "#d32f2f"
TRUE_PATH_COLOR = "#1565c0"
START_COLOR = "#2e7d32"
VIEW_COLOR = "#9575cd"
METHOD_COLORS = {"start": START_COLOR, "triangulation": "#1565c0", "path_integration": "#e65100"}
MAP_CMAP = "viridis"
ODOM_COLOR = "#9e9e9e"
PANEL_IN = 5.0
DEFAULT_DPI = 100
# The paper's Table 1: Albot1 oriented within ±7° and ±3 m after about 100 m.
PAPER_BEARING_DEG = 7.0
PAPER_DISTANCE_M = 3.0
_MARGIN_FRACTION = 0.04


def _figure(width_in: float, height_in: float) -> Figure:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width_in, height_in), layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _png(fig: Figure, dpi: int) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    return buf.getvalue()


def _anchor(start_pose: FloatArray | None, segments: FloatArray) -> FloatArray:
    return segments if start_pose is None else transform_segments(start_pose, segments)


def _anchor_path(start_pose: FloatArray | None, path: FloatArray) -> FloatArray:
    return path if start_pose is None or not len(path) else compose_arrays(start_pose, path)


def _extent(parts: Sequence[FloatArray]) -> tuple[float, float, float, float] | None:
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


def _set_extent(ax: Axes, extent: tuple[float, float, float, float] | None) -> None:
    if extent is not None:
        ax.set_xlim(extent[0], extent[2])
        ax.set_ylim(extent[1], extent[3])
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")


def _draw_world(ax: Axes, world: World | None) -> None:
    from matplotlib.collections import LineCollection

    if world is not None and len(world.obstacle_segments):
        ax.add_collection(LineCollection(world.obstacle_segments.reshape(-1, 2, 2),
                                         colors=WORLD_COLOR, linewidths=0.8, zorder=1))


def plot_map(
    ax: Axes,
    segments: FloatArray,
    map_ids: NDArray[np.int64] | None = None,
    *,
    world: World | None = None,
    start_pose: FloatArray | None = None,
    est_path: FloatArray | None = None,
    true_path: FloatArray | None = None,
    id_range: tuple[int, int] | None = None,
    extent: tuple[float, float, float, float] | None = None,
    title: str | None = None,
) -> Any:
    """Draw one global map on ``ax``; returns the surfaces' LineCollection (for a colorbar).

    ``segments``/``est_path`` are in the mapper's frame and are moved into the world by
    ``start_pose`` when given; ``true_path`` and ``world`` are in the world frame.
    """
    from matplotlib.collections import LineCollection

    _draw_world(ax, world)
    segs = _anchor(start_pose, np.asarray(segments, np.float64).reshape(-1, 4))
    lines = LineCollection(segs.reshape(-1, 2, 2), linewidths=1.6, cmap=MAP_CMAP, zorder=3,
                           label="map surfaces")
    if map_ids is not None and len(segs):
        lines.set_array(np.asarray(map_ids, dtype=np.float64))
        lo, hi = id_range if id_range is not None else (int(np.min(map_ids)), int(np.max(map_ids)))
        lines.set_clim(lo, max(hi, lo + 1))
    else:
        lines.set_color("#212121")
    ax.add_collection(lines)
    parts: list[FloatArray] = [segs.reshape(-1, 2)]
    if world is not None and len(world.obstacle_segments):
        ax.plot([], [], "-", color=WORLD_COLOR, lw=0.8, label="true walls")
    if true_path is not None and len(true_path):
        ax.plot(*true_path[:, :2].T, "-", color=TRUE_PATH_COLOR, lw=0.8, alpha=0.5, zorder=2,
                label="true path")
        parts.append(true_path[:, :2])
    if est_path is not None and len(est_path):
        from albot2d.plots import draw_direction_arrows

        path = _anchor_path(start_pose, np.asarray(est_path, np.float64).reshape(-1, 3))
        ax.plot(*path[:, :2].T, "-", color=EST_PATH_COLOR, lw=1.0, zorder=4,
                label="estimated path (→)")
        draw_direction_arrows(ax, path, color=EST_PATH_COLOR, count=8, size=9.0, zorder=4)
        ax.plot(*path[0, :2], "*", color=START_COLOR, ms=12, zorder=5, label="start")
        ax.plot(*path[-1, :2], "o", color=EST_PATH_COLOR, ms=6, zorder=5, label="robot")
        parts.append(path[:, :2])
    if world is not None:
        b = world.bounds
        parts.append(np.array([[b[0], b[1]], [b[2], b[3]]]))
    _set_extent(ax, extent if extent is not None else _extent(parts))
    if title:
        ax.set_title(title, fontsize=10)
    return lines


def plot_route(
    ax: Axes,
    route: RouteMap,
    *,
    world: World | None = None,
    start_pose: FloatArray | None = None,
    true_path: FloatArray | None = None,
    title: str | None = None,
) -> None:
    """Draw a route map: each remembered view's surfaces (faint) and its viewpoint, the
    viewpoints chained in order and coloured by how they were localised."""
    from matplotlib.collections import LineCollection
    from matplotlib.lines import Line2D

    _draw_world(ax, world)
    poses = _anchor_path(start_pose, route.compose_chain()) if len(route) else np.zeros((0, 3))
    views = [transform_segments(p, m.view.segments) for p, m in zip(poses, route, strict=True)]
    segs = np.vstack(views) if views else np.zeros((0, 4))
    ax.add_collection(LineCollection(segs.reshape(-1, 2, 2), colors=VIEW_COLOR, linewidths=0.5,
                                     alpha=0.5, zorder=2))
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
                handles.append(Line2D([], [], color=color, marker="o", ls="",
                                      label=f"{method.replace('_', ' ')} ({int(sel.sum())})"))
    if len(poses):
        ax.plot(*poses[0, :2], "*", color=START_COLOR, ms=12, zorder=5)
    handles.append(Line2D([], [], color=VIEW_COLOR, lw=1, label="remembered views' surfaces"))
    ax.legend(handles=handles, loc="upper right", fontsize=8, framealpha=0.8)
    parts = [segs.reshape(-1, 2), poses[:, :2]]
    if world is not None:
        b = world.bounds
        parts.append(np.array([[b[0], b[1]], [b[2], b[3]]]))
    _set_extent(ax, _extent(parts))
    if title:
        ax.set_title(title, fontsize=10)


def plot_homing(fig: Figure, mappers: Mapping[str, Mapping[str, Any]]) -> None:
    """Homing at each stop against odometer distance: errors when the truth is known
    (with the paper's ±7° / ±3 m band), else each mapper's estimates."""
    entries = {name: m["homing"] for name, m in mappers.items()}
    with_truth = any(e and e[0]["bearing_error_deg"] is not None for e in entries.values())
    ax_b, ax_d = fig.subplots(1, 2)
    if with_truth:
        keys = ("bearing_error_deg", "distance_error_m")
        labels = ("bearing error to start (deg, + = too far left)", "distance error to start (m)")
        for ax, band, unit in ((ax_b, PAPER_BEARING_DEG, "°"), (ax_d, PAPER_DISTANCE_M, " m")):
            ax.axhspan(-band, band, color="#c8e6c9", alpha=0.6, zorder=0,
                       label=f"paper's Albot₁ (±{band:g}{unit})")
            ax.axhline(0.0, color="#616161", lw=0.8)
    else:
        keys = ("bearing_est_deg", "distance_est_m")
        labels = ("estimated bearing to start (deg, + = left)", "estimated distance to start (m)")
    for name, rows in entries.items():
        if not rows:
            continue
        x = [r["travelled_m"] for r in rows]
        for ax, key in zip((ax_b, ax_d), keys, strict=True):
            ax.plot(x, [r[key] for r in rows], "o-", ms=4, lw=1.2, label=name)
    for ax, label in zip((ax_b, ax_d), labels, strict=True):
        ax.set_xlabel("distance travelled (odometer, m)")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=8)
    if not any(entries.values()):
        ax_b.set_title("no homing stops (the run never got far from its start)", fontsize=10)
    fig.suptitle("Orientation to the start at each stop: error against the truth (paper Table 1)"
                 if with_truth else
                 "Orientation to the start at each stop: estimates (no ground truth)")


def plot_estimated_paths(ax: Axes, result: ExperimentResult) -> None:
    """Raw odometry and every mapper's estimated path, all in the first pose's frame
    (for logs without ground truth)."""
    from matplotlib import colormaps

    from albot2d.geometry import between_arrays
    from albot2d.plots import draw_direction_arrows

    trace = result.trace
    odom = between_arrays(trace.odom_poses[0], trace.odom_poses)
    # Odometry is drawn wide and light underneath: a mapper that follows it (naive
    # integration does exactly) is drawn on top and said to be identical.
    ax.plot(*odom[:, :2].T, "-", color=ODOM_COLOR, lw=4.0, alpha=0.6, zorder=2,
            label="raw odometry")
    parts = [odom[:, :2]]
    colors = colormaps["tab10"].colors
    styles = ["-", "--", "-.", ":"]
    for k, (name, mapper) in enumerate(trace.mappers.items()):
        est = np.asarray(mapper.trajectory(), np.float64).reshape(-1, 3)
        same = est.shape == odom.shape and np.allclose(est[:, :2], odom[:, :2], atol=1e-6)
        color = colors[k % len(colors)]
        ax.plot(*est[:, :2].T, styles[k % len(styles)], color=color, lw=1.2, zorder=3 + k,
                label=f"{name} (= odometry)" if same else name)
        draw_direction_arrows(ax, est, color=color, count=8, size=9.0, zorder=3 + k)
        parts.append(est[:, :2])
    ax.plot(0.0, 0.0, "*", color=START_COLOR, ms=12, zorder=10, label="start")
    _set_extent(ax, _extent(parts))
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.legend(fontsize=8, loc="best", framealpha=0.8)
    ax.set_title(f"{result.title}\nestimated paths (→ direction; first pose's frame)",
                 fontsize=10)


# -- the figures of a run --------------------------------------------------------------
def _grid(n: int) -> tuple[int, int]:
    cols = n if n <= 3 else 2 if n == 4 else 3
    return (n + cols - 1) // cols, cols


def _panel_size(result: ExperimentResult, extent: Any) -> tuple[float, float]:
    if extent is None:
        return PANEL_IN, PANEL_IN
    w, h = extent[2] - extent[0], extent[3] - extent[1]
    aspect = min(max(h / max(w, 1e-9), 0.4), 2.5)
    return PANEL_IN, PANEL_IN * aspect + 0.6


def _map_panel(ax: Axes, result: ExperimentResult, name: str, row: int | None = None,
               update: int | None = None, extent: Any = None, title: str | None = None) -> Any:
    trace = result.trace
    mapper = trace.mappers[name]
    snap = mapper.global_map() if update is None else mapper.global_map(at_update=update)  # type: ignore[call-arg]
    end = trace.n_frames if row is None else row + 1
    est = np.asarray(mapper.trajectory(), np.float64).reshape(-1, 3)[:end]
    start = None if trace.true_poses is None else trace.true_poses[0]
    true_path = None if trace.true_poses is None else trace.true_poses[:end]
    n_maps = len(np.unique(snap.map_ids))
    default = f"{name}: {len(snap.segments)} surfaces from {n_maps} views"
    return plot_map(ax, snap.segments, snap.map_ids, world=result.world, start_pose=start,
                    est_path=est, true_path=true_path, extent=extent, title=title or default)


def _paths_panel(ax: Axes, result: ExperimentResult, extent: Any) -> None:
    trace = result.trace
    if result.world is not None and trace.true_poses is not None:
        from albot2d.plots import plot_paths

        plot_paths(result.world, trace.true_poses, trace.odom_poses, collided=trace.collided,
                   ax=ax)
        legend = ax.get_legend()
        keep = [h for h in legend.legend_handles
                if h.get_label() in ("walls", "true path (→ direction, ● end)", "odometry",
                                     "collision", "start")]
        legend.remove()
        ax.legend(handles=keep, loc="upper right", fontsize=7, framealpha=0.8)
        ax.set_title("world, true path and odometry", fontsize=10)
        _set_extent(ax, extent)
    else:
        plot_estimated_paths(ax, result)
        ax.set_title("odometry and estimated paths (first pose's frame)", fontsize=10)


def _mapper_extent(result: ExperimentResult, name: str) -> Any:
    from albot2d.evaluation.scoring import route_of

    trace, mapper = result.trace, result.trace.mappers[name]
    start = None if trace.true_poses is None else trace.true_poses[0]
    est = _anchor_path(start, np.asarray(mapper.trajectory(), np.float64).reshape(-1, 3))
    parts = [est[:, :2], _anchor(start, mapper.global_map().segments).reshape(-1, 2)]
    route = route_of(mapper)
    if route is not None and len(route):
        # Every remembered view, so the history panels (earlier maps) fit too.
        chain = _anchor_path(start, route.compose_chain())
        parts.append(chain[:, :2])
        parts += [transform_segments(p, m.view.segments).reshape(-1, 2)
                  for p, m in zip(chain, route, strict=True)]
    if trace.true_poses is not None:
        parts.append(trace.true_poses[:, :2])
    if result.world is not None:
        b = result.world.bounds
        parts.append(np.array([[b[0], b[1]], [b[2], b[3]]]))
    return _extent(parts)


def _colorbar(fig: Figure, lines: Any, ax: Any) -> None:
    if lines.get_array() is not None:
        fig.colorbar(lines, ax=ax, shrink=0.8, label="local map / view id (old → new)")


def error_curves(result: ExperimentResult) -> dict[str, tuple[FloatArray, FloatArray]]:
    """Per mapper and ``odometry``: (position error m, heading error deg) at every view,
    each trajectory anchored at the true start pose (needs the truth)."""
    from albot2d.evaluation.alignment import in_world_frame
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


def plot_errors_vs_distance(fig: Figure, result: ExperimentResult) -> None:
    """Heading error and position error of every mapper and raw odometry against the
    true distance travelled, each trajectory anchored at the true start (simulation)."""
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
    fig.suptitle(f"{result.title}\nerror of each pose estimate against the truth (every "
                 "trajectory starts at the true start pose, no alignment)", fontsize=9)


def render_experiment_figures(
    result: ExperimentResult, *, dpi: int = DEFAULT_DPI
) -> dict[str, bytes]:
    """Every figure of a run or replay, as ``{file name: PNG bytes}``."""
    from albot2d.evaluation.scoring import route_of

    out: dict[str, bytes] = {}
    trace, names = result.trace, list(result.trace.mappers)
    if result.world is not None and trace.true_poses is not None:
        from albot2d.plots import render_paths_png

        out["paths.png"] = render_paths_png(result.world, trace.true_poses, trace.odom_poses,
                                            collided=trace.collided, title=result.title)
    else:
        fig = _figure(8.0, 7.0)
        plot_estimated_paths(fig.subplots(), result)
        out["paths.png"] = _png(fig, dpi)
    # Overview: the paths, then every mapper's final map, side by side on one scale.
    rows, cols = _grid(len(names) + 1)
    extents = [_mapper_extent(result, n) for n in names]
    extent = _extent([np.array([[e[0], e[1]], [e[2], e[3]]]) for e in extents if e])
    pw, ph = _panel_size(result, extent)
    fig = _figure(pw * cols, ph * rows + 0.5)
    axes = np.atleast_1d(fig.subplots(rows, cols)).ravel()
    _paths_panel(axes[0], result, extent)
    for ax, name in zip(axes[1:], names, strict=False):
        _colorbar(fig, _map_panel(ax, result, name, extent=extent), ax)
        ax.legend(loc="upper right", fontsize=7, framealpha=0.8)
    for ax in axes[len(names) + 1:]:
        ax.set_visible(False)
    fig.suptitle(result.title)
    out["maps.png"] = _png(fig, dpi)
    if trace.true_poses is not None:
        fig = _figure(11.0, 7.5)
        plot_errors_vs_distance(fig, result)
        out["errors.png"] = _png(fig, dpi)
    for name, ext in zip(names, extents, strict=True):
        pw, ph = _panel_size(result, ext)
        fig = _figure(pw * 1.6, ph * 1.6)
        ax = fig.subplots()
        _colorbar(fig, _map_panel(ax, result, name, extent=ext), ax)
        ax.legend(loc="upper right", fontsize=8, framealpha=0.8)
        fig.suptitle(result.title, fontsize=9)
        out[f"{name}_map.png"] = _png(fig, dpi)
        route = route_of(trace.mappers[name])
        if route is None:
            continue
        snaps = result.report["mappers"][name].get("snapshots") or []
        rows, cols = _grid(len(snaps))
        fig = _figure(pw * cols, ph * rows + 0.5)
        axes = np.atleast_1d(fig.subplots(rows, cols)).ravel()
        id_range = (0, max(len(route) - 1, 1))
        for ax, snap in zip(axes, snaps, strict=False):
            title = (f"view {snap['view']} ({snap['travelled_m']:.0f} m): {snap['surfaces']} "
                     f"surfaces, {snap['update']} views remembered")
            lines = _map_panel(ax, result, name, row=snap["row"], update=snap["update"],
                               extent=ext, title=title)
            lines.set_clim(*id_range)
            _colorbar(fig, lines, ax)
            ax.legend(loc="upper right", fontsize=7, framealpha=0.8)
        for ax in axes[len(snaps):]:
            ax.set_visible(False)
        fig.suptitle(f"{name}'s global map as it evolves (transient: old parts are deleted)")
        out[f"{name}_history.png"] = _png(fig, dpi)
        fig = _figure(pw * 1.6, ph * 1.6)
        start = None if trace.true_poses is None else trace.true_poses[0]
        plot_route(fig.subplots(), route, world=result.world, start_pose=start,
                   true_path=trace.true_poses,
                   title=f"{name}'s route map: {len(route)} remembered views of {trace.n_frames}")
        out[f"{name}_route.png"] = _png(fig, dpi)
    fig = _figure(11.0, 4.5)
    plot_homing(fig, result.report["mappers"])
    out["homing.png"] = _png(fig, dpi)
    return out
