"""The step-time figure: drawn from a run's StepTimes or its steps.csv, matplotlib lazily."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from albot2d.evaluation.run.trace import StepTimes

pytest.importorskip("matplotlib")

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def some_steps() -> StepTimes:
    steps = StepTimes()
    rng = np.random.default_rng(0)
    for view in range(50):
        row = {
            "view": view,
            "simulation_ms": 0.1,
            "extraction_ms": 0.05,
            "albot1.tracking_ms": float(rng.uniform(0.1, 0.3)),
            "albot1.total_ms": float(rng.uniform(0.5, 1.0)),
            "albot1.remembered": view % 7 == 0,
        }
        if view % 7 == 0:  # a stage only some views run: 0 elsewhere
            row["albot1.global_map_ms"] = 2.0
            row["albot1.total_ms"] += 2.0
        steps.add_row(row)  # type: ignore[arg-type]
    return steps


def test_step_times_table_fills_missing_stages_and_round_trips_through_csv(
    tmp_path: Path,
) -> None:
    from albot2d.viz.steps import read_steps_csv

    steps = some_steps()
    assert steps.rows == 50
    gm = steps.column("albot1.global_map_ms")
    assert list(np.flatnonzero(gm)) == list(range(0, 50, 7))
    path = tmp_path / "steps.csv"
    path.write_text(steps.to_csv())
    back = read_steps_csv(str(path))
    assert set(back) == set(steps.columns)
    np.testing.assert_allclose(back["albot1.total_ms"], steps.column("albot1.total_ms"),
                               atol=1e-4)  # fmt: skip
    summary = steps.summary_ms()
    assert summary["albot1.global_map"]["max"] == 2.0 and summary["albot1.global_map"]["p50"] == 0
    assert "albot1.remembered" not in summary and "view" not in summary


def test_plot_step_times_stacks_every_stage_and_marks_the_remembered_views() -> None:
    from matplotlib.collections import PolyCollection

    from albot2d.viz.steps import plot_step_times, render_step_times_png

    fig = plot_step_times(some_steps(), bins=10)
    stacked, percentiles = fig.axes[:2]
    bands = [c for c in stacked.collections if isinstance(c, PolyCollection)]
    labels = [c.get_label() for c in bands]
    assert {"simulation", "extraction", "albot1 (mapper)"} <= set(labels)
    marks = [line for line in stacked.get_lines() if line.get_marker() == "|"]
    # views 7, 14, ... (view 0, start-up, is left out of the stacked areas)
    assert len(marks) == 1 and len(marks[0].get_xdata()) == len(range(7, 50, 7))
    assert percentiles.get_xscale() == "log"
    ticks = [t.get_text() for t in percentiles.get_yticklabels()]
    assert "albot1 (mapper)" in ticks and "simulation" in ticks
    assert render_step_times_png(some_steps()).startswith(PNG_MAGIC)
