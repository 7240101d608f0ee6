"""Hypothesis strategies for the log I/O tests: laser scans and frame sequences with truth."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import strategies as st

from albot2d.frames import Frame, Scan, beam_angles
from albot2d.geometry import Pose
from tests.strategies import poses

__all__ = ["frame_sequences", "scans"]

# Every kind of "not a hit" a simulator or a real log may hold in an invalid beam.
_JUNK = np.array([math.nan, math.inf, -math.inf, -1.0, 0.0, 81.91, 1e6])
# Valid beams stay this far from 0 and max range, so 1 mm rounding keeps them valid.
_EDGE_M = 0.002


@st.composite
def scans(draw: st.DrawFn) -> Scan:
    n = draw(st.sampled_from([180, 181, 360, 361]) | st.integers(min_value=2, max_value=40))
    fov = draw(st.floats(min_value=0.1, max_value=2 * math.pi))
    inclusive = draw(st.booleans())
    max_range = draw(st.floats(min_value=0.5, max_value=100.0))
    rng = np.random.default_rng(draw(st.integers(min_value=0, max_value=2**32 - 1)))
    valid = rng.random(n) < draw(st.floats(min_value=0.0, max_value=1.0))
    hits = rng.uniform(_EDGE_M, max_range - _EDGE_M, n)
    ranges = np.where(valid, hits, rng.choice(np.append(_JUNK, max_range), n))
    mount = draw(
        st.builds(
            Pose,
            st.floats(-1.0, 1.0, allow_subnormal=False),
            st.floats(-1.0, 1.0, allow_subnormal=False),
            st.floats(-math.pi, math.pi, exclude_max=True),
        )
    )
    angles = beam_angles(n, fov, inclusive=inclusive)
    return Scan(ranges, angles, valid, max_range, laser_pose=mount)


@st.composite
def frame_sequences(draw: st.DrawFn, max_frames: int = 4) -> list[Frame]:
    """Frames sharing one laser geometry, increasing timestamps, odometry and truth."""
    first = draw(scans())
    count = draw(st.integers(min_value=1, max_value=max_frames))
    t = draw(st.floats(min_value=0.0, max_value=2e9))
    rng = np.random.default_rng(draw(st.integers(min_value=0, max_value=2**32 - 1)))
    frames: list[Frame] = []
    prev_odom: Pose | None = None
    for index in range(count):
        n = first.n_beams
        if index == 0:
            ranges, valid = first.ranges, first.valid
        else:
            valid = rng.random(n) < 0.7
            hits = rng.uniform(_EDGE_M, first.max_range_m - _EDGE_M, n)
            ranges = np.where(valid, hits, rng.choice(_JUNK, n))
        scan = Scan(ranges, first.angles, valid, first.max_range_m, t, first.laser_pose)
        odom = draw(poses())
        increment = Pose() if prev_odom is None else prev_odom.between(odom)
        frames.append(Frame(index, t, scan, odom, increment, draw(poses()), draw(st.booleans())))
        prev_odom = odom
        t += draw(st.floats(min_value=0.01, max_value=10.0))
    return frames
