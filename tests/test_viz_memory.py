"""Big segment sets drawn without a Path object per segment (issue 12, memory of long
runs): ``nan_lines`` keeps every segment, ``colour_buckets`` gives every surface its own
colour of the map, and ``plot_map`` draws the same picture as one line per surface."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from albot2d.viz._figure import colour_buckets, nan_lines, new_figure
from albot2d.viz.maps import MAP_CMAP, map_surfaces, plot_map


def _segments(n: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    a = rng.uniform(0.0, 20.0, (n, 2))
    return np.hstack([a, a + rng.normal(0.0, 1.0, (n, 2))])


def _unnan(lines: list[np.ndarray]) -> np.ndarray:
    """The segments back from NaN-separated lines: every pair of finite rows between NaNs."""
    rows = np.vstack(lines)
    assert np.isnan(rows[2::3]).all()  # a pen-up after every segment
    return np.hstack([rows[0::3], rows[1::3]])


@pytest.mark.parametrize(("n", "per_line"), [(0, 4), (1, 4), (7, 3), (9, 3), (1000, 64)])
def test_nan_lines_keep_every_segment_in_order(n: int, per_line: int) -> None:
    segs = _segments(n)
    lines = nan_lines(segs, per_line=per_line)
    assert len(lines) == -(-n // per_line)
    assert all(len(line) <= 3 * per_line for line in lines)
    got = _unnan(lines) if lines else np.zeros((0, 4))
    assert np.array_equal(got, segs)
    assert np.array_equal(_unnan(nan_lines(segs.reshape(-1, 2, 2))) if n else got, segs)


@pytest.mark.parametrize("clim", [(0, 9), (0, 5000), (3, 4000), (100, 101)])
def test_colour_buckets_give_each_member_its_own_colour(clim: tuple[int, int]) -> None:
    from matplotlib import colormaps
    from matplotlib.colors import Normalize

    cmap = colormaps[MAP_CMAP]
    ids = np.random.default_rng(1).integers(clim[0], clim[1] + 1, 5000)
    order, starts, value = colour_buckets(ids, clim, cmap.N)
    assert np.array_equal(np.sort(order), np.arange(len(ids)))  # every member once
    assert len(value) == len(starts) - 1 <= cmap.N
    norm = Normalize(*clim)
    colours = cmap(norm(ids.astype(np.float64)))
    for g, v in enumerate(value):
        members = order[starts[g] : starts[g + 1]]
        assert np.all(np.diff(members) > 0)  # draw order kept within a colour
        assert np.array_equal(colours[members], np.broadcast_to(cmap(norm(v)), (len(members), 4)))
    # Distinct groups are distinct colours: nothing was merged that the map tells apart.
    assert len({tuple(cmap(norm(v))) for v in value}) == len(value)


def _pixels(draw: Callable[[Any], object]) -> np.ndarray:
    fig = new_figure(4.0, 4.0, layout=None)
    ax = fig.add_axes((0.0, 0.0, 1.0, 1.0))
    draw(ax)
    ax.set_xlim(-2, 22)
    ax.set_ylim(-2, 22)
    ax.set_axis_off()
    fig.canvas.draw()
    return np.asarray(fig.canvas.buffer_rgba())[..., :3].astype(int)


def test_plot_map_draws_the_picture_of_one_line_per_surface() -> None:
    """The map drawn as NaN-separated lines per colour against the reference drawing
    (a LineCollection of one (2, 2) line per surface, coloured by its id): the same
    pixels but for antialiased edges where surfaces of one colour cross."""
    from matplotlib.collections import LineCollection

    segs = _segments(3000, seed=3)
    ids = np.sort(np.random.default_rng(4).integers(0, 700, len(segs)))

    def reference(ax: Any) -> None:
        lines = LineCollection(list(segs.reshape(-1, 2, 2)), linewidths=1.6, cmap=MAP_CMAP)
        lines.set_array(ids.astype(np.float64))
        lines.set_clim(0, 699)
        ax.add_collection(lines)

    new = _pixels(lambda ax: plot_map(segs, map_ids=ids, ax=ax, id_range=(0, 699)))
    ref = _pixels(reference)
    differ = np.any(new != ref, axis=-1)
    inked = np.any(ref != 255, axis=-1)
    assert inked.mean() > 0.2  # a dense picture, so the comparison means something
    assert differ.mean() < 0.02, f"{differ.mean():.2%} of the pixels differ"
    assert np.abs(new - ref).max(axis=-1)[differ].mean() < 40  # and only slightly


def test_map_surfaces_carry_every_surface_once() -> None:
    segs = _segments(5000, seed=5)
    ids = np.arange(len(segs)) // 7
    ax = plot_map(segs, map_ids=ids)
    lines = map_surfaces(ax)
    drawn = [np.asarray(p.vertices) for p in lines.get_paths()]
    assert len(drawn) < len(segs) / 10  # a few lines, not one per surface
    got = _unnan(drawn)
    assert np.array_equal(got[np.lexsort(got.T[::-1])], segs[np.lexsort(segs.T[::-1])])
    lo, hi = lines.get_clim()
    assert (lo, hi) == (0, ids.max())
