"""The figure of step time along a run (``steps.png``): where each view's time went.

``plot_step_times(data)`` draws, per view, the time waiting for the frame (the simulator
step), the shared extraction and each mapper's total, on a log scale so spikes (a local
map remembered, a global-map update) stand out; views where a mapper remembered a local
map are marked on its line. ``data`` is a run's ``StepTimes`` (``trace.step_times``) or
the columns of its ``steps.csv`` (e.g. ``read_steps_csv``). matplotlib is imported lazily.
"""

from __future__ import annotations

import io
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from albot2d.evaluation.trace import StepTimes

__all__ = ["plot_step_times", "read_steps_csv", "render_step_times_png"]

DEFAULT_DPI = 100


def read_steps_csv(path: str) -> dict[str, NDArray[np.float64]]:
    """The columns of a ``steps.csv`` written by ``albot2d run``/``replay``."""
    with open(path, encoding="utf-8") as handle:
        names = handle.readline().strip().split(",")
        data = np.loadtxt(handle, delimiter=",", ndmin=2)
    return {name: data[:, i] for i, name in enumerate(names)}


def _columns(data: StepTimes | Mapping[str, ArrayLike]) -> dict[str, NDArray[np.float64]]:
    names = getattr(data, "columns", data)
    if hasattr(data, "column"):
        return {name: data.column(name) for name in names}  # type: ignore[union-attr]
    return {name: np.asarray(v, np.float64) for name, v in data.items()}  # type: ignore[union-attr]


def plot_step_times(data: StepTimes | Mapping[str, ArrayLike], *, ax: Axes | None = None) -> Axes:
    """Per-view stage times along the run (log scale); returns the axes drawn on."""
    if ax is None:
        from matplotlib.figure import Figure

        ax = Figure(figsize=(10.0, 4.0), layout="constrained").subplots()
    cols = _columns(data)
    rows = np.arange(len(next(iter(cols.values())))) if cols else np.zeros(0)
    lines = [name for name in ("simulation_ms", "extraction_ms") if name in cols]
    lines += [name for name in cols if name.endswith(".total_ms")]
    for name in lines:
        v = np.maximum(cols[name], 1e-4)  # a log axis cannot show 0
        (line,) = ax.plot(rows, v, lw=0.6, label=name.removesuffix("_ms"))
        remembered = cols.get(name.removesuffix("total_ms") + "remembered")
        if remembered is not None and name.endswith(".total_ms"):
            at = np.flatnonzero(remembered > 0)
            ax.plot(rows[at], v[at], "|", ms=5, color=line.get_color(), alpha=0.7)
    ax.set_yscale("log")
    ax.set_xlabel("view")
    ax.set_ylabel("time per view (ms)")
    ax.set_title("step time along the run (| = local map remembered)")
    if lines:
        ax.legend(loc="upper right", fontsize="small", ncols=min(len(lines), 4))
    ax.grid(True, which="both", alpha=0.2)
    return ax


def render_step_times_png(
    data: StepTimes | Mapping[str, ArrayLike], *, dpi: int = DEFAULT_DPI
) -> bytes:
    """``plot_step_times`` as PNG bytes."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig: Any = Figure(figsize=(10.0, 4.0), layout="constrained")
    FigureCanvasAgg(fig)
    plot_step_times(data, ax=fig.subplots())
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    return buf.getvalue()
