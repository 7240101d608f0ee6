"""The grid index forgets removed segments; the global map keeps only live ids in it."""

from __future__ import annotations

import numpy as np
import shapely
from hypothesis import given
from hypothesis import strategies as st

from albot2d.geometry import Pose
from albot2d.mapping import GlobalMap, GlobalMapParams
from albot2d.mapping.spatial_index import SegmentGridIndex, sorted_unique


def random_segments(rng: np.random.Generator, n: int) -> np.ndarray:
    a = rng.uniform(-30.0, 30.0, (n, 2))
    return np.hstack([a, a + rng.uniform(-4.0, 4.0, (n, 2))])


def test_removed_ids_leave_queries_and_live_ones_stay_found() -> None:
    rng = np.random.default_rng(4)
    segs = random_segments(rng, 2000)
    idx = SegmentGridIndex(2.0)
    idx.insert(np.arange(len(segs)), segs)
    gone = rng.choice(len(segs), 1500, replace=False)
    idx.remove(gone, segs[gone])
    idx.remove(gone[:10], segs[gone[:10]])  # twice: ignored
    live = np.setdiff1d(np.arange(len(segs)), gone)
    lines = shapely.linestrings(segs.reshape(-1, 2, 2))
    for x, y, w, h in rng.uniform([-35, -35, 0.1, 0.1], [30, 30, 25, 25], (30, 4)):
        found = idx.query_box(x, y, x + w, y + h)
        assert np.all(np.diff(found) > 0)  # sorted, unique
        assert not np.isin(found, gone).any()
        truth = np.flatnonzero(shapely.intersects(shapely.box(x, y, x + w, y + h), lines))
        assert set(np.intersect1d(truth, live).tolist()) <= set(found.tolist())
    idx.remove(live, segs[live])
    assert idx._cells == {}  # every cell emptied is dropped


def test_global_map_index_holds_exactly_the_live_surfaces_after_deletions() -> None:
    # Both rules: 'paper' deletes more (the count below), 'visible' is the default.
    for params in (GlobalMapParams.preset("paper"), GlobalMapParams()):
        _check_index_after_deletions(params)


def _check_index_after_deletions(params: GlobalMapParams) -> None:
    rng = np.random.default_rng(1)
    g = GlobalMap(params)
    deleted = 0
    for map_id in range(60):  # views around one room: later ones delete earlier ones
        pose = Pose(*rng.uniform(-1.0, 1.0, 2), rng.uniform(-np.pi, np.pi))
        ang = pose.theta + np.linspace(-1.2, 1.2, 8)
        r = rng.uniform(2.0, 5.0, 8)
        pts = np.column_stack([pose.x + r * np.cos(ang), pose.y + r * np.sin(ang)])
        segs = np.hstack([pts, pts + 0.5 * np.column_stack([-np.sin(ang), np.cos(ang)])])
        report = g.add_view(segs, map_id, pose)
        deleted += report.deleted_current + report.deleted_older
    indexed = set().union(*g._index._cells.values())
    alive = set(np.flatnonzero(g._removed[: g._n] == np.iinfo(np.int64).max).tolist())
    assert deleted > 50
    assert indexed == alive and len(alive) == len(g)


@given(st.lists(st.integers(-(2**40), 2**40), max_size=300))
def test_sorted_unique_is_numpys_unique(values: list[int]) -> None:
    ids = np.asarray(values, dtype=np.int64)
    got = sorted_unique(ids)
    np.testing.assert_array_equal(got, np.unique(ids))
    assert got.dtype == np.int64
