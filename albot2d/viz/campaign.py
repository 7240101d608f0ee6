"""The fuzzing campaign's figure: histograms of homing and pose errors over all episodes.

``plot_campaign_histograms(records, *, fig=None) -> Figure`` (a figure-level composite, six
panels); ``render_campaign_histograms_png`` gives it as PNG bytes. matplotlib (the ``viz``
extra) is imported inside the functions; the figure is drawn on the Agg canvas directly.
Panels comparing the mapper with raw odometry say in how many episodes it was better,
worse or tied (``campaign_summary.mapper_vs_odometry``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from albot2d.evaluation.fuzz.summary import mapper_vs_odometry
from albot2d.viz._figure import new_figure, png_bytes

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["plot_campaign_histograms", "render_campaign_histograms_png"]

MAPPER_COLOR = "#1f77b4"
ODOMETRY_COLOR = "#9e9e9e"
BINS = 30
DEFAULT_DPI = 110
# (title, mapper's metric, odometry's metric or None, unit)
PANELS = (
    ("homing: worst bearing error per episode", "homing_bearing_error_max_deg", None, "deg"),
    ("homing: worst distance error per episode", "homing_distance_error_max_m", None, "m"),
    ("RPE rotation (mean per episode)", "rpe_rot_deg", "odometry_rpe_rot_deg", "deg"),
    ("RPE translation (mean per episode)", "rpe_trans_m", "odometry_rpe_trans_m", "m"),
    (
        "worst heading error per episode",
        "heading_error_max_deg",
        "odometry_heading_error_max_deg",
        "deg",
    ),
    (
        "mean heading error per episode",
        "heading_error_mean_deg",
        "odometry_heading_error_mean_deg",
        "deg",
    ),
)


def _values(records: Sequence[Mapping[str, Any]], name: str) -> np.ndarray:
    out = [
        r["metrics"][name]
        for r in records
        if isinstance(r.get("metrics", {}).get(name), int | float)
    ]
    return np.asarray(out, dtype=np.float64)


def plot_campaign_histograms(
    records: Sequence[Mapping[str, Any]], *, fig: Figure | None = None
) -> Figure:
    """One histogram per error metric over the campaign's episode ``records``, the mapper
    against raw odometry, on ``fig`` (a new figure when None); returns the figure."""
    if fig is None:
        fig = new_figure(12.0, 6.5)
    axes = fig.subplots(2, 3).ravel()
    mapper = next((r["mapper"] for r in records if r.get("mapper")), "mapper")
    comparison = mapper_vs_odometry(records)
    for ax, (title, mine, odometry, unit) in zip(axes, PANELS, strict=True):
        series = [(mapper, _values(records, mine), MAPPER_COLOR)]
        if odometry is not None:
            series.append(("odometry", _values(records, odometry), ODOMETRY_COLOR))
        present = [s for s in series if len(s[1])]
        ax.set_title(title, fontsize=10)
        ax.set_xlabel(unit)
        if not present:
            ax.text(0.5, 0.5, "no values", ha="center", va="center", transform=ax.transAxes)
            continue
        top = max(float(v.max()) for _, v, _ in present)
        bins = np.linspace(0.0, top if top > 0 else 1.0, BINS + 1)
        for label, values, color in present:
            ax.hist(
                values,
                bins=bins,
                color=color,
                alpha=0.6,
                label=f"{label} (median {np.median(values):.3g})",
            )
        ax.set_ylabel("episodes")
        cmp = comparison.get(mine) if odometry is not None else None
        summary = (
            f"{mapper}: better in {cmp['mapper_better']}, worse in {cmp['mapper_worse']},"
            f"\ntied in {cmp['ties']} of {cmp['episodes']} episodes"
            if cmp
            else None
        )
        ax.legend(fontsize=8, title=summary, title_fontsize=8)
    fig.suptitle(f"fuzzing campaign: {len(records)} episodes, {mapper}")
    return fig


def render_campaign_histograms_png(
    records: Sequence[Mapping[str, Any]], *, dpi: int = DEFAULT_DPI
) -> bytes:
    """``plot_campaign_histograms`` as PNG bytes (``histograms.png`` of ``albot2d fuzz``)."""
    return png_bytes(plot_campaign_histograms(records), dpi)
