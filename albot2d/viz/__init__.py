"""Pictures of albot2d objects and results: the interfaces layer's figures and pages.

One module per figure family:

- ``world``: a world (``plot_world``); ``paths``: a run's true and odometry paths over it;
- ``maps``: a mapper's global map and Albot1's route map;
- ``run_figures``: every figure of ``albot2d run``/``replay`` (``render_experiment_figures``);
- ``anim``: the ``--animate`` GIF/MP4 of a global map over time;
- ``steps``: step time along a run (``steps.png``);
- ``campaign``: the histograms of ``albot2d fuzz``;
- ``paper``: the figures of ``albot2d experiments``; ``paper_page``: its ``index.html``
  (HTML, no matplotlib: it presents the same experiment data as the figures, so it lives
  beside them rather than in the CLI, which only parses options and writes files).

The convention (as shapely 2's plotting): ``plot_x(data, *, ax=None, ...) -> Axes`` draws
``data`` on ``ax`` (a new Agg figure when None; reach it with ``ax.get_figure()``) and
returns the axes. Figure-level composites of several panels are
``plot_x(data, *, fig=None, ...) -> Figure`` (``plot_homing``, ``plot_errors_vs_distance``,
``plot_campaign_histograms`` and the multi-panel paper figures), as their docstrings say.
``render_x_png(...) -> bytes`` gives a picture as PNG bytes, made in memory.

matplotlib (the optional ``viz`` extra) is imported inside the functions only: importing
this package, or any module of it, does not import matplotlib. Figures are built on the
Agg canvas directly (no pyplot, no global backend switch), headless and thread-safe.
"""

from albot2d.viz.anim import animated_mapper, ffmpeg_available, render_map_animation
from albot2d.viz.campaign import plot_campaign_histograms, render_campaign_histograms_png
from albot2d.viz.maps import map_surfaces, plot_map, plot_route
from albot2d.viz.paths import draw_direction_arrows, plot_paths, render_paths_png
from albot2d.viz.run_figures import (
    error_curves,
    plot_errors_vs_distance,
    plot_estimated_paths,
    plot_homing,
    render_experiment_figures,
)
from albot2d.viz.steps import plot_step_times, read_steps_csv, render_step_times_png
from albot2d.viz.world import plot_world, render_world_png, save_world_png

__all__ = [
    "animated_mapper",
    "draw_direction_arrows",
    "error_curves",
    "ffmpeg_available",
    "map_surfaces",
    "plot_campaign_histograms",
    "plot_errors_vs_distance",
    "plot_estimated_paths",
    "plot_homing",
    "plot_map",
    "plot_paths",
    "plot_route",
    "plot_step_times",
    "plot_world",
    "read_steps_csv",
    "render_campaign_histograms_png",
    "render_experiment_figures",
    "render_map_animation",
    "render_paths_png",
    "render_step_times_png",
    "render_world_png",
    "save_world_png",
]
