"""Map completeness measured against only the surfaces near the seen points (issue 12,
memory of long runs): the same share as against the whole map, and no surface within
reach of a seen point is ever left out."""

from __future__ import annotations

import importlib

import numpy as np
import pytest
import shapely

from albot2d.evaluation.metrics.map_quality import (
    MapQualityParams,
    map_quality,
    nearest_segment_distance,
)
from albot2d.geometry import Pose

# The module (``albot2d.evaluation.metrics.map_quality`` the attribute is the function).
mq = importlib.import_module("albot2d.evaluation.metrics.map_quality")


def _map(rng: np.random.Generator, n: int, span: float) -> np.ndarray:
    a = rng.uniform(0.0, span, (n, 2))
    return np.hstack([a, a + rng.normal(0.0, 0.3, (n, 2))])


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("reach_m", [0.01, 0.1, 0.75, 3.0])
def test_near_points_never_drops_a_surface_within_reach(
    seed: int, reach_m: float, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(mq, "_NEAR_BLOCK", 97 * (seed + 1))  # several blocks, a ragged last one
    rng = np.random.default_rng(seed)
    segs = _map(rng, 4000, 40.0)
    segs[:50, 2:] = segs[:50, :2]  # points as segments too
    centre = rng.uniform(5.0, 35.0, 2)
    pts = centre + rng.normal(0.0, 3.0, (300, 2))
    keep = mq._near_points(segs, pts, reach_m)
    dist = shapely.distance(shapely.linestrings(segs.reshape(-1, 2, 2)), shapely.multipoints(pts))
    assert not np.any(~keep & (dist <= reach_m))  # every surface that may cover is kept
    assert keep.mean() < 0.6  # and it does leave the far ones out


@pytest.mark.parametrize("seed", range(4))
def test_completeness_is_the_share_against_the_whole_map(seed: int) -> None:
    rng = np.random.default_rng(seed)
    segs = _map(rng, 3000, 30.0)
    truth = _map(rng, 200, 30.0)
    seen = rng.uniform(10.0, 16.0, (500, 2))
    tol = MapQualityParams().coverage_tolerance_m
    q = map_quality(segs, truth, start_pose=Pose(0.0, 0.0, 0.0), seen_points=seen)
    whole = float(np.mean(nearest_segment_distance(seen, segs) <= tol))
    assert q.completeness == whole and 0.0 < whole < 1.0
    far = map_quality(segs, truth, start_pose=Pose(0.0, 0.0, 0.0), seen_points=seen + 500.0)
    assert far.completeness == 0.0
