"""The Albot_x baselines: naive odometry integration and ground-truth integration."""

from __future__ import annotations

import numpy as np
import pytest

from albot2d.errors import InputError
from albot2d.frames import Frame, Scan, beam_angles
from albot2d.geometry import Pose, between_arrays
from albot2d.mapping import GroundTruthIntegration, Mapper, NaiveIntegration


def wall_scan(distance_m: float) -> Scan:
    """A scan of a wall straight ahead at ``distance_m`` (exact ranges)."""
    angles = beam_angles(181)
    ranges = np.where(np.abs(angles) < 1.2, distance_m / np.cos(angles), 30.0)
    return Scan(ranges, angles, ranges < 30.0, max_range_m=30.0)


def frames(n: int = 5) -> list[Frame]:
    out = []
    prev_odom = None
    for k in range(n):
        true = Pose(0.1 * k, 0.0, 0.0)
        odom = Pose(10.0 + 0.11 * k, 5.0, 0.02 * k)
        inc = Pose() if prev_odom is None else prev_odom.between(odom)
        out.append(Frame(k, float(k), wall_scan(4.0 - 0.1 * k), odom, inc, true))
        prev_odom = odom
    return out


@pytest.mark.parametrize("cls", [NaiveIntegration, GroundTruthIntegration])
def test_baselines_are_mappers_that_keep_every_view(cls: type) -> None:
    m = cls()
    assert isinstance(m, Mapper)
    fs = frames()
    for f in fs:
        m.observe(f)
    assert m.counts().views == len(fs) == m.counts().local_maps
    snap = m.global_map()
    assert len(snap.segments) >= len(fs)  # nothing deleted: one wall surface per view at least
    assert sorted(set(snap.map_ids.tolist())) == list(range(1, len(fs) + 1))


def test_naive_follows_raw_odometry_and_truth_follows_truth() -> None:
    fs = frames()
    naive, truth = NaiveIntegration(), GroundTruthIntegration()
    for f in fs:
        naive.observe(f)
        truth.observe(f)
    odo = np.array([f.odom_pose.as_array() for f in fs])
    tru = np.array([f.true_pose.as_array() for f in fs])  # type: ignore[union-attr]
    np.testing.assert_allclose(naive.trajectory(), between_arrays(odo[:1], odo), atol=1e-12)
    np.testing.assert_allclose(truth.trajectory(), between_arrays(tru[:1], tru), atol=1e-12)
    # With true poses every view's wall lands at the same place: x = 4 m.
    xs = truth.global_map().segments[:, [0, 2]]
    np.testing.assert_allclose(xs, 4.0, atol=0.02)


def test_truth_mapper_rejects_real_logs() -> None:
    f = frames(1)[0]
    real = Frame(f.index, f.timestamp, f.scan, f.odom_pose, f.odom_increment, None)
    with pytest.raises(InputError, match="true poses"):
        GroundTruthIntegration().observe(real)
