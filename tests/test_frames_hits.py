"""``Frame.world_hits``: the compiled laser-hit transform equals ``Scan.points`` then
``transform_points`` by the true pose bit for bit, is kept with the frame, and is refused
for a frame without truth."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from albot2d.frames import Frame, Scan, _hits_kernel, beam_angles
from albot2d.geometry import Pose, transform_points

pytest.importorskip("numba")

coords = st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False)
headings = st.floats(-10.0, 10.0, allow_nan=False)
poses = st.builds(Pose, coords, coords, headings)


@st.composite
def scans(draw: st.DrawFn) -> Scan:
    n = draw(st.sampled_from([2, 5, 181, 361]))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    angles = beam_angles(n) + rng.normal(0.0, draw(st.sampled_from([0.0, 0.01])), n)
    mount = Pose(rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), rng.uniform(-math.pi, math.pi))
    return Scan(
        ranges=rng.uniform(0.0, 30.0, n),
        angles=angles,
        valid=rng.random(n) < draw(st.sampled_from([0.0, 0.5, 1.0])),
        max_range_m=30.0,
        laser_pose=draw(st.sampled_from([Pose(), mount])),
    )


def _frame(scan: Scan, true: Pose | None) -> Frame:
    return Frame(0, 0.0, scan, Pose(), Pose(), true_pose=true)


@given(scans(), poses)
def test_world_hits_are_the_numpy_transforms_bit_for_bit(scan: Scan, true: Pose) -> None:
    assert _hits_kernel() is not None  # the compiled path is the one under test
    want = transform_points(true.as_array(), scan.points())
    got = _frame(scan, true).world_hits()
    assert got.shape == want.shape == (int(scan.valid.sum()), 2)
    np.testing.assert_array_equal(got, want)  # exact: same operations, same order


def test_world_hits_are_kept_read_only_and_need_a_true_pose() -> None:
    scan = Scan(np.full(181, 2.0), beam_angles(181), np.ones(181, bool), 30.0)
    frame = _frame(scan, Pose(1.0, 2.0, 0.5))
    hits = frame.world_hits()
    assert frame.world_hits() is hits and not hits.flags.writeable
    np.testing.assert_allclose(np.hypot(hits[:, 0] - 1.0, hits[:, 1] - 2.0), 2.0)
    with pytest.raises(ValueError, match="frame 0 has no true pose"):
        _frame(scan, None).world_hits()


def test_a_kernel_module_that_does_not_import_gives_the_numpy_path() -> None:
    from albot2d.compiled import compiled_kernel

    assert compiled_kernel("albot2d.geometry.points_numba", "hits_kernel") is _hits_kernel()
    assert compiled_kernel("albot2d.geometry.no_such_kernels", "hits_kernel") is None


def test_a_simulated_scan_owns_read_only_arrays_and_shares_its_angles() -> None:
    from albot2d.sim.laser import Laser, LaserParams

    laser = Laser(np.array([[5.0, -5.0, 5.0, 5.0]]), LaserParams())
    rng = np.random.default_rng(0)
    a, b = laser.scan(Pose(), rng), laser.scan(Pose(), rng)
    assert a.angles is b.angles and not a.angles.flags.writeable
    for scan in (a, b):
        assert not scan.ranges.flags.writeable and not scan.valid.flags.writeable
        assert scan.ranges.dtype == np.float64 and scan.valid.dtype == np.bool_
    np.testing.assert_allclose(a.points()[:, 0], 5.0, atol=0.1)
    with pytest.raises(ValueError, match="read-only array"):
        Scan.adopt(np.zeros(3), np.zeros(3), np.ones(3, bool), 30.0, 0.0, Pose())
