"""Surfaces.select: the same subsets as numpy's fancy indexing, fresh read-only arrays."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from albot2d.perception import Surfaces


def some_surfaces(n: int) -> Surfaces:
    rng = np.random.default_rng(n)
    return Surfaces(rng.uniform(-5.0, 5.0, (n, 4)), rng.random((n, 2)) < 0.5,
                    rng.integers(0, 181, (n, 2)), rng.random((n, 2)) < 0.3)  # fmt: skip


@given(st.integers(1, 12).flatmap(
    lambda n: st.tuples(st.just(n), st.one_of(
        st.lists(st.booleans(), min_size=n, max_size=n),
        st.lists(st.integers(-n, n - 1), max_size=2 * n),
    ))))  # fmt: skip
def test_select_is_fancy_indexing(case) -> None:  # type: ignore[no-untyped-def]
    n, index = case
    view = some_surfaces(n)
    idx = np.asarray(index, dtype=bool if index and isinstance(index[0], bool) else np.int64)
    got = view.select(idx)
    for name in ("segments", "occluded", "beams", "uncertain"):
        want = getattr(view, name)[idx]
        arr = getattr(got, name)
        assert arr.dtype == want.dtype and arr.shape == want.shape
        np.testing.assert_array_equal(arr, want)
        assert not arr.flags.writeable and not np.shares_memory(arr, getattr(view, name))


def test_select_refuses_what_fancy_indexing_refuses() -> None:
    view = some_surfaces(3)
    with pytest.raises(IndexError):
        view.select(np.array([True, False]))
    with pytest.raises(IndexError):
        view.select(np.array([3]))
