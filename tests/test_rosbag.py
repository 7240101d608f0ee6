"""ROS bags out and in: ``simulate``/``run --export rosbag1 rosbag2`` and ``replay`` of bags.

Round trip: the frames read back from a bag are the simulator's (ranges to float32, poses to
1e-9 m), agree with the CARMEN log of the same run to the log's precision, and replaying the
bag gives the CARMEN replay's report numbers to that precision. Bags made with rosbags
directly (``tests/bag_helpers.py``) check what albot2d never writes: odometry on /tf only,
other topics, clockwise and wider scans, range_min/range_max, NaN ranges and bad bags.
"""

from __future__ import annotations

import json
import math
import shutil
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from albot2d.cli import main
from albot2d.evaluation.run.setup import RunSpec, build_run
from albot2d.logs import read_frames, read_run
from albot2d.logs.rosbag import read_bag, typestore_for
from albot2d.logs.rosbag_writer import write_bag
from tests.bad_input_checks import refused
from tests.bag_helpers import BagScan, bag_messages, write_test_bag

N_FRAMES = 120
FLOAT32_REL = 2.0**-24  # half a float32 ulp, relative


@pytest.fixture(scope="module")
def sim_frames() -> list[Any]:
    """The first frames of the default run (office seed 0, dataset1, typical odometry)."""
    setup = build_run(RunSpec(max_frames=N_FRAMES))
    frames = []
    for frame in setup.simulator.drive(setup.tour, setup.profile):
        frames.append(frame)
        if len(frames) == N_FRAMES:
            break
    return frames


@pytest.fixture(scope="module")
def simulated(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``albot2d simulate --export rosbag2 rosbag1`` of a short run."""
    out = tmp_path_factory.mktemp("sim") / "run"
    argv = ["simulate", "--out", str(out), "--max-frames", str(N_FRAMES), "--no-png"]
    assert main([*argv, "--export", "rosbag2", "rosbag1"]) == 0
    return out


def _same_pose(a: Any, b: Any, tol: float) -> None:
    assert abs(a.x - b.x) <= tol and abs(a.y - b.y) <= tol
    assert abs(math.remainder(a.theta - b.theta, 2 * math.pi)) <= tol


def _check_against_simulator(frames: list[Any], sim: list[Any]) -> None:
    assert len(frames) == len(sim)
    for got, want in zip(frames, sim, strict=True):
        assert got.index == want.index
        assert abs(got.timestamp - want.timestamp) <= 1e-9
        np.testing.assert_array_equal(got.scan.valid, want.scan.valid)
        r, w = got.scan.ranges[got.scan.valid], want.scan.ranges[want.scan.valid]
        assert np.all(np.abs(r - w) <= FLOAT32_REL * np.abs(w))
        np.testing.assert_allclose(got.scan.angles, want.scan.angles, rtol=0, atol=1e-7)
        assert got.scan.max_range_m == want.scan.max_range_m
        _same_pose(got.scan.laser_pose, want.scan.laser_pose, 1e-12)
        _same_pose(got.odom_pose, want.odom_pose, 1e-9)
        _same_pose(got.odom_increment, want.odom_increment, 1e-9)


@pytest.mark.parametrize(("version", "storage"), [(1, "mcap"), (2, "mcap"), (2, "sqlite3")])
def test_a_bag_gives_back_the_simulated_frames(
    sim_frames: list[Any], tmp_path: Path, version: int, storage: str
) -> None:
    path = tmp_path / ("run.bag" if version == 1 else "run")
    assert write_bag(path, sim_frames, ros_version=version, storage=storage) == N_FRAMES  # type: ignore[arg-type]
    if version == 2:
        suffix = ".mcap" if storage == "mcap" else ".db3"
        assert (path / "metadata.yaml").is_file() and (path / f"run{suffix}").is_file()
    bag = read_bag(path)
    assert bag.ros_version == version and bag.odometry_source == "/odom"
    assert set(bag.topics) == {"/scan", "/odom", "/tf", "/tf_static", "/ground_truth"}
    _check_against_simulator(bag.frames, sim_frames)
    assert not list(tmp_path.glob(".*")), "temporary files left behind"


def test_the_bag_holds_ros_conventions(sim_frames: list[Any], tmp_path: Path) -> None:
    """Frames, types, latching and the truth topic, read with rosbags alone."""
    from rosbags.highlevel import AnyReader

    path = tmp_path / "run"
    write_bag(path, sim_frames, ros_version=2)
    with AnyReader([path]) as reader:
        types = {c.topic: c.msgtype for c in reader.connections}
        assert types == {
            "/scan": "sensor_msgs/msg/LaserScan", "/odom": "nav_msgs/msg/Odometry",
            "/tf": "tf2_msgs/msg/TFMessage", "/tf_static": "tf2_msgs/msg/TFMessage",
            "/ground_truth": "nav_msgs/msg/Odometry",
        }  # fmt: skip
        static = next(c for c in reader.connections if c.topic == "/tf_static")
        assert "transient_local" in str(static.ext.offered_qos_profiles).lower()
        seen: dict[str, list[Any]] = {}
        for connection, ns, raw in reader.messages():
            msg = reader.deserialize(raw, connection.msgtype)
            seen.setdefault(connection.topic, []).append((ns, msg))
    assert [len(seen[t]) for t in ("/scan", "/odom", "/tf", "/ground_truth", "/tf_static")] == [
        N_FRAMES, N_FRAMES, N_FRAMES, N_FRAMES, 1,
    ]  # fmt: skip
    ns, scan = seen["/scan"][5]
    assert scan.header.frame_id == "laser" and ns == round(sim_frames[5].timestamp * 1e9)
    assert scan.header.stamp.sec * 10**9 + scan.header.stamp.nanosec == ns
    assert np.all(np.isinf(scan.ranges[~sim_frames[5].scan.valid]))  # REP-117 no return
    _, odom = seen["/odom"][5]
    assert (odom.header.frame_id, odom.child_frame_id) == ("odom", "base_link")
    tf = seen["/tf"][5][1].transforms[0]
    assert (tf.header.frame_id, tf.child_frame_id) == ("odom", "base_link")
    mount = seen["/tf_static"][0][1].transforms[0]
    assert (mount.header.frame_id, mount.child_frame_id) == ("base_link", "laser")
    _, truth = seen["/ground_truth"][5]
    assert truth.header.frame_id == "map"
    assert truth.pose.pose.position.x == sim_frames[5].true_pose.x


def test_bags_agree_with_the_carmen_log_of_the_run(simulated: Path) -> None:
    run = read_run(simulated)
    carmen = list(read_frames(simulated / "log.clf"))
    for name in ("log.bag", "log_ros2"):
        frames = read_bag(simulated / name).frames
        assert len(frames) == len(carmen) == len(run.frames) == N_FRAMES
        for got, want in zip(frames, carmen, strict=True):
            assert abs(got.timestamp - want.timestamp) <= 0.5e-6 + 1e-9  # the log's µs
            np.testing.assert_array_equal(got.scan.valid, want.scan.valid)
            v = got.scan.valid
            # The log writes ranges to 1 mm, the bag as float32.
            assert np.all(np.abs(got.scan.ranges[v] - want.scan.ranges[v]) <= 0.5e-3 + 1e-6)
            _same_pose(got.odom_pose, want.odom_pose, 0.5e-6 + 1e-9)  # the log's 1e-6


def _numbers(report: dict[str, Any]) -> dict[str, Any]:
    out = {"frames": report["run"]["frames"], "relations": report["run"]["relations_used"]}
    out["odometry"] = report["odometry"]["rpe"]
    for name, mapper in report["mappers"].items():
        out[name] = {"rpe": mapper["rpe"], "counts": mapper["counts"]}
    return out


def _close(a: Any, b: Any, tol: float, path: str = "") -> list[str]:
    if isinstance(a, dict):
        return [d for k in a for d in _close(a[k], b[k], tol, f"{path}.{k}")]
    if isinstance(a, float) and isinstance(b, float):
        return [] if abs(a - b) <= tol + 1e-5 * abs(a) else [f"{path}: {a} vs {b}"]
    return [] if a == b else [f"{path}: {a} vs {b}"]


def test_replaying_the_bags_gives_the_carmen_replays_numbers(
    simulated: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    reports = {}
    for name in ("log.clf", "log.bag", "log_ros2"):
        out = tmp_path / name
        assert main(["replay", str(simulated / name), "--out", str(out), "--no-figures"]) == 0
        reports[name] = json.loads((out / "report.json").read_text())
    capsys.readouterr()
    carmen, ros1, ros2 = (_numbers(reports[n]) for n in ("log.clf", "log.bag", "log_ros2"))
    assert carmen["relations"] > 50  # the run's log.relations is found beside the bags
    assert reports["log.bag"]["run"]["relations_path"] == str(simulated / "log.relations")
    assert ros1 == ros2  # the same float32 ranges and float64 poses: bit for bit
    # The CARMEN log holds poses to 1e-6 m and ranges to 1 mm; the RPE numbers agree to that.
    assert _close(carmen, ros1, 1e-5) == []
    assert reports["log.bag"]["log"]["bag"]["format"] == "rosbag1"
    assert reports["log_ros2"]["log"]["bag"]["odometry"] == "/odom"


def test_run_exports_bags_beside_the_tum_files(tmp_path: Path) -> None:
    out = tmp_path / "run"
    argv = ["run", "--out", str(out), "--max-frames", "25", "--mapper", "naive", "--no-figures"]
    assert (
        main([*argv, "--export", "rosbag2", "--export", "rosbag1", "--bag-storage", "sqlite3"]) == 0
    )
    report = json.loads((out / "report.json").read_text())
    assert {"log.bag", "log_ros2", "odometry.tum", "groundtruth.tum"} <= set(report["exports"])
    assert list((out / "log_ros2").glob("*.db3"))
    frames = read_bag(out / "log_ros2").frames
    assert len(frames) == len(read_bag(out / "log.bag").frames) == 25
    tum = np.loadtxt(out / "odometry.tum")
    assert tum[:, 0] == pytest.approx([f.timestamp for f in frames], abs=1e-6)


def test_odometry_from_tf_other_topics_and_scan_geometry(tmp_path: Path) -> None:
    """No odometry topic: /tf odom->base_link; a clockwise 360-beam scan with range_min."""
    inc = -2 * math.pi / 360
    ranges = [float("inf"), 0.05, 5.0, float("nan"), 12.0, float("-inf")] + [3.0] * 354
    scans = [
        BagScan(t=100.0 + 0.1 * k, ranges=ranges, pose=(0.1 * k, 0.0, 0.01 * k),
                angle_min=math.pi - 1e-3, angle_increment=inc, range_min=0.1, range_max=10.0)
        for k in range(5)
    ]  # fmt: skip
    path = write_test_bag(
        tmp_path / "tf.bag", ros1=True, scans=scans, scan_topic="/base_scan", odom_topic=None
    )
    bag = read_bag(path, scan_topic="base_scan")
    assert bag.odometry_source == "/tf odom->base_link" and bag.scan_topic == "/base_scan"
    frame = bag.frames[3]
    assert frame.timestamp == pytest.approx(100.3, abs=1e-9)
    assert (frame.odom_pose.x, frame.odom_pose.theta) == pytest.approx((0.3, 0.03), abs=1e-12)
    assert frame.scan.laser_pose.x == pytest.approx(0.1)
    assert np.all(np.diff(frame.scan.angles) > 0)  # reversed into counter-clockwise order
    assert frame.scan.angles[-1] == pytest.approx(math.pi - 1e-3, abs=1e-6)
    valid = frame.scan.valid[::-1]  # back to the bag's order
    assert valid[:6].tolist() == [False, False, True, False, False, False]  # 12 > range_max
    assert frame.scan.max_range_m == 10.0
    nan_or_inf = np.isnan(frame.scan.ranges).sum(), np.isinf(frame.scan.ranges).sum()
    assert nan_or_inf == (1, 0)  # ±inf are REP-117 codes (stored as range_max); NaN is kept


def test_odometry_is_interpolated_and_scans_outside_it_dropped(tmp_path: Path) -> None:
    store = typestore_for(2)
    poses = [BagScan(t=float(t), ranges=[1.0, 1.0], pose=(t, 0.0, 0.0)) for t in (10, 11, 12)]
    odom = [m for m in bag_messages(store, False, poses) if m[0] in ("/odom", "/tf_static")]
    at = [BagScan(t=t, ranges=[1.0] * 181) for t in (9.5, 10.25, 11.5, 12.5)]
    scans = bag_messages(store, False, at, odom_topic=None, tf=False, mount=None)
    path = write_test_bag(
        tmp_path / "interp.mcap", sorted(odom + scans, key=lambda m: m[2]), ros1=False
    )
    bag = read_bag(path)
    assert [f.timestamp for f in bag.frames] == [10.25, 11.5]
    assert [f.odom_pose.x for f in bag.frames] == pytest.approx([10.25, 11.5])
    assert bag.scans_without_odometry == 2


def _scan_bag(tmp_path: Path, name: str = "s.bag", **fields: Any) -> Path:
    """Three 181-beam scans with ``fields`` changed (bag options: topics, tf, mount)."""
    options = {k: fields.pop(k) for k in ("scan_topic", "odom_topic", "tf", "mount") if k in fields}
    scan = {"t": 1.0, "ranges": [1.0] * 181} | fields
    scans = [BagScan(**(scan | {"t": scan["t"] + 0.1 * k})) for k in range(3)]
    return write_test_bag(tmp_path / name, ros1=name.endswith(".bag"), scans=scans, **options)


def _cut(path: Path, keep: float) -> Path:
    target = path if path.is_file() else next(path.glob("*.mcap"))
    data = target.read_bytes()
    target.write_bytes(data[: int(len(data) * keep)])
    return path


BAD_BAGS = {
    "truncated ROS 1": (lambda p: _cut(_scan_bag(p), 0.6), "not a readable ROS bag"),
    "truncated MCAP": (lambda p: _cut(_scan_bag(p, "s.mcap"), 0.5), "s.mcap"),
    "garbage .bag": (lambda p: _write(p / "g.bag", b"not a bag at all\n"), "not a ROS bag"),
    "empty file": (lambda p: _write(p / "e.mcap", b""), "not a ROS bag"),
    "not a bag directory": (lambda p: _mkdir(p / "d"), "not a readable ROS bag"),
    "empty bag": (lambda p: write_test_bag(p / "e.bag", [], ros1=True), "the bag has no topics"),
    "missing scan topic": (
        lambda p: _scan_bag(p, scan_topic="/laser"),
        "no topic /scan (give --scan-topic); the bag has /laser (sensor_msgs/msg/LaserScan)",
    ),
    "wrong scan type": (lambda p: _renamed_topics(p, {"/odom": "/scan", "/scan": "/other"}),
                        "topic /scan holds nav_msgs/msg/Odometry, expected sensor_msgs/msg/Laser"),
    "no odometry": (lambda p: _scan_bag(p, odom_topic=None, tf=False), "no odometry"),
    "NaN angle_min": (lambda p: _scan_bag(p, angle_min=float("nan")), "angle_min nan"),
    "range_max 0": (lambda p: _scan_bag(p, range_max=0.0), "make no interval"),
    "odometry off the map": (lambda p: _scan_bag(p, pose=(1e9, 0.0, 0.0)), "position x"),
    "a bag named as a log": (lambda p: _renamed(_scan_bag(p), "s.mcap"), "name it *.bag"),
}  # fmt: skip


def _write(path: Path, data: bytes) -> Path:
    path.write_bytes(data)
    return path


def _mkdir(path: Path) -> Path:
    path.mkdir()
    (path / "notes.txt").write_text("hello")
    return path


def _renamed(path: Path, name: str) -> Path:
    return path.rename(path.with_name(name))


def _renamed_topics(tmp_path: Path, names: dict[str, str]) -> Path:
    store = typestore_for(1)
    scans = [BagScan(t=1.0 + 0.1 * k, ranges=[1.0] * 181) for k in range(3)]
    messages = [(names.get(m[0], m[0]), *m[1:]) for m in bag_messages(store, True, scans)]
    return write_test_bag(tmp_path / "w.bag", messages, ros1=True)


@pytest.mark.parametrize("case", list(BAD_BAGS))
def test_bad_bags_are_one_line_and_no_output(
    case: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    make, expected = BAD_BAGS[case]
    bag = make(tmp_path)
    out = tmp_path / "out"
    refused(capsys, ["replay", str(bag), "--out", str(out)], str(bag), expected)
    assert not out.exists()


def test_nan_ranges_are_anomalies_and_strict_refuses_them(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bag = _scan_bag(tmp_path, ranges=[float("nan")] * 3 + [2.0] * 178)
    out = tmp_path / "out"
    assert main(["replay", str(bag), "--out", str(out), "--no-figures", "--mapper", "naive"]) == 0
    err = capsys.readouterr().err
    assert "9 non-finite ranges" in err and "warning" in err
    report = json.loads((out / "report.json").read_text())
    assert report["log"]["anomalies"]["non_finite_ranges"] == 9
    refused(capsys, ["replay", str(bag), "--strict", "--out", str(tmp_path / "o2")],
            "log anomalies (strict): 9 non-finite ranges")  # fmt: skip


def test_topic_options_are_for_bags_only(
    simulated: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["replay", str(simulated / "log.clf"), "--scan-topic", "/scan"]
    refused(capsys, [*argv, "--out", str(tmp_path / "o")], "apply to ROS bags only")


def test_a_failed_export_leaves_no_run_files(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A scan albot2d cannot write as a LaserScan fails the export; nothing stays."""
    from albot2d.cli import exporters

    def failing(source: Any, directory: Path) -> None:
        (directory / "half.bag").write_bytes(b"#ROSBAG")
        raise OSError(28, "No space left on device", str(directory / "half.bag"))

    monkeypatch.setitem(
        exporters.EXPORTERS, "rosbag1", exporters.Exporter("rosbag1", "", failing, True)
    )
    out = tmp_path / "sim"
    assert main(["simulate", "--out", str(out), "--max-frames", "5", "--no-png",
                 "--export", "rosbag1"]) == 2  # fmt: skip
    assert "No space left" in capsys.readouterr().err
    assert not out.exists() or list(out.iterdir()) == []


def test_simulate_writes_a_bag_that_replays_with_its_relations(
    simulated: Path, tmp_path: Path
) -> None:
    """The bag can be moved out of the run directory and scored with --relations."""
    bag = tmp_path / "moved.bag"
    shutil.copy(simulated / "log.bag", bag)
    out = tmp_path / "out"
    relations = str(simulated / "log.relations")
    argv = ["replay", str(bag), "--relations", relations, "--out", str(out), "--no-figures"]
    assert main([*argv, "--mapper", "naive"]) == 0
    report = json.loads((out / "report.json").read_text())
    assert report["run"]["relations_used"] == report["run"]["relations"] > 0


@pytest.mark.parametrize("command", ["simulate", "run"])
def test_bag_storage_needs_a_ros2_export(
    command: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    argv = [command, "--out", str(out), "--bag-storage", "sqlite3", "--export", "rosbag1"]
    refused(capsys, argv, "--bag-storage sqlite3 applies to --export rosbag2 only")
    assert not out.exists()


@pytest.mark.parametrize("name", ["log.bag", "log_ros2"])
def test_evo_reads_the_bags_trajectories_and_tf_tree(simulated: Path, name: str) -> None:
    """A ROS user's tool on the bag: evo's bag readers give the run's odometry and truth
    (evo's /tf reading needs ROS's tf2_py, so the tf tree is checked with rosbags above)."""
    pytest.importorskip("evo", reason="evo is the [eval] extra (also in the test extra)")
    from evo.tools import file_interface
    from rosbags.rosbag1 import Reader as Reader1
    from rosbags.rosbag2 import Reader as Reader2

    run = read_run(simulated)
    reader_type = Reader1 if name.endswith(".bag") else Reader2
    with reader_type(simulated / name) as reader:
        odom = file_interface.read_bag_trajectory(reader, "/odom")
        truth = file_interface.read_bag_trajectory(reader, "/ground_truth")
    stamps = [f.timestamp for f in run.frames]
    np.testing.assert_allclose(odom.timestamps, stamps, rtol=0, atol=1e-6)
    odom_xy = np.array([[f.odom_pose.x, f.odom_pose.y] for f in run.frames])
    np.testing.assert_allclose(odom.positions_xyz[:, :2], odom_xy, rtol=0, atol=1e-6)
    true_xy = np.array([[f.true_pose.x, f.true_pose.y] for f in run.frames])
    np.testing.assert_allclose(truth.positions_xyz[:, :2], true_xy, rtol=0, atol=1e-12)


def test_zero_header_stamps_use_the_record_time_and_a_bare_storage_dir_reads(
    tmp_path: Path,
) -> None:
    """Drivers that leave header stamps at 0: the bag's record time stamps the frames; a
    ROS 2 bag directory that lost its metadata.yaml is read from its one storage file."""
    store = typestore_for(2)
    real = [
        BagScan(t=5.0 + 0.1 * k, ranges=[2.0] * 181, pose=(0.1 * k, 0.0, 0.0)) for k in range(4)
    ]
    zero = [BagScan(t=0.0, ranges=s.ranges, pose=s.pose) for s in real]
    timed = bag_messages(store, False, real)
    messages = [
        (topic, kind, ns, message)
        for (topic, kind, ns, _), (*_, message) in zip(
            timed, bag_messages(store, False, zero), strict=True
        )
    ]
    bag = write_test_bag(tmp_path / "zero", messages, ros1=False)
    (bag / "metadata.yaml").unlink()
    frames = read_bag(bag).frames
    assert [f.timestamp for f in frames] == pytest.approx([5.0, 5.1, 5.2, 5.3], abs=1e-9)
    assert [f.odom_pose.x for f in frames] == pytest.approx([0.0, 0.1, 0.2, 0.3])


def test_an_upside_down_laser_is_mirrored_and_a_tilted_one_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """base_link -> laser rolled by pi (yaw 0.3 too): a beam at laser angle a points at
    0.3 - a; the hits in the base frame are those of the same scan mounted upright with
    mirrored angles. A 30 deg tilt is refused."""
    yaw, ranges = 0.3, [1.0 + 0.01 * k for k in range(181)]
    # Rz(yaw) * Rx(pi) as a quaternion (x, y, z, w).
    flipped = (math.cos(yaw / 2), math.sin(yaw / 2), 0.0, 0.0)
    scans = [BagScan(t=1.0 + 0.1 * k, ranges=ranges) for k in range(3)]
    bag = write_test_bag(tmp_path / "flip.bag", ros1=True, scans=scans, mount_rotation=flipped)
    scan = read_bag(bag).frames[0].scan
    assert scan.laser_pose.theta == pytest.approx(yaw) and scan.laser_pose.x == pytest.approx(0.1)
    assert np.all(np.diff(scan.angles) > 0)
    a = -math.pi / 2 + math.pi / 180 * np.arange(181)
    expected = np.column_stack(
        [0.1 + np.array(ranges) * np.cos(yaw - a), np.array(ranges) * np.sin(yaw - a)]
    )
    got = scan.points()
    order = np.lexsort(got.T)
    np.testing.assert_allclose(got[order], expected[np.lexsort(expected.T)], atol=1e-6)
    tilt = math.radians(30)
    tilted = (math.sin(tilt / 2), 0.0, 0.0, math.cos(tilt / 2))
    bad = write_test_bag(tmp_path / "tilt.bag", ros1=True, scans=scans, mount_rotation=tilted)
    refused(capsys, ["replay", str(bad), "--out", str(tmp_path / "o")], "tilted 30.0 deg")


def test_without_rosbags_bags_are_one_line_with_the_install_command(
    simulated: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    for name in [m for m in sys.modules if m == "rosbags" or m.startswith("rosbags.")]:
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.setitem(sys.modules, "rosbags", None)  # import rosbags raises ImportError
    hint = "pip install 'albot2d[ros]'"
    refused(capsys, ["replay", str(simulated / "log.bag"), "--out", str(tmp_path / "o")], hint)
    out = tmp_path / "sim"
    refused(capsys, ["simulate", "--out", str(out), "--export", "rosbag1"], hint)
    assert not out.exists()
