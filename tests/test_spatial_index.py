"""The grid index forgets removed segments; the global map keeps only live ids in it."""

from __future__ import annotations

import pickle

import numpy as np
import pytest
import shapely
from hypothesis import given
from hypothesis import strategies as st

from albot2d.geometry import Pose
from albot2d.geometry.spatial_index import (
    CompiledGridIndex,
    SegmentGridIndex,
    grid_index,
    sorted_unique,
)
from albot2d.mapping import GlobalMap, GlobalMapParams


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
    indexed = g._index.indexed_ids()
    alive = set(np.flatnonzero(g._removed[: g._n] == np.iinfo(np.int64).max).tolist())
    assert deleted > 50
    assert indexed == alive and len(alive) == len(g)


@given(st.lists(st.integers(-(2**40), 2**40), max_size=300))
def test_sorted_unique_is_numpys_unique(values: list[int]) -> None:
    ids = np.asarray(values, dtype=np.int64)
    got = sorted_unique(ids)
    np.testing.assert_array_equal(got, np.unique(ids))
    assert got.dtype == np.int64


def _random_ops(seed: int, n_ops: int, spread: float, cell: float):  # type: ignore[no-untyped-def]
    """A random sequence of inserts, removals of live ids and queries (small and huge boxes)."""
    rng = np.random.default_rng(seed)
    alive: dict[int, np.ndarray] = {}
    next_id = 0
    for _ in range(n_ops):
        if rng.random() < 0.6 or not alive:
            k = int(rng.integers(1, 25))
            start = rng.uniform(-spread, spread, (k, 2))
            segs = np.hstack([start, start + rng.uniform(-4.0 * cell, 4.0 * cell, (k, 2))])
            ids = np.arange(next_id, next_id + k, dtype=np.int64)
            next_id += k
            alive.update(zip(ids.tolist(), segs, strict=True))
            yield "insert", (ids, segs)
        else:
            picked = rng.choice(list(alive), size=min(len(alive), int(rng.integers(1, 40))),
                                replace=False)  # fmt: skip
            yield "remove", (np.asarray(picked, np.int64), np.array([alive.pop(i) for i in picked]))
        if rng.random() < 0.05:
            yield "query_box", (-10 * spread, -10 * spread, 10 * spread, 10 * spread)
        else:
            x, y = np.sort(rng.uniform(-1.2 * spread, 1.2 * spread, (2, 2)), axis=1)
            yield "query_box", (x[0], y[0], x[1], y[1])


@pytest.mark.parametrize(
    ("seed", "spread", "cell"), [(0, 50.0, 2.0), (1, 3.0, 0.5), (2, 400.0, 1.0)]
)
def test_compiled_index_answers_as_the_dict_index(seed: int, spread: float, cell: float) -> None:
    """The same queries after the same inserts and removals (the tables and the node pool
    grow from their smallest size on the way), and the same ids indexed at the end."""
    pytest.importorskip("numba")
    plain, compiled = SegmentGridIndex(cell), CompiledGridIndex(cell)
    queries = 0
    for op, args in _random_ops(seed, 1500, spread, cell):
        got = [getattr(index, op)(*args) for index in (plain, compiled)]
        if op == "query_box":
            assert got[1].dtype == np.int64
            np.testing.assert_array_equal(got[0], got[1])
            queries += len(got[0]) > 0
    assert queries > 100
    assert compiled.indexed_ids() == plain.indexed_ids()
    assert len(compiled._node_id) > 256 and len(compiled._keys) > 256  # both grew
    copied = pickle.loads(pickle.dumps(compiled))
    np.testing.assert_array_equal(copied.query_box(-spread, -spread, spread, spread),
                                  plain.query_box(-spread, -spread, spread, spread))  # fmt: skip


def test_global_map_uses_the_compiled_index_when_numba_imports() -> None:
    pytest.importorskip("numba")
    assert isinstance(GlobalMap()._index, CompiledGridIndex)
    assert isinstance(grid_index(1.0), CompiledGridIndex)


def test_compiled_index_refuses_cells_beyond_its_key_range() -> None:
    pytest.importorskip("numba")
    with pytest.raises(ValueError, match="beyond"):
        CompiledGridIndex(1.0).insert(np.array([0]), np.array([[0.0, 0.0, 2.0**31, 1.0]]))
