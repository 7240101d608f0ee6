"""The figure of step time along a run (``steps.png``): where each view's time went.

``plot_step_times(data)`` draws the time per view of each stage (the simulator step, the
shared extraction, each mapper's total) stacked along the run, and each stage's
percentiles (median, p95, p99, max) beside it; views where a mapper remembered a local
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
    from matplotlib.figure import Figure

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


def _stages(cols: Mapping[str, NDArray[np.float64]]) -> list[str]:
    """The stages a view's time is spent in, in the order they run: the simulator step,
    the shared extraction, then each mapper's total (its own sub-stages are inside it)."""
    names = [name for name in ("simulation_ms", "extraction_ms") if name in cols]
    return names + [name for name in cols if name.endswith(".total_ms")]


def _label(name: str) -> str:
    return name.removesuffix("_ms").replace(".total", " (mapper)")


def _bin_medians(values: NDArray[np.float64], bins: int) -> tuple[NDArray, NDArray]:
    """Per bin of consecutive views: its middle view and the median time (robust to the
    rare slow view, which the percentile panel shows instead)."""
    n = len(values)
    edges = np.unique(np.linspace(0, n, min(bins, n) + 1).astype(np.int64))
    med = np.array([np.median(values[a:b]) for a, b in itertools.pairwise(edges)])
    return 0.5 * (edges[:-1] + edges[1:] - 1), med


def plot_step_times(
    data: StepTimes | Mapping[str, ArrayLike], *, fig: Figure | None = None, bins: int = 200
) -> Figure:
    """Where each view's time goes, two panels on ``fig`` (a new figure when None).

    Left: the time per view of each stage stacked (simulation, extraction, each mapper),
    the median over bins of consecutive views, so the top edge is a typical view's time
    and each band's thickness its stage's share; ticks along the bottom mark the views
    where Albot₁-like mappers remembered a local map. The first view (start-up: JIT
    compilation, the first global map) is left out of the areas and reported in the
    title. Right: each stage's percentiles over the run (median, p95, p99 and the
    slowest view, log scale), so rare spikes are read off rather than lost in a tangle.
    """
    from matplotlib import colormaps

    from albot2d.viz.furniture import LABEL_PT, LEGEND_PT, TICK_PT, TITLE_PT

    if fig is None:
        fig = new_figure(12.0, 4.2)
    ax, pc = fig.subplots(1, 2, width_ratios=(2.2, 1.0))
    cols = _columns(data)
    stages = _stages(cols)
    colours = colormaps["tab10"]
    n = len(next(iter(cols.values()))) if cols else 0
    first_ms = sum(float(cols[name][0]) for name in stages) if n else 0.0
    if n > 1 and stages:
        x = np.arange(n, dtype=np.float64)[1:]
        means = []
        for name in stages:
            xb, mb = _bin_medians(np.asarray(cols[name], np.float64)[1:], bins)
            means.append(mb)
        ax.stackplot(xb + 1.0, *means, labels=[_label(nm) for nm in stages],
                     colors=[colours(k % 10) for k in range(len(stages))], alpha=0.85,
                     linewidth=0.0)  # fmt: skip
        for k, name in enumerate(stages):
            remembered = cols.get(name.removesuffix("total_ms") + "remembered")
            if name.endswith(".total_ms") and remembered is not None:
                at = np.flatnonzero(np.asarray(remembered)[1:] > 0) + 1
                if 0 < len(at) <= len(remembered) // 2:
                    ax.plot(at, np.full(len(at), -0.04), "|", ms=5, color=colours(k % 10),
                            transform=ax.get_xaxis_transform(), clip_on=False)  # fmt: skip
        ax.set_xlim(1.0, max(float(x[-1]), 2.0))
        ax.set_ylim(bottom=0.0)
    ax.set_xlabel("view", fontsize=LABEL_PT)
    ax.set_ylabel(f"time per view (ms, median of {max(n // bins, 1)} views)", fontsize=LABEL_PT)
    ax.set_title(
        f"typical time per view by stage, stacked ({n} views; the first, {first_ms:.0f} ms "
        "of start-up, left out)\n| along the bottom: a local map remembered; rare slow "
        "views: see the percentiles",
        fontsize=TITLE_PT,
    )
    ax.tick_params(labelsize=TICK_PT)
    ax.grid(True, axis="y", alpha=0.3)
    if stages:
        ax.legend(loc="upper left", fontsize=LEGEND_PT, ncols=min(len(stages), 3),
                  framealpha=0.9)  # fmt: skip
    qs = (("median", 50.0, "o"), ("p95", 95.0, "s"), ("p99", 99.0, "^"), ("max", 100.0, "x"))
    y = np.arange(len(stages))[::-1]
    q_colours = {"median": "k", "p95": "#1565c0", "p99": "#ef6c00", "max": "#c62828"}
    for label, q, marker in qs:
        vals = [max(float(np.percentile(np.asarray(cols[nm])[1:] if n > 1 else cols[nm], q)),
                    1e-4) for nm in stages]  # fmt: skip
        pc.plot(vals, y, marker, ls="", ms=6, label=label, color=q_colours[label])
    for k, name in enumerate(stages):
        v = np.asarray(cols[name])[1:] if n > 1 else np.asarray(cols[name])
        lo, hi = np.percentile(v, [50.0, 99.0]) if len(v) else (0.0, 0.0)
        pc.plot([max(lo, 1e-4), max(hi, 1e-4)], [y[k]] * 2, "-", lw=6, alpha=0.35,
                color=colours(k % 10), solid_capstyle="butt")  # fmt: skip
    pc.set_xscale("log")
    pc.set_yticks(y, [_label(nm) for nm in stages], fontsize=TICK_PT)
    pc.set_xlabel("time per view (ms, log)", fontsize=LABEL_PT)
    pc.set_title("per-stage percentiles over the run", fontsize=TITLE_PT)
    pc.tick_params(axis="x", labelsize=TICK_PT)
    pc.grid(True, axis="x", which="both", alpha=0.25)
    pc.set_ylim(-0.7, len(stages) - 0.3)
    pc.legend(loc="upper center", bbox_to_anchor=(0.5, -0.18), ncols=4, fontsize=LEGEND_PT,
              frameon=False)  # fmt: skip
    return fig


def render_step_times_png(
    data: StepTimes | Mapping[str, ArrayLike], *, dpi: int = DEFAULT_DPI
) -> bytes:
    """``plot_step_times`` as PNG bytes."""
    return png_bytes(plot_step_times(data), dpi)
