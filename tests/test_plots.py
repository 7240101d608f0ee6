"""World plots: real matplotlib rendering to PNG; the module imports without matplotlib."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.test_worldgen_io import sample_world
from worldgen.world import Tour

REPO = Path(__file__).resolve().parents[1]
pytest.importorskip("matplotlib")


def test_plots_module_imports_without_matplotlib() -> None:
    code = "import sys; sys.modules['matplotlib'] = None; import albot2d.plots; print('ok')"
    out = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok"


def test_plot_world_draws_everything_on_given_axes() -> None:
    from matplotlib.figure import Figure

    from albot2d.plots import plot_world

    world = sample_world()
    tour = Tour(world.roadmap.nodes[:4], kind="loop")
    ax = Figure().add_subplot()
    assert plot_world(world, tour=tour, ax=ax) is ax
    assert ax.get_aspect() == 1.0
    title = ax.get_title()
    assert "sample" in title and "seed 7" in title and "20.0 × 10.0 m" in title
    segments = [
        seg for c in ax.collections if hasattr(c, "get_segments") for seg in c.get_segments()
    ]
    assert len(segments) >= len(world.walls) + len(world.roadmap.edges)
    tour_lines = [line for line in ax.lines if line.get_label() == "tour"]
    assert len(tour_lines) == 1
    np.testing.assert_array_equal(np.asarray(tour_lines[0].get_xydata()), tour.waypoints)
    x0, x1 = ax.get_xlim()
    assert x0 <= world.bounds[0] and x1 >= world.bounds[2]


def test_plot_without_roadmap_has_fewer_segments() -> None:
    from albot2d.plots import plot_world

    world = sample_world()

    def count(show: bool) -> int:
        ax = plot_world(world, show_roadmap=show)
        return sum(len(c.get_segments()) for c in ax.collections if hasattr(c, "get_segments"))

    assert count(True) - count(False) == len(world.roadmap.edges)


def test_save_world_png_writes_a_png(tmp_path: Path) -> None:
    from albot2d.plots import render_world_png, save_world_png

    world = sample_world()
    path = tmp_path / "world.png"
    save_world_png(world, path, dpi=50)
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    width, height = int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")
    assert width > height > 100  # a 20 m × 10 m world gives a landscape picture
    assert render_world_png(world, dpi=50) == data
    assert [p.name for p in tmp_path.iterdir()] == ["world.png"]


def test_save_world_png_into_missing_dir_leaves_nothing(tmp_path: Path) -> None:
    from albot2d.plots import save_world_png

    with pytest.raises(FileNotFoundError):
        save_world_png(sample_world(), tmp_path / "nope" / "world.png", dpi=30)
    assert list(tmp_path.iterdir()) == []


def test_free_space_holes_are_not_filled() -> None:
    import dataclasses

    import shapely
    from matplotlib.colors import to_rgb

    from albot2d.plots import FREE_SPACE_COLOR, plot_world

    world = sample_world()
    # A hole that is not clutter, so only the free-space fill decides its colour.
    holed = shapely.box(0, 0, 20, 10).difference(shapely.box(14, 6, 18, 9))
    world = dataclasses.replace(world, clutter=(), free_space=holed, dynamic_obstacles=())
    ax = plot_world(world, show_roadmap=False)
    ax.figure.canvas.draw()
    rgba = np.asarray(ax.figure.canvas.buffer_rgba())

    def colour_at(x: float, y: float) -> np.ndarray:
        px, py = ax.transData.transform((x, y))
        return rgba[rgba.shape[0] - int(py), int(px), :3] / 255.0

    free = np.array(to_rgb(FREE_SPACE_COLOR))
    assert np.allclose(colour_at(16.0, 7.5), 1.0, atol=0.02)  # the hole: white background
    assert np.allclose(colour_at(12.0, 3.0), free, atol=0.02)
