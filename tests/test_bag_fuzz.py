"""Property-based fuzzing of the ROS bag reader: mutated bags either read or raise
``InputError``, never anything else (as ``tests/test_reader_fuzz.py`` does for CARMEN logs).

Two kinds of input: valid ROS 1, MCAP and sqlite3 bags mutated byte by byte (truncated,
overwritten, spliced), and bags whose LaserScan and Odometry fields hold the values that
break readers (NaN, infinities, 1e308, huge and empty range arrays, stamps at the limits).
A bag that is accepted must also go through the time-order rule. The ``ci`` profile tries
25 inputs per test; ``HYPOTHESIS_PROFILE=fuzz python -m pytest tests/test_bag_fuzz.py``
tries 5000.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import example, given
from hypothesis import strategies as st

from albot2d.errors import InputError
from albot2d.logs.anomalies import ordered_frames
from albot2d.logs.carmen import MAX_BEAMS
from albot2d.logs.rosbag import read_bag
from albot2d.validation import COORDINATE_LIMIT_M
from tests.bag_helpers import BagScan, write_test_bag
from tests.strategies import corrupted

_NASTY_32 = [0.0, -0.0, -1.0, 3e38, -3e38, 1e-45, 1e7, 0.5, math.pi, -7.0, float("nan"),
             float("inf"), float("-inf")]  # fmt: skip
_NASTY = st.sampled_from([*_NASTY_32, 1e308, -1e308, 1e-308])  # poses are float64
_NASTY_FLOAT32 = st.sampled_from(_NASTY_32)  # LaserScan's fields and ranges are float32
_SUFFIXES = {"ros1": ".bag", "mcap": ".mcap", "sqlite3": ".db3"}


def _valid_bag(directory: Path, kind: str) -> bytes:
    """The bytes of a small valid bag of ``kind`` (one storage file)."""
    scans = [BagScan(t=5.0 + 0.1 * k, ranges=[1.0 + 0.01 * j for j in range(31)],
                     pose=(0.1 * k, 0.0, 0.05 * k), angle_increment=math.pi / 30)
             for k in range(4)]  # fmt: skip
    if kind == "ros1":
        return write_test_bag(directory / "v.bag", ros1=True, scans=scans).read_bytes()
    bag = write_test_bag(directory / "v", ros1=False, scans=scans, storage=kind)
    return next(p for p in bag.iterdir() if p.suffix != ".yaml").read_bytes()


@pytest.fixture(scope="module")
def valid_bags(tmp_path_factory: pytest.TempPathFactory) -> dict[str, bytes]:
    return {kind: _valid_bag(tmp_path_factory.mktemp(kind), kind) for kind in _SUFFIXES}


def _check(path: Path) -> None:
    """Read ``path``: frames that then go through the time-order rule, or InputError."""
    try:
        bag = read_bag(path)
    except InputError as exc:
        assert str(exc).startswith(str(path)), exc
        assert "\n" not in str(exc)
        return
    frames, anomalies = ordered_frames(bag.frames)
    assert anomalies.frames_read == len(bag.frames) >= anomalies.frames_kept == len(frames)
    for frame in frames:
        assert frame.scan.n_beams <= MAX_BEAMS
        assert abs(frame.odom_pose.x) <= COORDINATE_LIMIT_M
        assert np.all(np.diff(frame.scan.angles) >= 0)
        valid = frame.scan.ranges[frame.scan.valid]
        assert np.all(np.isfinite(valid)) and np.all(valid <= frame.scan.max_range_m)


@pytest.mark.parametrize("kind", list(_SUFFIXES))
@given(data=st.data())
def test_byte_mutations_raise_only_input_error(
    tmp_path_factory: pytest.TempPathFactory, valid_bags: dict[str, bytes], kind: str, data: Any
) -> None:
    path = tmp_path_factory.mktemp("fuzz") / f"m{_SUFFIXES[kind]}"
    path.write_bytes(data.draw(corrupted(valid_bags[kind])))
    _check(path)


@st.composite
def _field_scans(draw: st.DrawFn) -> list[BagScan]:
    scans = []
    for k in range(draw(st.integers(1, 3))):
        n = draw(st.sampled_from([0, 1, 2, 31, 181, MAX_BEAMS + 1]))
        value = st.floats(width=32) | _NASTY_FLOAT32
        # Too many beams: one value repeated (drawing each would be slow).
        big = n > 181
        ranges = [draw(value)] * n if big else draw(st.lists(value, min_size=n, max_size=n))
        fields: dict[str, Any] = {}
        for name in ("angle_min", "angle_increment", "range_min", "range_max", "angle_max"):
            if draw(st.booleans()):
                fields[name] = draw(_NASTY_FLOAT32 | st.floats(-10, 10, width=32))
        t = draw(st.sampled_from([0.0, 1.0 + k, 2e9, 1.0]))  # ROS 2 stamps are int32 seconds
        pose = tuple(draw(_NASTY | st.floats(-5, 5)) if draw(st.booleans()) else 0.0
                     for _ in range(3))  # fmt: skip
        scan = {name: fields.pop(name) for name in list(fields) if name != "angle_max"}
        scans.append(BagScan(t=t, ranges=ranges, pose=pose, extra=fields, **scan))  # type: ignore[arg-type]
    return scans


@given(scans=_field_scans(), ros1=st.booleans(), odom=st.booleans())
@example(scans=[BagScan(t=1.0, ranges=[float("nan")] * 181)], ros1=True, odom=True)
@example(scans=[BagScan(t=0.0, ranges=[0.0] * 31, pose=(0.0, 0.0, math.inf))], ros1=False,
         odom=False)  # fmt: skip
@example(scans=[BagScan(t=1.0, ranges=[1.0] * (MAX_BEAMS + 1))], ros1=True, odom=True)
@example(scans=[BagScan(t=1.0, ranges=[])], ros1=False, odom=True)
@example(scans=[BagScan(t=0.0, ranges=[0.0] * 31, angle_increment=3e38)], ros1=False, odom=False)
@example(scans=[BagScan(t=1.0, ranges=[1.0] * 181, range_max=float("inf"))], ros1=False,
         odom=False)  # fmt: skip
def test_field_values_raise_only_input_error(
    tmp_path_factory: pytest.TempPathFactory, scans: list[BagScan], ros1: bool, odom: bool
) -> None:
    path = tmp_path_factory.mktemp("fields") / ("f.bag" if ros1 else "f")
    write_test_bag(path, ros1=ros1, scans=scans, odom_topic="/odom" if odom else None)
    _check(path)
