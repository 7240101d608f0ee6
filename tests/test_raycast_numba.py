"""The compiled (numba) raycasting kernel gives the numpy kernel's ranges.

Bit for bit on every beam that does not graze a segment end (there a hit and a miss are
both right to rounding, and the two kernels may round differently); the tolerance below is
the promised 1e-12 m. Skipped where numba is not installed.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import example, given
from hypothesis import strategies as st

from albot2d.frames import beam_angles
from albot2d.sim.raycast import BeamFan, RayCaster
from tests.raycast_helpers import (
    assert_same_ranges,
    assume_not_touching,
    coord,
    office_segments,
    segment_sets,
)

pytest.importorskip("numba")

SAME_M = 1e-12


def casters(segs: np.ndarray, **kwargs: object) -> tuple[RayCaster, RayCaster]:
    numpy_caster = RayCaster(segs, backend="numpy", **kwargs)  # type: ignore[arg-type]
    numba_caster = RayCaster(segs, backend="numba", **kwargs)  # type: ignore[arg-type]
    assert (numpy_caster.backend, numba_caster.backend) == ("numpy", "numba")
    return numpy_caster, numba_caster


@given(
    segs=segment_sets(),
    extra=st.one_of(st.none(), segment_sets(max_size=4)),
    ox=coord,
    oy=coord,
    th=st.floats(-20.0, 20.0),
    cell=st.one_of(st.none(), st.floats(0.3, 30.0)),
    n_beams=st.sampled_from([2, 37, 181, 360]),
    span=st.sampled_from([math.pi, 1.0, 2 * math.pi]),
    shuffle=st.booleans(),
    r_max=st.floats(1.0, 100.0),
)
@example(  # a ray along a wall that lies on a grid line, through pieces' shared ends
    segs=office_segments(2),
    extra=None,
    ox=2.0,
    oy=4.0,
    th=0.0,
    cell=1.0,
    n_beams=360,
    span=2 * math.pi,
    shuffle=False,
    r_max=30.0,
)
def test_numba_kernel_gives_the_numpy_ranges(
    segs: np.ndarray,
    extra: np.ndarray | None,
    ox: float,
    oy: float,
    th: float,
    cell: float | None,
    n_beams: int,
    span: float,
    shuffle: bool,
    r_max: float,
) -> None:
    everything = segs if extra is None else np.vstack([segs, extra])
    assume_not_touching(everything, ox, oy)
    angles = beam_angles(n_beams, span * (1.0 - 1.0 / n_beams)) + th
    if shuffle:
        angles = np.random.default_rng(n_beams).permutation(angles)
    slow, fast = casters(segs, cell_size_m=cell)
    want = slow.cast((ox, oy), angles, r_max, extra_segments=extra)
    got = fast.cast((ox, oy), angles, r_max, extra_segments=extra)
    assert_same_ranges(got, want, r_max, everything, (ox, oy), angles, tol_m=SAME_M)


@pytest.mark.parametrize("cell", [None, 0.5, 1.0, 2.0, 4.0])
def test_walls_on_grid_lines_and_rays_along_them(cell: float | None) -> None:
    """Office walls at multiples of 4 m lie on the grid lines of these cells; origins at
    half metres send beams exactly along walls, grid lines and through cell corners."""
    segs = office_segments(5)
    slow, fast = casters(segs, cell_size_m=cell)
    angles = np.linspace(-math.pi, math.pi, 360, endpoint=False)
    rng = np.random.default_rng(11)
    for ox, oy in rng.integers(1, 40, (12, 2)) / 2.0:
        o = (float(ox), float(oy))
        want, got = slow.cast(o, angles, 30.0), fast.cast(o, angles, 30.0)
        assert_same_ranges(got, want, 30.0, segs, o, angles, tol_m=SAME_M)


def test_dense_world_at_long_range_equals_the_occlusion_cut() -> None:
    """80 m in a dense world: numpy casts near then far; numba just walks further."""
    segs = office_segments(30)
    slow, fast = casters(segs)
    fan = BeamFan.from_angles(beam_angles(181))
    rng = np.random.default_rng(5)
    for _ in range(10):
        o = (float(rng.uniform(1, 119)), float(rng.uniform(1, 119)))
        th = float(rng.uniform(-math.pi, math.pi))
        want = slow.cast(o, fan, 80.0, heading=th)
        got = fast.cast(o, fan, 80.0, heading=th)
        assert_same_ranges(got, want, 80.0, segs, o, fan.angles + th, tol_m=SAME_M)


def test_many_pieces_seen_edge_on() -> None:
    """The origin on the line of a long wall cut into more pieces than the kernel tracks:
    the beam pointing along the wall hits its near end, every other beam misses it."""
    wall = np.array([[1.0, 0.0, 60.0, 0.0], [-30.0, 3.0, 30.0, 3.0]])
    slow, fast = casters(wall, cell_size_m=0.5)
    assert fast.n_pieces > 64
    angles = np.array([0.0, 1e-3, -1e-3, math.pi / 2, math.pi])
    got = fast.cast((0.0, 0.0), angles, 100.0)
    np.testing.assert_array_equal(got, slow.cast((0.0, 0.0), angles, 100.0))
    assert got[0] == pytest.approx(1.0, abs=SAME_M)
    assert np.isinf(got[[1, 2, 4]]).all() and got[3] == pytest.approx(3.0)


@pytest.mark.parametrize("origin", [(-500.0, 7.0), (30.0, -200.0), (1e4, 1e4)])
def test_origin_outside_the_indexed_area(origin: tuple[float, float]) -> None:
    segs = office_segments(4)
    slow, fast = casters(segs)
    angles = np.linspace(-math.pi, math.pi, 720, endpoint=False)
    for r_max in (50.0, 1000.0):
        want = slow.cast(origin, angles, r_max)
        got = fast.cast(origin, angles, r_max)
        assert_same_ranges(got, want, r_max, segs, origin, angles, tol_m=SAME_M)
