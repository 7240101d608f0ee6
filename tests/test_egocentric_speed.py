"""The egocentric measure's fast paths give the reference results exactly."""

from __future__ import annotations

import numpy as np

from albot2d.evaluation.egocentric import unique_on_grid


def reference_unique_on_grid(points: np.ndarray, grid_m: float) -> np.ndarray:
    """The first point of each occupied cell in input order, by unique rows."""
    _, first = np.unique(np.floor(points / grid_m).astype(np.int64), axis=0, return_index=True)
    return points[np.sort(first)]


def test_unique_on_grid_equals_unique_rows_on_a_dense_cloud() -> None:
    rng = np.random.default_rng(5)
    pts = rng.uniform(-20.0, 20.0, (50_000, 2))
    pts = np.vstack([pts, pts[:5000] + 1e-4, np.round(pts[5000:9000], 1)])  # shared cells
    out = unique_on_grid(pts, 0.05)
    np.testing.assert_array_equal(out, reference_unique_on_grid(pts, 0.05))
    assert 0 < len(out) < len(pts)


def test_unique_on_grid_far_apart_cells_use_the_row_path() -> None:
    """Cells too far apart for one int64 key (span ≥ 2^62) take the unique-rows path."""
    pts = np.array([[-1e17, 0.0], [1e17, 3e2], [1e17, 3e2], [0.0, -1e17], [0.0, 1e17]])
    np.testing.assert_array_equal(unique_on_grid(pts, 0.05), reference_unique_on_grid(pts, 0.05))
