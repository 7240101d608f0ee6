"""World plots: real matplotlib rendering to PNG; ``albot2d.viz`` imports without matplotlib."""

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


# Every module of the package, imported in a fresh interpreter: none may load matplotlib
# (it is the optional ``viz`` extra, and slow to import), and all import where it is absent.
_IMPORT_ALL_VIZ = """
import importlib, pkgutil, sys
{block}
import albot2d.viz
names = [m.name for m in pkgutil.iter_modules(albot2d.viz.__path__, "albot2d.viz.")]
for name in names:
    importlib.import_module(name)
print(len(names), sorted(m for m, mod in sys.modules.items()
             if m.split(".")[0] == "matplotlib" and mod is not None))
"""


@pytest.mark.parametrize("block", ["", "sys.modules['matplotlib'] = None"])
def test_viz_package_imports_without_matplotlib(block: str) -> None:
    code = _IMPORT_ALL_VIZ.format(block=block)
    out = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True,
                         timeout=120)  # fmt: skip
    assert out.returncode == 0, out.stderr
    count, loaded = out.stdout.strip().split(" ", 1)
    assert int(count) >= 10  # world, paths, maps, run_figures, anim, steps, campaign, paper, …
    assert loaded == "[]"


def test_plot_world_draws_everything_on_given_axes() -> None:
    from matplotlib.figure import Figure

    from albot2d.viz.world import plot_world

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
    from albot2d.viz.world import plot_world

    world = sample_world()

    def count(show: bool) -> int:
        ax = plot_world(world, show_roadmap=show)
        return sum(len(c.get_segments()) for c in ax.collections if hasattr(c, "get_segments"))

    assert count(True) - count(False) == len(world.roadmap.edges)


def test_save_world_png_writes_a_png(tmp_path: Path) -> None:
    from albot2d.viz.world import render_world_png, save_world_png

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
    from albot2d.viz.world import save_world_png

    with pytest.raises(FileNotFoundError):
        save_world_png(sample_world(), tmp_path / "nope" / "world.png", dpi=30)
    assert list(tmp_path.iterdir()) == []


def test_free_space_holes_are_not_filled() -> None:
    import dataclasses

    import shapely
    from matplotlib.colors import to_rgb

    from albot2d.viz.world import FREE_SPACE_COLOR, plot_world

    world = sample_world()
    # A hole that is not clutter, so only the free-space fill decides its colour.
    holed = shapely.box(0, 0, 20, 10).difference(shapely.box(14, 6, 18, 9))
    world = dataclasses.replace(world, clutter=(), free_space=holed, dynamic_obstacles=())
    ax = plot_world(world, show_roadmap=False)
    ax.get_figure(root=True).canvas.draw()
    rgba = np.asarray(ax.get_figure(root=True).canvas.buffer_rgba())

    def colour_at(x: float, y: float) -> np.ndarray:
        px, py = ax.transData.transform((x, y))
        return rgba[rgba.shape[0] - int(py), int(px), :3] / 255.0

    free = np.array(to_rgb(FREE_SPACE_COLOR))
    assert np.allclose(colour_at(16.0, 7.5), 1.0, atol=0.02)  # the hole: white background
    assert np.allclose(colour_at(12.0, 3.0), free, atol=0.02)
