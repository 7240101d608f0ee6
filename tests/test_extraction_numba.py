"""The compiled (numba) line extraction gives the numpy path's surfaces.

Beams, occlusion and uncertainty flags are equal bit for bit; coordinates are equal to
1e-12 m, because LLVM may fuse the multiply-adds of a corner's line intersection (one
rounding instead of two), which numpy never does: a 1-ulp difference, found by hypothesis.

Random cluttered worlds with range noise and dropouts, every parameter switch, and real
simulator scans (181 and 361 beams). Skipped where numba is not installed.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from albot2d.errors import InputError
from albot2d.frames import Scan
from albot2d.geometry import Pose
from albot2d.perception import ExtractionParams, Surfaces, extract_surfaces
from tests.perception_helpers import box, scan_of
from tests.strategies import examples
from worldgen.tours import make_tour

pytest.importorskip("numba")


def assert_same(a: Surfaces, b: Surfaces) -> None:
    np.testing.assert_array_equal(a.beams, b.beams)
    np.testing.assert_allclose(a.segments, b.segments, rtol=0.0, atol=1e-12)
    np.testing.assert_array_equal(a.occluded, b.occluded)
    np.testing.assert_array_equal(a.uncertain, b.uncertain)


def both(scan: Scan, params: ExtractionParams | None = None) -> tuple[Surfaces, Surfaces]:
    return (extract_surfaces(scan, params, backend="numpy"),
            extract_surfaces(scan, params, backend="numba"))  # fmt: skip


PARAMS = st.builds(
    ExtractionParams,
    split_distance_m=st.sampled_from([0.02, 0.05, 0.1]),
    merge_distance_m=st.sampled_from([0.03, 0.05, 0.2]),
    min_points=st.integers(2, 8),
    max_range_m=st.sampled_from([math.inf, 6.0]),
    continuation_distance_m=st.sampled_from([0.0, 0.05]),
    max_endpoint_gap_m=st.sampled_from([math.inf, 0.1]),
    corner_max_shift_m=st.sampled_from([0.0, 0.15]),
)


@settings(max_examples=examples(60), deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    n_walls=st.integers(0, 12),
    n_beams=st.sampled_from([181, 361]),
    sigma=st.sampled_from([0.0, 0.005, 0.02]),
    dropout=st.sampled_from([0.0, 0.05]),
    params=PARAMS,
    mount=st.sampled_from([Pose(), Pose(0.16, 0.0, 0.0), Pose(0.1, -0.05, 0.3)]),
)
def test_numba_gives_the_numpy_surfaces_on_random_worlds(
    seed: int, n_walls: int, n_beams: int, sigma: float, dropout: float,
    params: ExtractionParams, mount: Pose,
) -> None:  # fmt: skip
    rng = np.random.default_rng(seed)
    walls = [box(0.0, 0.0, 6.0, 4.0)]
    centres = rng.uniform(-5.0, 5.0, (n_walls, 2))
    ends = centres + rng.uniform(-1.5, 1.5, (n_walls, 2))
    walls.append(np.column_stack([centres, ends]))
    heading = float(rng.uniform(-math.pi, math.pi))
    scan = scan_of(np.vstack(walls), Pose(0.3, -0.2, heading), n_beams=n_beams,
                   noise_sigma=sigma, rng=rng, laser_pose=mount)  # fmt: skip
    if dropout:
        valid = scan.valid & (rng.random(n_beams) >= dropout)
        scan = Scan(np.where(valid, scan.ranges, scan.max_range_m), scan.angles, valid,
                    scan.max_range_m, laser_pose=mount)  # fmt: skip
    assert_same(*both(scan, params))


@pytest.mark.parametrize("n_beams", [181, 361])
def test_numba_gives_the_numpy_surfaces_on_simulated_office_scans(n_beams: int) -> None:
    from albot2d.sim.laser import LaserNoise, LaserParams
    from albot2d.sim.simulator import Simulator
    from worldgen.generate import generate

    world = generate("office", seed=3)
    sim = Simulator(world, seed=5, laser=LaserParams(n_beams=n_beams),
                    laser_noise=LaserNoise.sick_lms200())  # fmt: skip
    tour = make_tour(world, np.random.default_rng(0), kind="loop", min_length_m=30.0)
    total = 0
    for _, frame in zip(range(120), sim.drive(tour), strict=False):
        numpy_view, numba_view = both(frame.scan)
        assert_same(numpy_view, numba_view)
        total += len(numba_view)
    assert total > 120  # the scans did have surfaces to compare


def test_both_backends_reject_lambda_within_the_beam_spacing() -> None:
    scan = scan_of(np.array([[3.0, -5.0, 3.0, 5.0]]), n_beams=19)  # 10° spacing
    for backend in ("numpy", "numba"):
        with pytest.raises(InputError, match="breakpoint_lambda_deg"):
            extract_surfaces(scan, backend=backend)


def test_unknown_backend_is_rejected() -> None:
    scan = scan_of(box(0.0, 0.0, 3.0, 2.0))
    with pytest.raises(InputError, match="backend"):
        extract_surfaces(scan, backend="fortran")


def test_empty_and_tiny_scans_agree() -> None:
    angles = np.linspace(-math.pi / 2, math.pi / 2, 181)
    nothing = Scan(np.full(181, 30.0), angles, np.zeros(181, bool), 30.0)
    assert_same(*both(nothing))
    tiny = scan_of(box(0.0, 0.0, 3.0, 2.0), n_beams=3, fov_rad=0.01)
    assert_same(*both(tiny))
