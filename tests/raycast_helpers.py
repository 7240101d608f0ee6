"""Reference ranges and worlds for the raycaster and laser tests.

``shapely_ranges`` is the exact reference: each beam is a shapely LineString out to
``max_range`` intersected with every segment; the range is the distance from the origin
to the nearest intersection point (overlaps count by their nearest point). Segments the
raycaster treats as zero-length are left out here too. ``BACKENDS`` parametrises a test
over the raycaster's kernels (numba only where it is installed); ``assert_same_ranges``
compares two casts of the same beams.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from hypothesis import assume
from hypothesis import strategies as st

from albot2d.geometry import point_segment_distance
from albot2d.sim.raycast import MIN_SEGMENT_LENGTH_M, numba_available

__all__ = [
    "BACKENDS",
    "CONTACT_M",
    "EXACT_M",
    "assert_same_ranges",
    "assume_not_touching",
    "box_segments",
    "coord",
    "grazing",
    "office_segments",
    "ring_segments",
    "segment_sets",
    "shapely_ranges",
]

#: Exact means equal to this many metres.
EXACT_M = 1e-9
#: The raycaster's default contact tolerance.
CONTACT_M = 1e-9

BACKENDS = [
    "numpy",
    pytest.param(
        "numba", marks=pytest.mark.skipif(not numba_available(), reason="numba not installed")
    ),
]

coord = st.floats(-50.0, 50.0, allow_nan=False, allow_subnormal=False)


def shapely_ranges(
    segments: np.ndarray, origin: tuple[float, float], angles: np.ndarray, max_range: float
) -> np.ndarray:
    """Exact reference ranges (``inf`` where nothing is within ``max_range``)."""
    segs = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
    keep = np.hypot(segs[:, 2] - segs[:, 0], segs[:, 3] - segs[:, 1]) >= MIN_SEGMENT_LENGTH_M
    lines = shapely.linestrings(segs[keep].reshape(-1, 2, 2))
    ox, oy = origin
    out = np.full(len(angles), np.inf)
    for k, a in enumerate(np.asarray(angles, dtype=np.float64)):
        end = (ox + max_range * math.cos(a), oy + max_range * math.sin(a))
        ray = shapely.LineString([(ox, oy), end])
        hits = shapely.intersection(ray, lines)
        hits = hits[~shapely.is_empty(hits)]
        if len(hits) == 0:
            continue
        pts = shapely.get_coordinates(hits)
        out[k] = float(np.hypot(pts[:, 0] - ox, pts[:, 1] - oy).min())
    return out


def box_segments(xmin: float, ymin: float, xmax: float, ymax: float) -> np.ndarray:
    """The four walls of an axis-aligned rectangle, sharing their corner vertices."""
    c = np.array([[xmin, ymin], [xmax, ymin], [xmax, ymax], [xmin, ymax]])
    return np.hstack([c, np.roll(c, -1, axis=0)])


def ring_segments(points: np.ndarray) -> np.ndarray:
    """Edges of the closed polygon through ``points`` (``(K, 2)``)."""
    p = np.asarray(points, dtype=np.float64)
    return np.hstack([p, np.roll(p, -1, axis=0)])


def office_segments(n: int, room_m: float = 4.0, door_m: float = 1.0) -> np.ndarray:
    """An ``n`` × ``n`` grid of square rooms, a door in the middle of every inner wall."""
    side = (room_m - door_m) / 2.0
    segs = []
    for i in range(n + 1):
        for j in range(n):
            a, c = j * room_m, i * room_m
            if i in (0, n):
                segs += [[a, c, a + room_m, c], [c, a, c, a + room_m]]
            else:
                segs += [[a, c, a + side, c], [a + side + door_m, c, a + room_m, c]]
                segs += [[c, a, c, a + side], [c, a + side + door_m, c, a + room_m]]
    return np.asarray(segs, dtype=np.float64)


def grazing(segs: np.ndarray, origin: tuple[float, float], angles: np.ndarray) -> np.ndarray:
    """Beams passing within EXACT_M of a segment end: a hit or a miss there are both right."""
    ends = np.asarray(segs, dtype=np.float64).reshape(-1, 2) - np.asarray(origin)
    d = np.column_stack([np.cos(angles), np.sin(angles)])
    along = d @ ends.T
    across = np.abs(d[:, 0:1] * ends[:, 1] - d[:, 1:2] * ends[:, 0])
    return np.any((across < EXACT_M) & (along > -EXACT_M), axis=1)


@st.composite
def segment_sets(draw: st.DrawFn, max_size: int = 25) -> np.ndarray:
    n = draw(st.integers(1, max_size))
    values = draw(st.lists(coord, min_size=4 * n, max_size=4 * n))
    segs = np.asarray(values, dtype=np.float64).reshape(n, 4)
    # Some axis-aligned walls sharing vertices, like real worlds.
    if draw(st.booleans()):
        x0, y0 = draw(coord), draw(coord)
        w, h = draw(st.floats(0.5, 20.0)), draw(st.floats(0.5, 20.0))
        segs = np.vstack([segs, box_segments(x0, y0, x0 + w, y0 + h)])
    return segs


def assume_not_touching(segs: np.ndarray, ox: float, oy: float) -> None:
    """Within the contact tolerance of a wall (but not on it) the laser is inside the wall by
    design (all ranges 0) while the references still see past it: skip those origins."""
    d = point_segment_distance(np.array([[ox, oy]]), segs)
    assume(not np.any((d > 0.0) & (d <= 4 * CONTACT_M)))


def assert_same_ranges(
    got: np.ndarray,
    want: np.ndarray,
    max_range: float,
    segs: np.ndarray | None = None,
    origin: tuple[float, float] = (0.0, 0.0),
    angles: np.ndarray | None = None,
    *,
    tol_m: float = EXACT_M,
) -> None:
    """Equal to ``tol_m`` or both inf; a hit within EXACT_M of ``max_range`` may fall either
    side, and so may a beam grazing a segment end (when ``segs`` and ``angles`` are given)."""
    exempt = np.zeros(len(got), dtype=bool)
    if segs is not None and angles is not None:
        exempt = grazing(segs, origin, angles)
    both = np.isfinite(got) & np.isfinite(want) & ~exempt
    np.testing.assert_allclose(got[both], want[both], rtol=0.0, atol=tol_m)
    only = (np.isfinite(got) != np.isfinite(want)) & ~exempt
    edge = np.where(np.isfinite(got), got, want)[only]
    assert np.all(np.abs(edge - max_range) < EXACT_M), (np.flatnonzero(only), edge)
