"""The scan-matching front end alone (``scan_odometry``, KISS-ICP): accuracy, protocol,
determinism, and the ``[slam]`` extra's clean errors (the loop closing: test_slam_loops.py).

Tests that need kiss-icp skip when the ``[slam]`` extra is not installed; the clean error
for a missing extra is tested either way (by making ``kiss_icp`` unimportable).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest

from albot2d.cli import main
from albot2d.errors import InputError
from albot2d.evaluation.metrics.map_quality import map_quality
from albot2d.evaluation.metrics.rpe import relative_pose_error
from albot2d.frames import Frame, Scan, beam_angles
from albot2d.geometry import Pose, between_arrays
from albot2d.logs.relations import relations_from_truth
from albot2d.mapping import Mapper, NaiveIntegration
from albot2d.mapping.registry import BUILTIN_MAPPERS
from albot2d.mapping.slam import ScanMatchingParams, ScanMatchingSLAM
from tests.runs import map_frames, office_loop
from worldgen.world import World

MISSING = "kiss-icp is not installed (pip install -e '.[slam]')"


@pytest.fixture(scope="module")
def kiss() -> ModuleType:
    return pytest.importorskip("kiss_icp", reason=MISSING)


@pytest.fixture(scope="module")
def office_run() -> tuple[World, list[Frame]]:
    """A ~30 m loop through a small office, dataset3 profile, typical odometry noise."""
    return office_loop()


def test_slam_beats_odometry_and_naive_integration(
    kiss: ModuleType, office_run: tuple[World, list[Frame]]
) -> None:
    world, frames = office_run
    slam = map_frames(ScanMatchingSLAM(), frames)
    naive = map_frames(NaiveIntegration(), frames)
    times = np.array([f.timestamp for f in frames])
    truth = np.array([f.true_pose.as_array() for f in frames])  # type: ignore[union-attr]
    rel = relations_from_truth(times, truth)

    def rpe(poses: np.ndarray) -> tuple[float, float]:
        r = relative_pose_error(times, poses, rel.t1, rel.t2, rel.motion).overall
        assert r.trans_m_mean is not None and r.rot_deg_mean is not None
        return r.trans_m_mean, r.rot_deg_mean

    odometry = rpe(np.array([f.odom_pose.as_array() for f in frames]))
    scan_matched = rpe(slam.trajectory())
    assert scan_matched[0] < odometry[0] and scan_matched[1] < odometry[1]

    start = frames[0].true_pose
    assert start is not None
    q_slam = map_quality(slam.global_map().segments, world.obstacle_segments, start_pose=start)
    q_naive = map_quality(naive.global_map().segments, world.obstacle_segments, start_pose=start)
    assert q_slam.accuracy_m_mean is not None and q_naive.accuracy_m_mean is not None
    assert q_slam.accuracy_m_mean < q_naive.accuracy_m_mean
    assert q_slam.accuracy_m_p95 < q_naive.accuracy_m_p95  # type: ignore[operator]


def test_slam_is_a_deterministic_protocol_mapper(
    kiss: ModuleType, office_run: tuple[World, list[Frame]]
) -> None:
    _, frames = office_run
    frames = frames[:120]
    first = BUILTIN_MAPPERS["scan_odometry"]()
    assert isinstance(first, Mapper) and first.name == "scan_odometry"
    map_frames(first, frames)
    again = map_frames(ScanMatchingSLAM(), frames)
    traj = first.trajectory()
    assert traj.shape == (len(frames), 3) and np.all(np.isfinite(traj))
    np.testing.assert_array_equal(traj, again.trajectory())
    snap, snap_again = first.global_map(), again.global_map()
    np.testing.assert_array_equal(snap.segments, snap_again.segments)
    np.testing.assert_array_equal(snap.map_ids, snap_again.map_ids)
    assert snap.segments.shape[1] == 4 and len(snap.segments) == len(snap.map_ids)
    np.testing.assert_array_equal(first.pose().as_array(), traj[-1])
    np.testing.assert_array_equal(traj[0], 0.0)  # the global frame is the first pose's
    counts = first.counts()
    assert counts.views == counts.local_maps == len(frames)
    assert counts.triangulations + counts.path_integrations == len(frames) - 1
    assert {"extraction", "scan_matching", "global_map"} <= set(first.timings_ms())


def blind_scan() -> Scan:
    angles = beam_angles(181)
    return Scan(np.full(181, 30.0), angles, np.zeros(181, bool), max_range_m=30.0)


def test_scans_without_enough_hits_follow_odometry(kiss: ModuleType) -> None:
    frames, prev = [], None
    for k in range(6):
        odom = Pose(3.0 + 0.2 * k, -1.0, 0.1 * k)
        inc = Pose() if prev is None else prev.between(odom)
        frames.append(Frame(k, float(k), blind_scan(), odom, inc))
        prev = odom
    slam = map_frames(ScanMatchingSLAM(), frames)
    odo = np.array([f.odom_pose.as_array() for f in frames])
    np.testing.assert_allclose(slam.trajectory(), between_arrays(odo[:1], odo), atol=1e-9)
    assert slam.counts().path_integrations == len(frames) - 1
    assert slam.counts().triangulations == 0
    assert len(slam.global_map().segments) == 0


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ({"voxel_size_m": 0.0}, "voxel_size_m"),
        ({"layer_heights_m": (0.0,)}, "layer_heights_m"),
        ({"layer_heights_m": (0.5, 0.5)}, "layer_heights_m"),
        ({"min_range_m": 40.0}, "min_range_m"),
        ({"fixed_threshold_m": -1.0}, "fixed_threshold_m"),
        ({"map_update_m": -1.0}, "map_update_m"),
        ({"prior": "imu"}, "prior"),
        ({"prior_gate_deg": 0.0}, "prior_gate_deg"),
    ],
)
def test_bad_params_name_the_field(overrides: dict[str, object], message: str) -> None:
    with pytest.raises(InputError, match=message):
        ScanMatchingParams(**overrides)  # type: ignore[arg-type]


@pytest.fixture
def without_kiss(monkeypatch: pytest.MonkeyPatch) -> None:
    """Make kiss_icp unimportable, as when the extra is not installed."""
    for name in ("kiss_icp", "kiss_icp.config", "kiss_icp.kiss_icp"):
        monkeypatch.setitem(sys.modules, name, None)


@pytest.mark.usefixtures("without_kiss")
def test_missing_extra_is_one_clean_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(InputError, match=r"pip install 'albot2d\[slam\]'"):
        ScanMatchingSLAM()
    out = tmp_path / "out"
    code = main(["run", "--mapper", "naive", "--mapper", "slam", "--kind", "rooms", "--width",
                 "15", "--height", "15", "--tour-length", "20", "--out", str(out)])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 2
    assert err.strip().count("\n") == 0 and "albot2d[slam]" in err
    assert not (out / "report.json").exists()


def test_run_cli_scores_the_slam_mapper(
    kiss: ModuleType, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    assert main(["run", "--mapper", "albot1", "--mapper", "scan_odometry", "--mapper", "slam",
                 "--kind", "rooms", "--width", "15", "--height", "15", "--tour-length", "20",
                 "--profile", "dataset3", "--max-frames", "60", "--no-figures",
                 "--out", str(out)]) == 0  # fmt: skip
    assert "slam" in capsys.readouterr().out
    report = json.loads((out / "report.json").read_text())
    assert list(report["mappers"]) == ["albot1", "scan_odometry", "slam"]
    slam = report["mappers"]["slam"]
    assert slam["counts"]["views"] == 60 and slam["rpe"]["relations"] > 0


def test_front_end_is_kiss_icps_own_step_unless_map_updates_are_thinned(
    kiss: ModuleType, office_run: tuple[World, list[Frame]]
) -> None:
    """The front end runs KISS-ICP's ``register_frame`` step by step (to thin the map
    insertions): with the default (every scan joins the map) it gives the library's own
    poses (to rounding: ~1e-17 rad); with ``map_update_m``/``_deg`` fewer scans join the map and the
    poses differ."""
    from kiss_icp.kiss_icp import KissICP

    from albot2d.mapping.protocol import StageTimer
    from albot2d.mapping.slam.front_end import KissIcpOdometry, _planar, se2_matrix_4x4

    frames = office_run[1][:120]
    ours = KissIcpOdometry(ScanMatchingParams(), StageTimer())
    icp = KissICP(ours._config(ours._icp.config))
    reference = []
    for frame in frames:
        pose = ours.register(frame)
        icp.last_delta = se2_matrix_4x4(frame.odom_increment.as_array())
        lifted = ours.lift(frame.scan.points())
        icp.register_frame(lifted, np.zeros(len(lifted)))
        icp.last_pose = se2_matrix_4x4(_planar(icp.last_pose))
        reference.append(_planar(icp.last_pose))
        np.testing.assert_allclose(pose, reference[-1], rtol=0, atol=1e-12)
    thinned = KissIcpOdometry(ScanMatchingParams(map_update_m=0.5, map_update_deg=10.0),
                              StageTimer())  # fmt: skip
    poses = np.array([thinned.register(f) for f in frames])
    assert np.all(np.isfinite(poses))
    assert np.abs(poses - np.array(reference)).max() > 1e-6


def test_scan_to_scan_prior_recovers_the_mit_logs_fast_turns(
    kiss: ModuleType, shared_data: Path
) -> None:
    """The MIT log's odometry overstates fast turns (30° between scans 153 and 154 where
    the relations say 17°). KISS-ICP against its local map stays near such a prior; the
    previous scan alone pulls the heading to the truth (README, issue 11), so with the
    scan-to-scan prior far fewer short relations are off by more than 5°; ``gated`` takes
    its heading only on the scans where the two disagree by more than 2°."""
    from albot2d.evaluation.metrics.rpe import relation_errors
    from albot2d.logs import read_frames, read_relations
    from albot2d.mapping.protocol import StageTimer
    from albot2d.mapping.slam.front_end import KissIcpOdometry

    frames = list(read_frames(shared_data / "raw" / "mit-csail.clf.gz"))[:400]
    rel = read_relations(shared_data / "relations" / "mit-csail.relations")
    times = np.array([f.timestamp for f in frames])
    short = rel.t2 - rel.t1 < 2.0
    bad, switches = {}, {}
    for prior in ("odometry", "scan_to_scan", "gated"):
        fe = KissIcpOdometry(ScanMatchingParams(prior=prior), StageTimer())
        poses = np.array([fe.register(f) for f in frames])
        switches[prior] = fe.prior_switches
        _, rot, used = relation_errors(times, poses, rel.t1, rel.t2, rel.motion)
        assert np.count_nonzero(used & short) > 150
        bad[prior] = int(np.count_nonzero(used & short & (np.degrees(rot) > 5.0)))
    assert bad["scan_to_scan"] * 3 < bad["odometry"], bad
    assert bad["gated"] * 2 < bad["odometry"], bad
    assert switches["odometry"] == switches["scan_to_scan"] == 0
    assert 0 < switches["gated"] < len(frames) // 2
