"""The Agg figure and PNG helpers every figure module of ``albot2d.viz`` shares.

Figures are built on the Agg canvas directly (no pyplot, no global backend switch), which
works headless and in threads; matplotlib is imported inside the functions.
"""

from __future__ import annotations

import io
from typing import TYPE_CHECKING, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["line_segments", "new_figure", "png_bytes"]


Layout = Literal["constrained", "compressed", "tight"] | None


def new_figure(width_in: float, height_in: float, *, layout: Layout = "constrained") -> Figure:
    """A matplotlib ``Figure`` of that size attached to an Agg canvas."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width_in, height_in), layout=layout)
    FigureCanvasAgg(fig)
    return fig


def line_segments(segments: ArrayLike) -> list[NDArray[np.float64]]:
    """``(N, 4)`` or ``(N, 2, 2)`` segments as the list of ``(2, 2)`` arrays that
    ``LineCollection`` is typed to take (a sequence of lines, not one 3-D array)."""
    return list(np.asarray(segments, dtype=np.float64).reshape(-1, 2, 2))


def png_bytes(fig: Figure, dpi: float) -> bytes:
    """``fig`` saved as PNG, in memory."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    return buf.getvalue()
