"""The fan a scan swept (``knowledge.fan_cells``): the numpy reference against an
independent shapely oracle, and the compiled kernel equal to the reference."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from hypothesis import example, given, settings
from hypothesis import strategies as st

from albot2d.control.knowledge import fan_cells
from tests.strategies import examples

numba_fan = pytest.importorskip(
    "albot2d.control.knowledge_numba", reason="numba (a default dependency) is not installed"
).fan_cells

WINDOW = (-2.0, -3.0)  # the grid's origin (m)


def _wedges(x: float, y: float, theta: float, angles: np.ndarray, reach: np.ndarray,
            margin: float) -> shapely.Geometry:  # fmt: skip
    """The fan as polygons: per pair of neighbouring beams, the sector of radius
    min(reach) - margin between them (arcs sampled finely)."""
    parts = []
    for j in range(len(angles) - 1):
        radius = min(reach[j], reach[j + 1]) - margin
        if radius <= 0.0:
            continue
        arc = np.linspace(angles[j], angles[j + 1], 64) + theta
        ring = [(x, y), *zip(x + radius * np.cos(arc), y + radius * np.sin(arc), strict=True)]
        parts.append(shapely.Polygon(ring))
    return shapely.union_all(parts)


@pytest.mark.parametrize("seed", range(6))
def test_fan_cells_match_the_swept_sectors(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = int(rng.integers(5, 60))
    angles = np.linspace(-math.pi / 2, math.pi / 2, n)
    reach = rng.uniform(0.5, 6.0, n) * (rng.random(n) > 0.15)  # some invalid beams
    x, y, theta = 4.0, 3.0, float(rng.uniform(-math.pi, math.pi))
    r, nx, ny = 0.1, 120, 100
    margin = math.sqrt(0.5) * r
    cells = fan_cells(x, y, theta, angles, reach, *WINDOW, r, 0, nx, 0, ny, nx, margin)
    ix, iy = np.meshgrid(np.arange(nx), np.arange(ny))
    cx, cy = WINDOW[0] + (ix + 0.5) * r, WINDOW[1] + (iy + 0.5) * r
    fan = _wedges(x, y, theta, angles, reach, margin)
    inside = shapely.contains_xy(fan, cx, cy).reshape(-1)
    # Away from the wedges' boundary (where sampled arcs and strict inequalities may
    # differ by a hair), the oracle decides.
    clear = shapely.distance(shapely.boundary(fan), shapely.points(cx, cy)).reshape(-1) > 1e-3
    mine = np.zeros(nx * ny, dtype=bool)
    mine[cells] = True
    assert inside.sum() > 50
    assert np.array_equal(mine[clear], inside[clear])
    assert np.all(np.diff(cells) > 0)  # row-major, each cell once


@st.composite
def fan_problems(draw: st.DrawFn) -> tuple:
    n = draw(st.integers(2, 200))
    fov = draw(st.floats(0.05, 2.0 * math.pi))
    angles = np.linspace(-fov / 2.0, fov / 2.0, n)
    reach = np.array(draw(st.lists(st.floats(0.0, 12.0), min_size=n, max_size=n)))
    x, y = draw(st.floats(-5.0, 25.0)), draw(st.floats(-5.0, 25.0))
    theta = draw(st.floats(-10.0, 10.0))
    r = draw(st.sampled_from([0.05, 0.1, 0.2]))
    ix0, iy0 = draw(st.integers(0, 60)), draw(st.integers(0, 60))
    ix1, iy1 = draw(st.integers(ix0 + 1, 250)), draw(st.integers(iy0 + 1, 250))
    return (x, y, theta, angles, reach, *WINDOW, r, ix0, ix1, iy0, iy1, 250, math.sqrt(0.5) * r)


@settings(max_examples=examples(60), deadline=None)
@given(fan_problems())
@example((4.0, 3.0, 0.0, np.linspace(-1.0, 1.0, 3), np.array([0.0, 0.0, 0.0]), *WINDOW, 0.1,
          0, 10, 0, 10, 250, 0.07))  # fmt: skip
def test_compiled_fan_equals_the_reference(problem: tuple) -> None:
    reference = fan_cells(*problem)
    compiled = numba_fan(*problem)
    assert compiled.dtype == reference.dtype
    assert np.array_equal(compiled, reference)
