"""Figures of a run: the error-vs-distance figure and its legend, replay figures without
truth (odometry under naive, direction arrows, titles), and the --animate GIF. Every
figure of a run drawn without a warning: tests/test_cli_run.py."""

from __future__ import annotations

import io

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from albot2d.evaluation import RunSpec, run_experiment
from albot2d.evaluation.experiment import ExperimentResult
from albot2d.plots_maps import (
    _figure,
    error_curves,
    plot_errors_vs_distance,
    plot_estimated_paths,
    plot_homing,
)

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def result() -> ExperimentResult:
    spec = RunSpec(
        kind="rooms",
        seed=2,
        world_params={"width_m": 15.0, "height_m": 15.0},
        profile="dataset3",
        tour_length_m=20.0,
        max_frames=60,
    )
    return run_experiment(spec)


def test_error_curves_against_the_truth(result: ExperimentResult) -> None:
    curves = error_curves(result)
    assert list(curves) == ["odometry", "albot1", "naive", "truth"]
    position, heading = curves["truth"]
    assert np.abs(position).max() < 1e-9 and np.abs(heading).max() < 1e-6
    assert np.allclose(curves["naive"][0], curves["odometry"][0], atol=1e-9)
    assert curves["odometry"][0][-1] > 0.0  # typical noise: odometry drifts


def test_error_figure_labels_every_curve(result: ExperimentResult) -> None:
    fig = _figure(8.0, 6.0)
    plot_errors_vs_distance(fig, result)
    heading_ax, position_ax = fig.axes[:2]
    labels = [t.get_text() for t in position_ax.get_legend().get_texts()]
    assert labels == ["raw odometry", "albot1", "naive (= odometry)", "truth"]
    assert "heading error" in heading_ax.get_ylabel()


def test_replay_paths_show_odometry_under_naive_and_no_truth_title(
    result: ExperimentResult,
) -> None:
    fig = _figure(6.0, 6.0)
    ax = fig.subplots()
    plot_estimated_paths(ax, result)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels[:4] == ["raw odometry", "albot1", "naive (= odometry)", "truth"]
    assert len(ax.texts) >= 8  # direction arrows along the paths (annotations)
    fig = _figure(8.0, 4.0)
    no_truth = {
        name: {"homing": [dict(e, bearing_error_deg=None) for e in m["homing"]]}
        for name, m in result.report["mappers"].items()
    }
    plot_homing(fig, no_truth)
    assert "Table 1" not in fig.get_suptitle() and "no ground truth" in fig.get_suptitle()


def test_animation_gif(result: ExperimentResult) -> None:
    from PIL import Image

    from albot2d.plots_anim import animated_mapper, render_map_animation

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
    from albot2d.plots_anim import ffmpeg_available, render_map_animation

    if not ffmpeg_available():
        pytest.skip("no ffmpeg executable: --animate writes the GIF only")
    files = render_map_animation(request.getfixturevalue("result"), moments=3, dpi=40)
    assert set(files) == {"albot1_map.gif", "albot1_map.mp4"}
    assert files["albot1_map.mp4"][4:8] == b"ftyp"  # an MP4 container
