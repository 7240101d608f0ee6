"""Figures of a run: the error-vs-distance figure and its legend, replay figures without
truth (odometry under naive, direction arrows, titles), and the --animate GIF. Every
figure of a run drawn without a warning: tests/test_cli_run.py."""

from __future__ import annotations

import dataclasses
import io
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from albot2d.evaluation import run_experiment
from albot2d.evaluation.metrics.homing import HomingResult
from albot2d.evaluation.run.experiment import ExperimentResult
from albot2d.viz import error_curves, plot_errors_vs_distance, plot_estimated_paths, plot_homing
from tests.runs import small_run

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def result() -> ExperimentResult:
    return run_experiment(small_run(2, max_frames=60))


def test_error_curves_against_the_truth(result: ExperimentResult) -> None:
    curves = error_curves(result)
    assert list(curves) == ["odometry", "albot1", "naive", "truth"]
    position, heading = curves["truth"]
    assert np.abs(position).max() < 1e-9 and np.abs(heading).max() < 1e-6
    assert np.allclose(curves["naive"][0], curves["odometry"][0], atol=1e-9)
    assert curves["odometry"][0][-1] > 0.0  # typical noise: odometry drifts


def test_error_figure_labels_every_curve(result: ExperimentResult) -> None:
    fig = plot_errors_vs_distance(result)
    heading_ax, position_ax = fig.axes[:2]
    labels = [t.get_text() for t in position_ax.get_legend().get_texts()]
    assert labels == ["raw odometry", "albot1", "naive (= odometry)", "truth"]
    assert "heading error" in heading_ax.get_ylabel()


def test_replay_paths_show_odometry_under_naive_and_no_truth_title(
    result: ExperimentResult,
) -> None:
    ax = plot_estimated_paths(result)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels[:4] == ["raw odometry", "albot1", "naive (= odometry)", "truth"]
    assert len(ax.texts) >= 8  # direction arrows along the paths (annotations)

    def without_truth(h: HomingResult) -> HomingResult:
        return dataclasses.replace(h, bearing_true_deg=None, distance_true_m=None)

    no_truth = {
        name: [
            dataclasses.replace(
                stop,
                homing=dataclasses.replace(
                    stop.homing, bearing_true_deg=None, distance_true_m=None
                ),
            )
            for stop in scores.homing
        ]
        for name, scores in result.scores.mappers.items()
    }
    fig = plot_homing(no_truth)
    assert "Table 1" not in fig.get_suptitle() and "no ground truth" in fig.get_suptitle()


def test_animation_gif(result: ExperimentResult) -> None:
    from PIL import Image

    from albot2d.viz.anim import animated_mapper, render_map_animation

    assert animated_mapper(result) == "albot1"
    files = render_map_animation(result, moments=4, dpi=40, mp4=False)
    assert list(files) == ["albot1_map.gif"]
    image = Image.open(io.BytesIO(files["albot1_map.gif"]))
    assert image.format == "GIF" and image.n_frames == 4
    frames = []
    for k in (0, 3):
        image.seek(k)
        frames.append(np.asarray(image.convert("RGB")))
    assert not np.array_equal(frames[0], frames[1])  # the map and the robot move


def test_animation_mp4_when_ffmpeg_is_installed(request: pytest.FixtureRequest) -> None:
    from albot2d.viz.anim import ffmpeg_available, render_map_animation

    if not ffmpeg_available():
        pytest.skip("no ffmpeg executable: --animate writes the GIF only")
    files = render_map_animation(request.getfixturevalue("result"), moments=3, dpi=40)
    assert set(files) == {"albot1_map.mp4"}  # MP4 where ffmpeg exists, GIF otherwise
    assert files["albot1_map.mp4"][4:8] == b"ftyp"  # an MP4 container


def test_map_and_route_follow_the_plot_convention(result: ExperimentResult) -> None:
    """``plot_map``/``plot_route`` take the data first and return the axes they drew on
    (a new figure when no ``ax``); the surfaces' LineCollection is reachable for a colour
    bar and carries every surface, coloured by its view."""
    from matplotlib.axes import Axes

    from albot2d.viz import map_surfaces, plot_map, plot_route

    albot1 = result.trace.mappers["albot1"]
    snap = albot1.global_map()
    ax = plot_map(snap.segments, map_ids=snap.map_ids, world=result.world)
    assert isinstance(ax, Axes) and ax.get_figure(root=True) is not None
    lines = map_surfaces(ax)
    # Drawn as NaN-separated lines, one colour value per line: every surface once, each
    # with its own view's colour (tests/test_viz_memory.py checks the pixels).
    rows = np.vstack([p.vertices for p in lines.get_paths()])
    assert np.isnan(rows[2::3]).all() and len(rows) == 3 * len(snap.segments)
    values = lines.get_array()
    assert values is not None and set(values) <= set(snap.map_ids.tolist())
    assert lines.get_clim() == (snap.map_ids.min(), max(snap.map_ids.max(), snap.map_ids.min() + 1))
    given = plot_map(snap.segments, ax=ax)
    assert given is ax and map_surfaces(ax) is not lines  # the last map drawn
    with pytest.raises(ValueError, match="plot_map"):
        map_surfaces(plot_route(albot1.route))
    route_ax = plot_route(albot1.route, world=result.world)
    viewpoints = sum(len(ln.get_xdata()) for ln in route_ax.lines if ln.get_marker() == "o")
    assert viewpoints == len(albot1.route)  # every remembered view, coloured by method


def test_paper_figures_follow_the_plot_convention(tmp_path: Path) -> None:
    """Single-panel paper figures return Axes, multi-panel ones a Figure; ``save_figure``
    writes either as a PNG."""
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from albot2d.viz.paper import plot_bars, plot_sequence, save_figure

    bars = {"bars": [{"label": "a", "ours": 1.0, "sd": 0.1, "paper": 1.2},
                     {"label": "b", "ours": None, "sd": None, "paper": 3.0}],
            "ylabel": "m"}  # fmt: skip
    ax = plot_bars(bars)
    assert isinstance(ax, Axes) and [t.get_text() for t in ax.get_xticklabels()] == ["a", "b"]
    seq = {"poses": [[0.0, 0.0, 0.0], [1.0, 0.0, 0.5]], "rows": [3, 4],
           "methods": ["triangulation", ""], "tracked": [5, 2],
           "walls": [[-2.0, -2.0, 2.0, -2.0]]}  # fmt: skip
    fig = plot_sequence(seq)
    assert isinstance(fig, Figure) and len(fig.axes) == 2
    for name, spec in (("bars.png", {"plot": "bars", "data": bars}),
                       ("seq.png", {"plot": "sequence", "data": seq})):  # fmt: skip
        save_figure(spec, tmp_path / name)
        assert (tmp_path / name).read_bytes().startswith(PNG_MAGIC)
