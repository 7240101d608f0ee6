"""The Agg figure and PNG helpers every figure module of ``albot2d.viz`` shares.

Figures are built on the Agg canvas directly (no pyplot, no global backend switch), which
works headless and in threads; matplotlib is imported inside the functions.
"""

from __future__ import annotations

import gc
import io
from collections.abc import Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = [
    "colour_buckets",
    "figure_batch",
    "figure_of",
    "line_segments",
    "nan_lines",
    "new_figure",
    "png_bytes",
    "release_figure",
]


Layout = Literal["constrained", "compressed", "tight"] | None


def new_figure(width_in: float, height_in: float, *, layout: Layout = "constrained") -> Figure:
    """A matplotlib ``Figure`` of that size attached to an Agg canvas."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width_in, height_in), layout=layout)
    FigureCanvasAgg(fig)
    return fig


def figure_of(ax: Axes) -> Figure:
    """The ``Figure`` that ``ax`` is drawn on."""
    # ``Axes.figure`` is typed ``Figure | SubFigure``; the axes drawn here sit on a Figure.
    fig = ax.get_figure(root=True)
    assert fig is not None  # an Axes always belongs to a figure
    return fig


def line_segments(segments: ArrayLike) -> list[NDArray[np.float64]]:
    """``(N, 4)`` or ``(N, 2, 2)`` segments as the list of ``(2, 2)`` arrays that
    ``LineCollection`` is typed to take (a sequence of lines, not one 3-D array)."""
    return list(np.asarray(segments, dtype=np.float64).reshape(-1, 2, 2))


NAN_LINE_SEGMENTS = 2048
"""Segments per NaN-separated line: bounded so no single Agg path grows without limit."""


def nan_lines(
    segments: ArrayLike, *, per_line: int = NAN_LINE_SEGMENTS
) -> list[NDArray[np.float64]]:
    """``(N, 4)`` or ``(N, 2, 2)`` segments as a few ``(3k, 2)`` polylines, each segment
    followed by a NaN row (a pen-up: Agg removes NaNs, so the segments stay apart).

    ``LineCollection`` makes one ``Path`` object per line it is given: for the 820,000
    surfaces of a long run's naive map, one per segment cost ~1 KB each per figure; these
    lines cost the 48 bytes of their vertices. The paths are marked not to be simplified,
    so each segment is stroked as it would be alone (matplotlib simplifies long paths)."""
    segs = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
    lines: list[NDArray[np.float64]] = []
    for lo in range(0, len(segs), per_line):
        block = segs[lo : lo + per_line]
        line = np.full((len(block), 3, 2), np.nan)
        line[:, :2] = block.reshape(-1, 2, 2)
        lines.append(line.reshape(-1, 2))
    return lines


def colour_buckets(
    values: ArrayLike, clim: tuple[float, float], n_colours: int
) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.float64]]:
    """Group ``values`` by the colour a ``n_colours``-entry colour map gives them under
    ``clim`` (matplotlib's ``Normalize`` then ``Colormap`` arithmetic, so each group is one
    colour). Returns ``(order, starts, value)``: ``order`` sorts the values by group
    (stable, so draw order within a group is kept), group ``g`` is
    ``order[starts[g]:starts[g + 1]]`` and ``value[g]`` is one of its members' values
    (drawing the group with it gives every member its own colour)."""
    v = np.asarray(values, dtype=np.float64).ravel()
    lo, hi = float(clim[0]), float(clim[1])
    x = (v - lo) / (hi - lo) if hi > lo else np.zeros_like(v)
    x *= n_colours
    x[x == n_colours] = n_colours - 1
    idx = np.clip(x, -1, n_colours).astype(np.intp)  # -1 / n_colours: under / over
    order = np.argsort(idx, kind="stable")
    keys = idx[order]
    starts = (
        np.flatnonzero(np.r_[True, keys[1:] != keys[:-1]]) if len(keys) else np.zeros(0, np.intp)
    )
    return order, np.r_[starts, len(keys)].astype(np.intp), v[order[starts]]


def png_bytes(fig: Figure, dpi: float, *, release: bool = True) -> bytes:
    """``fig`` saved as PNG, in memory; then (``release``, the default) emptied with
    ``release_figure``, as every figure here is drawn once."""
    from albot2d.viz.furniture import png_metadata

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, metadata=png_metadata(fig), bbox_inches="tight",
                pad_inches=0.08)  # fmt: skip
    if release:
        release_figure(fig)
        if _batches:
            gc.collect()  # only what was made since figure_batch began: see there
    return buf.getvalue()


_batches: list[None] = []  # open figure_batch contexts (a list: nested or in threads)


@contextmanager
def figure_batch() -> Iterator[None]:
    """Draw several figures: each one's garbage is collected as soon as it is saved.

    A released figure still leaves its axes, ticks and texts to the cyclic collector,
    which runs a full collection rarely: a run's dozen figures piled up ~11 MB at its
    memory peak. Collecting after each is cheap here because the objects that existed
    before the batch are frozen (``gc.freeze``) and not traversed again: ~10 ms a figure,
    not ~150 ms for the whole heap of a run."""
    if not _batches:
        gc.freeze()
    _batches.append(None)
    try:
        yield
    finally:
        _batches.pop()
        if not _batches:
            gc.unfreeze()


def release_figure(fig: Figure) -> None:
    """Free what a saved figure holds: its artists (``Figure.clear``) and its Agg canvas,
    whose renderer keeps the whole RGBA buffer (8 MB for the 4-panel overview at 100 dpi).

    A figure is a web of reference cycles (figure, axes, artists, canvas), so dropping it
    leaves all of that to the cyclic garbage collector, which may run figures later; a run
    drawing a dozen figures held them all at its memory peak."""
    from matplotlib.backend_bases import FigureCanvasBase

    fig.clear()
    FigureCanvasBase(fig)  # the figure's canvas now: the Agg one and its buffer are freed
