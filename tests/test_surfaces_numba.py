"""The compiled segment transform equals ``geometry.transform_segments`` bit for bit."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from albot2d.geometry import Pose, transform_segments
from albot2d.perception import Surfaces
from albot2d.perception.surfaces import _transform_kernel, transform_segments_fast

pytest.importorskip("numba")

coords = st.floats(-1e4, 1e4, allow_nan=False, allow_infinity=False)
poses = st.tuples(coords, coords, st.floats(-10.0, 10.0, allow_nan=False))


@given(poses, arrays(np.float64, st.tuples(st.integers(0, 40), st.just(4)), elements=coords))
def test_compiled_transform_is_the_numpy_one_bit_for_bit(pose, segs) -> None:  # type: ignore[no-untyped-def]
    assert _transform_kernel() is not None  # the compiled path is the one under test
    want = transform_segments(np.array(pose), segs)
    got = transform_segments_fast(np.array(pose), segs)
    assert got.shape == want.shape == (len(segs), 4)
    np.testing.assert_array_equal(got, want)  # exact: same operations, same order
    np.testing.assert_array_equal(transform_segments_fast(Pose(*pose), segs), want)


def test_read_only_and_strided_inputs_and_surfaces_transformed() -> None:
    rng = np.random.default_rng(3)
    segs = rng.uniform(-20.0, 20.0, (50, 8))[:, ::2]  # a strided (non-contiguous) view
    pose = Pose(1.5, -2.25, 0.7).as_array()
    np.testing.assert_array_equal(transform_segments_fast(pose, segs),
                                  transform_segments(pose, segs))  # fmt: skip
    view = Surfaces.from_segments(rng.uniform(-5.0, 5.0, (7, 4)))  # read-only arrays
    moved = view.transformed(pose)
    np.testing.assert_array_equal(moved.segments, transform_segments(pose, view.segments))
    assert not moved.segments.flags.writeable
    assert moved.occluded is view.occluded


def test_an_unusual_pose_takes_the_numpy_path_and_its_errors() -> None:
    with pytest.raises(ValueError):
        transform_segments_fast([1.0, 2.0], np.zeros((1, 4)))
