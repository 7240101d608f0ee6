"""Egocentric map quality's grid deduplication: one int64 key per cell against unique rows.

Run: ``python -m pytest benchmarks/test_egocentric.py --benchmark-only``. 400,000 samples
of 20,000 overlapping surfaces (a long run's naive map near the robot); both give the
same points (``tests/test_egocentric_speed.py``).
"""

from __future__ import annotations

import numpy as np
import pytest

from albot2d.evaluation.metrics.egocentric import unique_on_grid
from albot2d.evaluation.metrics.map_quality import sample_segments


def unique_rows(points: np.ndarray, grid_m: float) -> np.ndarray:
    """The previous implementation: unique rows of the cell indices (axis=0)."""
    _, first = np.unique(np.floor(points / grid_m).astype(np.int64), axis=0, return_index=True)
    return points[np.sort(first)]


@pytest.mark.benchmark(group="egocentric grid dedup (400k samples)")
@pytest.mark.parametrize("how", ["int64 key", "unique rows"])
def test_unique_on_grid(benchmark, how: str) -> None:  # type: ignore[no-untyped-def]
    rng = np.random.default_rng(0)
    a = rng.uniform(-20.0, 20.0, (20_000, 2))
    ang = rng.uniform(-np.pi, np.pi, 20_000)
    segs = np.hstack([a, a + np.column_stack([np.cos(ang), np.sin(ang)])])
    pts = sample_segments(segs, 0.05)[:400_000]
    fn = unique_on_grid if how == "int64 key" else unique_rows
    assert len(benchmark(fn, pts, 0.05)) > 100_000
