"""Speed of perception: line extraction per scan (the hot spot) and one RTSV step.

Run: ``python -m pytest benchmarks/test_perception.py --benchmark-only
--benchmark-group-by=group``. Extraction runs the numpy path (today's) and the compiled
numba kernel side by side per beam count, on the same scan, with equal surfaces; the
goal is ≤ 100 µs per 361-beam scan with numba.
"""

from __future__ import annotations

import numpy as np
import pytest

from albot2d.geometry import Pose
from albot2d.perception import extract_surfaces, rtsv, start_tracking
from tests.perception_helpers import box, scan_of

OFFICE = np.vstack(
    [
        box(0.0, 0.0, 8.0, 4.0),
        *[
            box(x, y, 0.3, 0.25)
            for x, y in [(2.0, 1.0), (3.0, -2.0), (-2.0, 2.0), (4.0, 2.5), (1.0, -1.5), (5.5, 0.0)]
        ],
        [[-4.0, 4.0, -4.0, 1.0], [0.0, -4.0, 0.0, -2.5]],
    ]
)
START = Pose(-3.0, 0.2, 0.15)
STEP = Pose(0.2, 0.01, 0.03)


def _scan(n_beams: int, pose: Pose = START):
    return scan_of(OFFICE, pose, n_beams=n_beams, noise_sigma=0.01, rng=np.random.default_rng(5))


@pytest.mark.parametrize("backend", ["numpy", "numba"])
@pytest.mark.parametrize("n_beams", [181, 361])
def test_extract_surfaces_speed(benchmark, n_beams: int, backend: str) -> None:
    if backend == "numba":
        pytest.importorskip("numba")
    benchmark.group = f"line extraction {n_beams} beams"
    scan = _scan(n_beams)
    extract_surfaces(scan, backend=backend)  # compile (or load the cache) first
    surfaces = benchmark(extract_surfaces, scan, backend=backend)
    assert len(surfaces) >= 8
    numpy_view = extract_surfaces(scan, backend="numpy")
    # Equal to the numpy path within 1e-12 m, as tests/test_extraction_numba.py pins it:
    # LLVM may fuse a corner intersection's multiply-adds (a last-bit difference).
    np.testing.assert_array_equal(surfaces.beams, numpy_view.beams)
    np.testing.assert_allclose(surfaces.segments, numpy_view.segments, rtol=0.0, atol=1e-12)


def test_rtsv_speed(benchmark) -> None:
    first = extract_surfaces(_scan(361))
    second = extract_surfaces(_scan(361, START.compose(STEP)))
    tracked = start_tracking(first)
    survivors, _ = benchmark(rtsv, tracked, second, STEP)
    assert len(survivors) >= 3
