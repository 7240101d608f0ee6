"""An animation of a view-based mapper's global map over time, beside the truth.

``render_map_animation(result)`` draws, for moments spread over the run, the world with
the true path so far, the robot's footprint (its disc and heading) and its laser beams
(left: the run's laser model, noise-free, cast from the true pose at that moment), and
the mapper's global map at that moment (right: ``global_map(at_update=k)``, anchored at
the true start pose so drift shows, surfaces coloured old → new by the local map they
came from) with its estimated path, the robot's footprint at its estimated pose and the
current view (the local map remembered last, thick orange). Albot1's map is transient:
watch old parts disappear as places are revisited.

Written by ``albot2d run --animate`` as ``NAME_map.mp4`` where ffmpeg is installed, else
as ``NAME_map.gif`` (matplotlib's PillowWriter). matplotlib is imported inside functions.
"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from albot2d.geometry import transform_segments
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
DEFAULT_DPI = 100
BEAM_COLOR = "#e53935"
VIEW_NOW_COLOR = "#ff8f00"
BEAM_STRIDE = 3  # every third beam: the fan stays readable


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


def _robot_marker(ax: Any, color: str, radius_m: float) -> tuple[Any, Any, Any]:
    """The robot's footprint: its disc (true size), a heading line and a ring around it
    (a robot's disc is a few pixels in a building-sized picture)."""
    from matplotlib.patches import Circle

    disc = Circle((0.0, 0.0), radius_m, facecolor=color, edgecolor="k", lw=0.8, alpha=0.6,
                  zorder=7)  # fmt: skip
    ax.add_patch(disc)
    (heading,) = ax.plot([], [], "-", color="k", lw=1.6, zorder=8)
    (ring,) = ax.plot([], [], "o", ms=14, mfc="none", mec=color, mew=1.5, zorder=8)
    return disc, heading, ring


def _place_robot(disc: Any, heading: Any, ring: Any, pose: np.ndarray, length: float) -> None:
    x, y, theta = (float(v) for v in pose)
    disc.center = (x, y)
    ring.set_data([x], [y])
    heading.set_data([x, x + length * math.cos(theta)], [y, y + length * math.sin(theta)])


def _laser(result: ExperimentResult) -> Any:
    """The run's laser model (noise-free) over its world, or None (no world)."""
    from albot2d.sim.laser import Laser, LaserParams

    if result.world is None:
        return None
    recorded = (result.report.get("params", {}).get("simulator") or {}).get("laser")
    try:
        params = LaserParams(**recorded) if isinstance(recorded, dict) else LaserParams()
    except TypeError:  # a report of another version: the default laser
        params = LaserParams()
    return Laser.for_world(result.world, params)


def _beams(laser: Any, pose: np.ndarray) -> np.ndarray:
    """Segments from the laser to each (every ``BEAM_STRIDE``-th) beam's hit or its range."""
    from albot2d.geometry import Pose

    robot = Pose(float(pose[0]), float(pose[1]), float(pose[2]))
    at = laser.laser_pose(robot)
    ranges = np.asarray(laser.true_ranges(robot), np.float64)
    ranges = np.where(np.isfinite(ranges), ranges, laser.params.max_range_m)[::BEAM_STRIDE]
    angles = at.theta + np.asarray(laser.angles)[::BEAM_STRIDE]
    ends = np.column_stack([at.x + ranges * np.cos(angles), at.y + ranges * np.sin(angles)])
    return np.column_stack([np.tile([at.x, at.y], (len(ends), 1)), ends])


def render_map_animation(
    result: ExperimentResult,
    name: str | None = None,
    *,
    moments: int = DEFAULT_MOMENTS,
    fps: int = DEFAULT_FPS,
    dpi: int = DEFAULT_DPI,
    mp4: bool | None = None,
) -> dict[str, bytes]:
    """``{"NAME_map.mp4": bytes}`` when ``mp4`` (default: when ffmpeg is available), else
    ``{"NAME_map.gif": bytes}``; ``{}`` when no mapper has a map history."""
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

    from albot2d.viz.furniture import LABEL_PT, LEGEND_PT, TITLE_PT, axes_colorbar

    radius = result.world.robot_radius_m if result.world is not None else 0.25
    laser = _laser(result) if truth is not None else None
    route = mapper.route_map()
    chain = anchor_path(start, route.compose_chain()) if len(route) else np.zeros((0, 3))
    fig = new_figure(12.0, 6.2, layout="compressed")
    ax_true, ax_map = fig.subplots(1, 2)
    for ax in (ax_true, ax_map):
        if result.world is not None and len(result.world.obstacle_segments):
            segs = line_segments(result.world.obstacle_segments)
            color = "#1a1a1a" if ax is ax_true else WORLD_COLOR
            ax.add_collection(LineCollection(segs, colors=color, linewidths=0.8, zorder=1))
        set_extent(ax, extent)
        ax.set_xlabel("x (m)", fontsize=LABEL_PT)
        ax.set_ylabel("y (m)", fontsize=LABEL_PT)
        ax.tick_params(labelsize=LABEL_PT - 1)
    beams = LineCollection([], colors=BEAM_COLOR, linewidths=0.5, alpha=0.45, zorder=2)
    ax_true.add_collection(beams)
    (true_line,) = ax_true.plot([], [], "-", color=TRUE_PATH_COLOR, lw=1.4, zorder=3)
    true_robot = _robot_marker(ax_true, TRUE_PATH_COLOR, radius)
    ax_true.set_title("truth: world, true path, robot and its laser", fontsize=TITLE_PT + 1)
    if truth is None:
        ax_true.set_title("no ground truth (a real log)", fontsize=TITLE_PT + 1)
    surfaces = LineCollection([], linewidths=1.6, cmap=MAP_CMAP, zorder=3)
    surfaces.set_clim(0, max(len(route) - 1, 1))
    ax_map.add_collection(surfaces)
    view_now = LineCollection([], colors=VIEW_NOW_COLOR, linewidths=3.0, zorder=5)
    ax_map.add_collection(view_now)
    (est_line,) = ax_map.plot([], [], "-", color=EST_PATH_COLOR, lw=1.2, zorder=4)
    est_robot = _robot_marker(ax_map, EST_PATH_COLOR, radius)
    for ax, pose in ((ax_true, truth), (ax_map, est)):
        if pose is not None and len(pose):
            ax.plot(*pose[0, :2], "*", color=START_COLOR, ms=12, zorder=5)
    axes_colorbar(fig, surfaces, ax_map, "local map it came from (old → new)")
    below = {"loc": "upper center", "bbox_to_anchor": (0.5, -0.1), "ncols": 3,
             "fontsize": LEGEND_PT + 1, "frameon": False}  # fmt: skip
    ax_true.legend(handles=[
        Line2D([], [], color="#1a1a1a", lw=0.8, label="walls"),
        Line2D([], [], color=TRUE_PATH_COLOR, lw=1.4, label="true path"),
        Line2D([], [], color=TRUE_PATH_COLOR, marker="o", ls="", ms=9, alpha=0.6,
               label="robot (footprint, heading)"),
        Line2D([], [], color=BEAM_COLOR, lw=0.8, alpha=0.6, label="laser beams"),
        Line2D([], [], color=START_COLOR, marker="*", ls="", ms=10, label="start"),
    ], **below)  # fmt: skip
    ax_map.legend(handles=[
        Line2D([], [], color="#21918c", lw=1.6, label="global map surfaces"),
        Line2D([], [], color=VIEW_NOW_COLOR, lw=3.0, label="current view (last local map)"),
        Line2D([], [], color=WORLD_COLOR, lw=0.8, label="true walls"),
        Line2D([], [], color=EST_PATH_COLOR, lw=1.2, label="estimated path"),
        Line2D([], [], color=EST_PATH_COLOR, marker="o", ls="", ms=9, alpha=0.6,
               label="robot at its estimate"),
    ], **below)  # fmt: skip
    title = fig.suptitle("", fontsize=TITLE_PT + 1)

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
            if laser is not None:
                beams.set_segments(line_segments(_beams(laser, truth[row])))
        if 0 < update <= len(chain):
            last = route[update - 1].view.segments
            view_now.set_segments(line_segments(transform_segments(chain[update - 1], last)))
        ax_map.set_title(f"{name}'s global map: {len(segs)} surfaces, {update} local maps",
                         fontsize=TITLE_PT + 1)  # fmt: skip
        title.set_text(
            f"{result.title}\nview {int(trace.frame_indices[row])} of "
            f"{trace.n_frames}, {float(trace.travelled_m[row]):.0f} m driven"
        )
        return [surfaces, view_now, beams, est_line, true_line, title]

    # Lay the figure out once (constrained layout is costly), then draw each moment
    # exactly once into the writer (FuncAnimation would draw every frame twice).
    draw(len(plan) - 1)
    fig.draw_without_rendering()
    fig.set_layout_engine("none")
    if mp4 if mp4 is not None else ffmpeg_available():
        writers: list[tuple[str, Any]] = [("mp4", animation.FFMpegWriter(fps=fps))]
    else:
        writers = [("gif", animation.PillowWriter(fps=fps))]
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
