"""The map-quality and egocentric measures' fast paths give the reference results exactly."""

from __future__ import annotations

import numpy as np
import pytest

from albot2d.evaluation.metrics.egocentric import _covered, _grid_samples_within, unique_on_grid
from albot2d.evaluation.metrics.map_quality import (
    nearest_segment_distance,
    nearest_segment_distance_bounded,
    sample_segments,
)
from albot2d.geometry import segment_lengths


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


def random_map(rng: np.random.Generator, n: int) -> np.ndarray:
    """``n`` overlapping 0.2–3 m surfaces in a 40 m square, as a naive map's are."""
    a = rng.uniform(-20.0, 20.0, (n, 2))
    ang, length = rng.uniform(-np.pi, np.pi, n), rng.uniform(0.2, 3.0, n)
    return np.hstack([a, a + length[:, None] * np.column_stack([np.cos(ang), np.sin(ang)])])


def test_covered_equals_nearest_distance_within_tolerance() -> None:
    rng = np.random.default_rng(2)
    segs = np.vstack([random_map(rng, 3000), [[0.0, 0.0, 1.0, 0.0]]])
    pts = np.vstack([rng.uniform(-21.0, 21.0, (20_000, 2)),
                     [[0.5, 0.25], [0.5, -0.25], [1.25, 0.0], [0.5, 0.2500001]]])  # fmt: skip
    expected = nearest_segment_distance(pts, segs) <= 0.25
    got = _covered(pts, segs, 0.25)
    np.testing.assert_array_equal(got, expected)
    assert got[-4:].tolist() == [True, True, True, False]  # exactly at the tolerance: in
    assert not _covered(pts, np.zeros((0, 4)), 0.25).any()


@pytest.mark.parametrize("reach_m", [0.5, 7.0, 100.0])
def test_grid_samples_within_reach_equal_sampling_everything(reach_m: float) -> None:
    rng = np.random.default_rng(3)
    segs = random_map(rng, 4000)
    everything = unique_on_grid(sample_segments(segs, 0.05), 0.05)
    expected = everything[np.hypot(everything[:, 0], everything[:, 1]) <= reach_m]
    np.testing.assert_array_equal(_grid_samples_within(segs, 0.05, 0.05, reach_m), expected)


def reference_sample_segments(segs: np.ndarray, spacing_m: float) -> np.ndarray:
    """The rows-by-owner formulation sample_segments replaced."""
    counts = np.maximum(np.ceil(segment_lengths(segs) / spacing_m).astype(np.int64), 1) + 1
    owner = np.repeat(np.arange(len(segs)), counts)
    starts = np.cumsum(counts) - counts
    t = (np.arange(counts.sum()) - starts[owner]) / (counts[owner] - 1)
    a, b = segs[owner, :2], segs[owner, 2:]
    return a + t[:, None] * (b - a)


@pytest.mark.parametrize("spacing_m", [0.05, 0.37])
def test_sample_segments_equals_the_gathering_formulation_bit_for_bit(spacing_m: float) -> None:
    rng = np.random.default_rng(6)
    segs = rng.uniform(-30.0, 30.0, (3000, 4))
    segs[:50, 2:] = segs[:50, :2]  # zero-length surfaces: two samples on the point
    got, expected = sample_segments(segs, spacing_m), reference_sample_segments(segs, spacing_m)
    assert got.shape == expected.shape
    np.testing.assert_array_equal(got.view(np.int64), expected.view(np.int64))


def test_bounded_nearest_distance_equals_the_tree_bit_for_bit() -> None:
    """Near points (found within the first radius), middling ones (the second) and far
    ones (the tree's nearest query) alike."""
    rng = np.random.default_rng(8)
    walls = random_map(rng, 400)
    pts = np.vstack([sample_segments(walls, 0.05) + rng.normal(0.0, 0.2, (1, 2)),
                     rng.uniform(-60.0, 60.0, (5000, 2))])  # fmt: skip
    got = nearest_segment_distance_bounded(pts, walls)
    expected = nearest_segment_distance(pts, walls)
    np.testing.assert_array_equal(got.view(np.int64), expected.view(np.int64))
    assert (expected > 2.0).sum() > 1000 and (expected <= 0.5).sum() > 1000
    assert len(nearest_segment_distance_bounded(np.zeros((0, 2)), walls)) == 0
    assert np.isinf(nearest_segment_distance_bounded(pts[:3], np.zeros((0, 4)))).all()


def test_within_a_tolerance_the_bounded_query_answers_as_the_tree() -> None:
    """``beyond="inf"`` (completeness: only "within the tolerance" is asked) gives the
    same verdict for every point as the tree's nearest distance, points at the tolerance
    included, and inf only past it."""
    rng = np.random.default_rng(9)
    walls = random_map(rng, 300)
    tol = 0.1
    pts = np.vstack([sample_segments(walls, 0.05) + rng.normal(0.0, 0.1, (1, 2)),
                     rng.uniform(-60.0, 60.0, (3000, 2))])  # fmt: skip
    expected = nearest_segment_distance(pts, walls)
    got = nearest_segment_distance_bounded(pts, walls, (tol,), beyond="inf")
    np.testing.assert_array_equal(got <= tol, expected <= tol)
    assert (expected <= tol).sum() > 1000 and (expected > tol).sum() > 1000
    assert np.isinf(got[expected > tol]).all()
    with pytest.raises(ValueError, match="beyond must be"):
        nearest_segment_distance_bounded(pts, walls, beyond="none")
