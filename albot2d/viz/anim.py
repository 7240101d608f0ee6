"""An animation of a view-based mapper's global map over time, beside the truth.

``render_map_animation(result)`` draws, for moments spread over the run, the world with
the true path so far and the robot (left) and the mapper's global map at that moment
(right: ``global_map(at_update=k)``, anchored at the true start pose so drift shows,
surfaces coloured old → new by the view they came from) with its estimated path and
pose. Albot1's map is transient: watch old parts disappear as places are revisited.

Written by ``albot2d run --animate`` as ``NAME_map.gif`` (matplotlib's PillowWriter) and,
when ffmpeg is installed, ``NAME_map.mp4`` too. matplotlib is imported inside functions.
"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from albot2d.viz._figure import line_segments, new_figure
from albot2d.viz.maps import (
    EST_PATH_COLOR,
    MAP_CMAP,
    START_COLOR,
    TRUE_PATH_COLOR,
    WORLD_COLOR,
    anchor_path,
    anchor_segments,
    set_extent,
)
from albot2d.viz.run_figures import mapper_extent

if TYPE_CHECKING:
    from albot2d.evaluation.run.experiment import ExperimentResult

__all__ = ["animated_mapper", "ffmpeg_available", "render_map_animation"]

DEFAULT_MOMENTS = 40
DEFAULT_FPS = 5
DEFAULT_DPI = 72


def ffmpeg_available() -> bool:
    """Whether matplotlib can write MP4 here (an ffmpeg executable is installed)."""
    from matplotlib import animation

    return bool(animation.writers.is_available("ffmpeg"))


def animated_mapper(result: ExperimentResult) -> str | None:
    """The mapper to animate: ``albot1`` if present, else the first with a map history
    (a route map), else None."""
    from albot2d.evaluation.run.scoring import route_of

    names = [n for n, m in result.trace.mappers.items() if route_of(m) is not None]
    return "albot1" if "albot1" in names else (names[0] if names else None)


def _moments(result: ExperimentResult, name: str, count: int) -> list[tuple[int, int]]:
    """(trace row, map update) pairs spread evenly over the run, the last at its end."""
    from albot2d.evaluation.run.scoring import route_of

    trace = result.trace
    route = route_of(trace.mappers[name])
    assert route is not None
    map_frames = np.array([m.frame_index for m in route], dtype=np.int64)
    n = trace.n_frames
    rows = sorted({max(math.ceil(n * k / count) - 1, 0) for k in range(1, count + 1)})
    return [(r, int(np.count_nonzero(map_frames <= trace.frame_indices[r]))) for r in rows]


def _robot_marker(ax: Any, color: str) -> tuple[Any, Any]:
    (dot,) = ax.plot([], [], "o", color=color, ms=7, zorder=6)
    (heading,) = ax.plot([], [], "-", color=color, lw=2.0, zorder=6)
    return dot, heading


def _place_robot(dot: Any, heading: Any, pose: np.ndarray, length: float) -> None:
    x, y, theta = (float(v) for v in pose)
    dot.set_data([x], [y])
    heading.set_data([x, x + length * math.cos(theta)], [y, y + length * math.sin(theta)])


def render_map_animation(
    result: ExperimentResult,
    name: str | None = None,
    *,
    moments: int = DEFAULT_MOMENTS,
    fps: int = DEFAULT_FPS,
    dpi: int = DEFAULT_DPI,
    mp4: bool | None = None,
) -> dict[str, bytes]:
    """``{"NAME_map.gif": bytes}`` (and ``"NAME_map.mp4"`` when ``mp4``; default: when
    ffmpeg is available), or ``{}`` when no mapper has a map history."""
    from matplotlib import animation
    from matplotlib.collections import LineCollection
    from matplotlib.lines import Line2D

    name = name or animated_mapper(result)
    if name is None:
        return {}
    trace = result.trace
    from albot2d.mapping.protocol import ViewBasedMapper

    mapper = trace.mappers[name]
    if not isinstance(mapper, ViewBasedMapper):  # animated_mapper() chose one with a history
        raise TypeError(f"mapper {name!r} keeps no map history to animate")
    truth = trace.true_poses
    start = None if truth is None else truth[0]
    est = anchor_path(start, np.asarray(mapper.trajectory(), np.float64).reshape(-1, 3))
    plan = _moments(result, name, moments)
    extent = mapper_extent(result, name)
    span = 1.0 if extent is None else max(extent[2] - extent[0], extent[3] - extent[1])
    arrow = span / 40.0

    fig = new_figure(11.0, 5.6)
    ax_true, ax_map = fig.subplots(1, 2)
    for ax in (ax_true, ax_map):
        if result.world is not None and len(result.world.obstacle_segments):
            segs = line_segments(result.world.obstacle_segments)
            color = "#1a1a1a" if ax is ax_true else WORLD_COLOR
            ax.add_collection(LineCollection(segs, colors=color, linewidths=0.8, zorder=1))
        set_extent(ax, extent)
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
    (true_line,) = ax_true.plot([], [], "-", color=TRUE_PATH_COLOR, lw=1.2, zorder=3)
    true_robot = _robot_marker(ax_true, TRUE_PATH_COLOR)
    ax_true.set_title("truth: world, true path and robot", fontsize=10)
    if truth is None:
        ax_true.set_title("no ground truth (a real log)", fontsize=10)
    surfaces = LineCollection([], linewidths=1.6, cmap=MAP_CMAP, zorder=3)
    surfaces.set_clim(0, max(len(mapper.route_map()) - 1, 1))
    ax_map.add_collection(surfaces)
    (est_line,) = ax_map.plot([], [], "-", color=EST_PATH_COLOR, lw=1.0, zorder=4)
    est_robot = _robot_marker(ax_map, EST_PATH_COLOR)
    for ax, pose in ((ax_true, truth), (ax_map, est)):
        if pose is not None and len(pose):
            ax.plot(*pose[0, :2], "*", color=START_COLOR, ms=12, zorder=5)
    fig.colorbar(surfaces, ax=ax_map, shrink=0.8, label="local map / view id (old → new)")
    ax_true.legend(handles=[
        Line2D([], [], color="#1a1a1a", lw=0.8, label="walls"),
        Line2D([], [], color=TRUE_PATH_COLOR, lw=1.2, marker="o", label="true path, robot"),
        Line2D([], [], color=START_COLOR, marker="*", ls="", ms=10, label="start"),
    ], loc="upper right", fontsize=7, framealpha=0.8)  # fmt: skip
    ax_map.legend(handles=[
        Line2D([], [], color="#21918c", lw=1.6, label="global map surfaces"),
        Line2D([], [], color=WORLD_COLOR, lw=0.8, label="true walls"),
        Line2D([], [], color=EST_PATH_COLOR, lw=1.0, marker="o", label="estimated path, pose"),
    ], loc="upper right", fontsize=7, framealpha=0.8)  # fmt: skip
    title = fig.suptitle("", fontsize=9)

    def draw(k: int) -> list[Any]:
        row, update = plan[k]
        snap = mapper.global_map(at_update=update)
        segs = anchor_segments(start, np.asarray(snap.segments, np.float64).reshape(-1, 4))
        surfaces.set_segments(line_segments(segs))
        surfaces.set_array(np.asarray(snap.map_ids, dtype=np.float64))
        est_line.set_data(est[: row + 1, 0], est[: row + 1, 1])
        _place_robot(*est_robot, est[row], arrow)
        if truth is not None:
            true_line.set_data(truth[: row + 1, 0], truth[: row + 1, 1])
            _place_robot(*true_robot, truth[row], arrow)
        ax_map.set_title(f"{name}'s global map: {len(segs)} surfaces after {update} "
                         "remembered views", fontsize=10)  # fmt: skip
        title.set_text(
            f"{result.title}\nview {int(trace.frame_indices[row])} of "
            f"{trace.n_frames}, {float(trace.travelled_m[row]):.0f} m driven"
        )
        return [surfaces, est_line, true_line, title]

    # Lay the figure out once (constrained layout is costly), then draw each moment
    # exactly once into the writer (FuncAnimation would draw every frame twice).
    draw(len(plan) - 1)
    fig.draw_without_rendering()
    fig.set_layout_engine("none")
    writers: list[tuple[str, Any]] = [("gif", animation.PillowWriter(fps=fps))]
    if mp4 if mp4 is not None else ffmpeg_available():
        writers.append(("mp4", animation.FFMpegWriter(fps=fps)))
    out: dict[str, bytes] = {}
    with tempfile.TemporaryDirectory(prefix="albot2d-anim.") as tmp:
        for ext, writer in writers:
            path = Path(tmp) / f"map.{ext}"
            with writer.saving(fig, str(path), dpi):
                for k in range(len(plan)):
                    draw(k)
                    writer.grab_frame()
            out[f"{name}_map.{ext}"] = path.read_bytes()
    return out
