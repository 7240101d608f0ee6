"""The figure of step time along a run (``steps.png``): where each view's time went.

``plot_step_times(data)`` draws, per view, the time waiting for the frame (the simulator
step), the shared extraction and each mapper's total, on a log scale so spikes (a local
map remembered, a global-map update) stand out; views where a mapper remembered a local
map are marked along the bottom. ``data`` is a run's ``StepTimes`` (``trace.step_times``) or
the columns of its ``steps.csv`` (e.g. ``read_steps_csv``). matplotlib is imported lazily.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from albot2d.viz._figure import new_figure, png_bytes

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from albot2d.evaluation.run.trace import StepTimes

__all__ = ["plot_step_times", "read_steps_csv", "render_step_times_png"]

DEFAULT_DPI = 100


def read_steps_csv(path: str) -> dict[str, NDArray[np.float64]]:
    """The columns of a ``steps.csv`` written by ``albot2d run``/``replay``."""
    with open(path, encoding="utf-8") as handle:
        names = handle.readline().strip().split(",")
        data = np.loadtxt(handle, delimiter=",", ndmin=2)
    return {name: data[:, i] for i, name in enumerate(names)}


def _columns(data: StepTimes | Mapping[str, ArrayLike]) -> dict[str, NDArray[np.float64]]:
    from albot2d.evaluation.run.trace import StepTimes

    if isinstance(data, StepTimes):
        return {name: data.column(name) for name in data.columns}
    return {name: np.asarray(v, np.float64) for name, v in data.items()}


def _binned(values: NDArray[np.float64], bins: int) -> tuple[NDArray, NDArray, NDArray]:
    """Per bin of consecutive views: first view, median and max (all views if few)."""
    if len(values) <= bins:
        rows = np.arange(len(values), dtype=np.float64)
        return rows, values, values
    edges = np.linspace(0, len(values), bins + 1).astype(np.int64)
    med = np.array([np.median(values[a:b]) for a, b in itertools.pairwise(edges)])
    top = np.maximum.reduceat(values, edges[:-1])
    return edges[:-1].astype(np.float64), med, top


def plot_step_times(
    data: StepTimes | Mapping[str, ArrayLike], *, ax: Axes | None = None, bins: int = 400
) -> Axes:
    """Per-view stage times along the run (log scale); returns the axes drawn on.

    Runs longer than ``bins`` views are drawn per bin of consecutive views: the median
    (solid) and the slowest view (faint), so spikes stay visible. Ticks along the bottom
    mark the views where a mapper remembered a local map (mappers that remember only some
    views: Albot1, not the integrators that keep every view)."""
    if ax is None:
        ax = new_figure(10.0, 4.0).add_subplot()
    cols = _columns(data)
    lines: list[str] = [name for name in ("simulation_ms", "extraction_ms") if name in cols]
    lines += [name for name in cols if name.endswith(".total_ms")]
    for name in lines:
        v = np.maximum(cols[name], 1e-4)  # a log axis cannot show 0
        x, med, top = _binned(v, bins)
        (line,) = ax.plot(x, med, lw=1.0, label=name.removesuffix("_ms"))
        if len(v) > bins:
            ax.plot(x, top, lw=0.5, alpha=0.35, color=line.get_color())
        remembered = cols.get(name.removesuffix("total_ms") + "remembered")
        if name.endswith(".total_ms") and remembered is not None:
            at = np.flatnonzero(remembered > 0)
            if 0 < len(at) <= len(remembered) // 2:
                ax.plot(at, np.full(len(at), 0.03), "|", ms=6, color=line.get_color(),
                        alpha=0.6, transform=ax.get_xaxis_transform())  # fmt: skip
    ax.set_yscale("log")
    ax.set_xlabel("view")
    ax.set_ylabel("time per view (ms)")
    ax.set_title("step time along the run (faint: slowest view per bin; | local map remembered)")
    if lines:
        ax.legend(loc="upper right", fontsize="small", ncols=min(len(lines), 4))
    ax.grid(True, which="both", alpha=0.2)
    return ax


def render_step_times_png(
    data: StepTimes | Mapping[str, ArrayLike], *, dpi: int = DEFAULT_DPI
) -> bytes:
    """``plot_step_times`` as PNG bytes."""
    fig = new_figure(10.0, 4.0)
    plot_step_times(data, ax=fig.subplots())
    return png_bytes(fig, dpi)
