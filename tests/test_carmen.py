"""CARMEN reader/writer: round trips, the real MIT log, stats, bad lines, beam geometry."""

from __future__ import annotations

import gzip
import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given

from albot2d.errors import InputError
from albot2d.frames import Frame
from albot2d.geometry import Pose, wrap_angle
from albot2d.logs import (
    EXACT,
    LOG_PRECISION,
    CarmenReader,
    FloatFormat,
    LaserRecord,
    NeffRecord,
    OdomRecord,
    ParamRecord,
    format_record,
    read_carmen,
    read_frames,
    write_carmen,
)
from tests.log_strategies import frame_sequences

STAMPS = "1.5 host 0.25"


def _write(tmp_path: Path, text: str, name: str = "log.clf") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def _flaser(ranges: list[float], pose: str = "0 0 0", stamp: str = "1.5") -> str:
    values = " ".join(map(str, ranges))
    return f"FLASER {len(ranges)} {values} {pose} {pose} {stamp} host 0.25"


def _assert_same_frames(read: list[Frame], written: list[Frame], fmt: FloatFormat) -> None:
    exact = fmt == EXACT
    t_tol = 0.0 if exact else 1e-6
    assert len(read) == len(written)
    for k, (got, want) in enumerate(zip(read, written, strict=True)):
        assert got.index == k
        assert got.timestamp == pytest.approx(want.timestamp, rel=0, abs=t_tol)
        assert got.scan.timestamp == got.timestamp
        for a, b in ((got.odom_pose, want.odom_pose),):
            assert a.x == pytest.approx(b.x, rel=0, abs=t_tol)
            assert a.y == pytest.approx(b.y, rel=0, abs=t_tol)
            assert abs(wrap_angle(a.theta - b.theta)) <= t_tol
        expected_increment = read[k - 1].odom_pose.between(got.odom_pose) if k else Pose()
        assert got.odom_increment == expected_increment
        assert got.true_pose is None
        np.testing.assert_array_equal(got.scan.valid, want.scan.valid)
        np.testing.assert_allclose(got.scan.angles, want.scan.angles, rtol=0, atol=1e-9)
        valid = want.scan.valid
        range_tol = 0.0 if exact else 5e-4 + 1e-12
        np.testing.assert_allclose(
            got.scan.ranges[valid], want.scan.ranges[valid], rtol=0, atol=range_tol
        )
        assert got.scan.max_range_m == want.scan.max_range_m
        assert got.scan.laser_pose == want.scan.laser_pose


@pytest.mark.parametrize("fmt", [LOG_PRECISION, EXACT], ids=["log_precision", "exact"])
@pytest.mark.parametrize("suffix", [".clf", ".clf.gz"])
@given(frames=frame_sequences())
def test_write_read_round_trip(tmp_path_factory, fmt, suffix, frames):
    path = tmp_path_factory.mktemp("rt") / f"log{suffix}"
    assert write_carmen(path, frames, params={"seed": 7}, float_format=fmt) == len(frames)
    assert (path.read_bytes()[:2] == b"\x1f\x8b") == suffix.endswith(".gz")
    _assert_same_frames(list(read_frames(path)), frames, fmt)


@given(frames=frame_sequences(max_frames=2))
def test_raw_log_layout_and_params(tmp_path_factory, frames):
    path = tmp_path_factory.mktemp("layout") / "log.clf"
    params = {
        "laser": {"noise_m": 0.01},
        "world": "maze-3",
        "note": "two words\tand a tab",
        "sizes": [1, "a b"],
        "empty": "",
        "my key": True,
    }
    write_carmen(path, frames, params=params)
    reader = CarmenReader(path)
    records = list(reader)
    params = {r.name: r.value for r in records if isinstance(r, ParamRecord)}
    assert params["albot2d_laser.noise_m"] == "0.01"
    assert params["albot2d_world"] == "maze-3"
    assert json.loads(params["albot2d_note"]) == "two words\tand a tab"
    assert json.loads(params["albot2d_sizes"]) == [1, "a b"]
    assert json.loads(params["albot2d_empty"]) == ""
    assert params["albot2d_my_key"] == "true"
    assert float(params["robot_front_laser_max"]) == frames[0].scan.max_range_m
    assert "albot2d_version" in params
    assert reader.stats.counts == {"PARAM": len(params), "ODOM": len(frames), "FLASER": len(frames)}
    lasers = [r for r in records if isinstance(r, LaserRecord)]
    odoms = [r for r in records if isinstance(r, OdomRecord)]
    for laser, odom, frame in zip(lasers, odoms, frames, strict=True):
        assert laser.hostname == odom.hostname == "albot2d"
        assert laser.pose == laser.odom_pose == odom.pose
        assert laser.ipc_timestamp == odom.ipc_timestamp
        assert laser.logger_timestamp >= 0.0
        # Invalid beams carry the max range (rounded up to 1 mm): a no-return to any reader.
        no_return = laser.ranges[~frame.scan.valid]
        max_range = frame.scan.max_range_m
        assert np.all((no_return >= max_range) & (no_return < max_range + 1e-3))


def test_gzip_detected_by_magic_not_suffix(tmp_path):
    text = _flaser([1.0, 2.0, 3.0]) + "\n"
    gz_named_clf = tmp_path / "a.clf"
    gz_named_clf.write_bytes(gzip.compress(text.encode()))
    plain_named_gz = _write(tmp_path, text, "b.clf.gz")
    for path in (gz_named_clf, plain_named_gz):
        (record,) = read_carmen(path)
        np.testing.assert_array_equal(record.ranges, [1.0, 2.0, 3.0])


def test_mit_log_reads_completely(shared_data):
    path = shared_data / "raw" / "mit-csail.clf.gz"
    reader = CarmenReader(path)
    lasers = [r for r in reader if isinstance(r, LaserRecord)]
    assert reader.stats.counts == {"FLASER": 1988}
    assert reader.stats.n_comments == 3 and reader.stats.n_skipped == 0
    assert {r.n_beams for r in lasers} == {361}
    assert all(r.pose == r.odom_pose for r in lasers)
    frames = list(read_frames(path))
    assert len(frames) == 1988 and frames[-1].index == 1987
    t = np.array([f.timestamp for f in frames])
    assert t[0] == pytest.approx(1134864629.9, abs=0.05)
    assert t[-1] == pytest.approx(1134865053.9, abs=0.05)
    assert np.all(np.diff(t) > 0)
    assert frames[0].odom_pose.x == pytest.approx(577.0, abs=1.0)
    path_length = sum(math.hypot(f.odom_increment.x, f.odom_increment.y) for f in frames)
    assert path_length == pytest.approx(374.0, abs=2.0)
    scan = frames[0].scan
    np.testing.assert_allclose(np.degrees(scan.angles[[0, 1, -1]]), [-90.0, -89.5, 90.0])
    assert not np.any(scan.valid[scan.ranges >= 81.0])
    assert 0.5 < np.mean([f.scan.valid.mean() for f in frames]) < 1.0


def test_unknown_types_counted_and_comments(tmp_path):
    lines = [
        "# a comment",
        "SYNC 1 2 3",
        "",
        "PARAM robot_frontlaser_offset 0.25 1.0 host 0.0",
        "TRUEPOS 0 0 0 0 0 0 1.0 host 1.0",
        "ODOM 1 2 0.5 0.1 0.2 0.0 " + STAMPS,
        _flaser([1.0, 2.0]),
        "SYNC 4",
        "NEFF 123.5",
        "RLASER 2 1 1 0 0 0 0 0 0 2.0 host 0.3",
    ]
    path = _write(tmp_path, "\n".join(lines) + "\n")
    reader = CarmenReader(path, include_comments=True)
    records = list(reader)
    assert reader.stats.skipped == {"SYNC": 2, "TRUEPOS": 1}
    assert reader.stats.counts == {"PARAM": 1, "ODOM": 1, "FLASER": 1, "NEFF": 1, "RLASER": 1}
    assert (reader.stats.n_lines, reader.stats.n_comments, reader.stats.n_blank) == (10, 1, 1)
    assert records[0].text == "a comment"
    assert isinstance(records[-2], NeffRecord) and records[-2].value == 123.5
    odom = records[2]
    assert isinstance(odom, OdomRecord)
    assert (odom.pose, odom.tv_mps, odom.rv_radps) == (Pose(1, 2, 0.5), 0.1, 0.2)
    assert odom.line_number == 6
    # RLASER and ODOM are not frames; the FLASER one is, with the PARAM mount.
    (frame,) = read_frames(path)
    assert frame.index == 0 and frame.scan.laser_pose == Pose(0.25, 0.0, 0.0)


def test_truncated_gzip_names_the_file(tmp_path):
    data = gzip.compress(("\n".join([_flaser([1.0] * 50)] * 50) + "\n").encode())
    path = tmp_path / "cut.clf.gz"
    path.write_bytes(data[: len(data) // 2])
    with pytest.raises(InputError, match=r"cut\.clf\.gz: corrupt or truncated gzip data"):
        list(read_carmen(path))


def test_reader_is_lazy(tmp_path):
    path = _write(tmp_path, _flaser([1.0]) + "\nFLASER 2 oops\n")
    records = read_carmen(path)
    assert next(records).ranges.tolist() == [1.0]
    with pytest.raises(InputError, match=r"log\.clf:2:"):
        next(records)


BAD_LINES = [
    ("FLASER", "no n"),
    ("FLASER x 1 0 0 0 0 0 0 " + STAMPS, "'x' (field 1) is not an integer"),
    ("FLASER -2 " + STAMPS, "must be >= 0, got -2"),
    ("FLASER 3 1 2 0 0 0 0 0 0 " + STAMPS, "n=3 has 13 fields, expected 14 (ends where logger_"),
    (
        "FLASER 4 1",
        "n=4 has 3 fields, expected 15 (ends where range 1, range 2, range 3, x, ... should be)",
    ),
    ("FLASER 999999999999 1 2", "n 999999999999 (field 1) is more than the limit of 65536"),
    ("FLASER 2 1 2 3 0 0 0 0 0 0 " + STAMPS, "1 extra"),
    ("FLASER 2 1 2 0 0 0 0 0 0", "ends where ipc_timestamp, ipc_hostname, logger_timestamp"),
    ("FLASER 2 1 2 0 0 0 0 0 0 1.5 host", "ends where logger_timestamp"),
    ("FLASER 2 1.0 abc 0 0 0 0 0 0 " + STAMPS, "range 1 'abc' (field 3) is not a number"),
    ("FLASER 2 1 2 0 zz 0 0 0 0 " + STAMPS, "y 'zz' (field 5) is not a number"),
    ("FLASER 2 1 2 0 0 0 0 0 0 nan host 0.25", "ipc_timestamp 'nan' (field 10) is not finite"),
    ("RLASER 1 1 0 0 0 0 0 0 x host 0", "ipc_timestamp 'x'"),
    (
        "ODOM 1 2 3 0 0 0 1.5 host",
        "ODOM has 9 fields, expected 10 (ends where logger_timestamp should be)",
    ),
    ("ODOM 1 2 q 0 0 0 " + STAMPS, "theta 'q' (field 3) is not a number"),
    ("ODOM 1 2 3 0 0 inf " + STAMPS, "accel 'inf' (field 6) is not finite"),
    ("PARAM lonely", "needs a name and a value"),
    ("NEFF", "NEFF has 1 fields"),
    ("NEFF many", "value 'many'"),
    ("ROBOTLASER1 0 -1.5 3.1 0.01 50 0.01 0 2 1 2", "ends where num_remissions should be"),
    ("ROBOTLASER1 0 -1.5 3.1 0.01 50 0.01 0 2 1 2 3 1 2 " + "0 " * 11 + STAMPS, "n_rem=3"),
    ("ROBOTLASER1 0 -1.5 3.1 0.01 50 0.01 0 -1", "num_readings must be >= 0"),
    ("ROBOTLASER1 0 -1.5 3.1 0.01 50 0.01 0 1 1 0 " + "0 " * 10 + "x " + STAMPS, "turn_axis"),
]


@pytest.mark.parametrize(("line", "reason"), BAD_LINES)
def test_bad_lines_name_file_line_and_reason(tmp_path, line, reason):
    path = _write(tmp_path, "# header\n" + line + "\n" + _flaser([1.0]) + "\n")
    with pytest.raises(InputError) as info:
        list(read_carmen(path))
    message = str(info.value)
    kind = line.split()[0]
    assert message.startswith(f"{path}:2: {kind} ")
    assert f"{kind} {kind}" not in message
    assert reason in message


def _read_one(tmp_path: Path, text: str, **options) -> Frame:
    (frame,) = read_frames(_write(tmp_path, text), **options)
    return frame


@pytest.mark.parametrize(
    ("n", "convention", "step_deg", "last_deg"),
    [
        (180, None, 1.0, 89.0),
        (181, None, 1.0, 90.0),
        (360, None, 0.5, 89.5),
        (361, None, 0.5, 90.0),
        (360, "fov_over_n_minus_1", 180 / 359, 90.0),
        (361, "fov_over_n", 0.5, 90.0),  # odd n is unambiguous: the option is for even n
        (8, None, 22.5, 67.5),
    ],
)
def test_flaser_beam_angles(tmp_path, n, convention, step_deg, last_deg):
    frame = _read_one(tmp_path, _flaser([1.0] * n) + "\n", even_beam_convention=convention)
    deg = np.degrees(frame.scan.angles)
    assert deg[0] == pytest.approx(-90.0)
    assert deg[1] - deg[0] == pytest.approx(step_deg)
    assert deg[-1] == pytest.approx(last_deg)


def test_flaser_angles_and_max_range_from_params(tmp_path):
    params = "PARAM laser_front_laser_fov 100\nPARAM laser_front_laser_resolution 1.0\n"
    params += "PARAM robot_front_laser_max 8.0\n"
    frame = _read_one(tmp_path, params + _flaser([1.0] * 100 + [7.99, 8.0]) + "\n")
    deg = np.degrees(frame.scan.angles)
    assert deg[0] == pytest.approx(-50.0) and deg[-1] == pytest.approx(51.0)
    assert frame.scan.max_range_m == 8.0
    assert frame.scan.valid.tolist()[-2:] == [True, False]
    # Keyword arguments win over PARAMs.
    frame = _read_one(
        tmp_path, params + _flaser([1.0] * 4) + "\n", fov_deg=90, even_beam_convention="fov_over_n"
    )
    np.testing.assert_allclose(np.degrees(frame.scan.angles), [-45.0, -22.5, 0.0, 22.5])


def test_validity_rules(tmp_path):
    ranges = [1.0, 0.0, -1.0, math.inf, math.nan, 29.99, 30.0, 32.767, 81.91]
    frame = _read_one(tmp_path, _flaser(ranges) + "\n")
    assert frame.scan.valid.tolist() == [
        True,
        False,
        False,
        False,
        False,
        True,
        False,
        False,
        False,
    ]
    assert frame.scan.max_range_m == 30.0
    frame = _read_one(tmp_path, _flaser(ranges) + "\n", no_return_threshold_m=81.0)
    assert frame.scan.valid.tolist()[-4:] == [True, True, True, False]
    frame = _read_one(tmp_path, _flaser(ranges) + "\n", max_range_m=10.0)
    assert frame.scan.valid.tolist()[-4:] == [False] * 4 and frame.scan.max_range_m == 10.0


def test_odometry_increments_and_indices(tmp_path):
    poses = [Pose(1.0, 2.0, 0.5), Pose(1.5, 2.2, 0.7), Pose(1.4, 2.9, -3.0)]
    lines = []
    for k, p in enumerate(poses):
        lines.append(f"ODOM {p.x} {p.y} {p.theta} 0 0 0 {k}.0 host 0.0")
        lines.append(_flaser([1.0, 2.0], pose=f"{p.x} {p.y} {p.theta}", stamp=f"{k}.5"))
    frames = list(read_frames(_write(tmp_path, "\n".join(lines))))
    assert [f.index for f in frames] == [0, 1, 2]
    assert [f.timestamp for f in frames] == [0.5, 1.5, 2.5]
    assert frames[0].odom_increment == Pose()
    for prev, frame, pose in zip(frames, frames[1:], poses[1:], strict=False):
        assert frame.odom_pose == pose
        composed = prev.odom_pose.compose(frame.odom_increment)
        assert composed.distance_to(pose) < 1e-12
        assert abs(wrap_angle(composed.theta - pose.theta)) < 1e-12


def test_robotlaser1_geometry_and_format_round_trip(tmp_path):
    # laser pose = robot pose ⊕ (0.2, 0, 0): the robot faces +y, so the laser sits 0.2 m north.
    line = (
        "ROBOTLASER1 0 -1.0 2.0 0.5 20.0 0.01 0 5 1.0 2.0 25.0 3.0 0.0 "
        "2 0.5 0.6 "
        f"1.0 2.2 {math.pi / 2} 1.0 2.0 {math.pi / 2} 0.3 0.1 0.5 0.2 0.0 " + STAMPS
    )
    path = _write(tmp_path, line + "\n")
    (record,) = read_carmen(path)
    assert (record.start_angle_rad, record.fov_rad, record.angular_resolution_rad) == (-1, 2, 0.5)
    assert record.max_range_m == 20.0 and record.remissions.tolist() == [0.5, 0.6]
    assert record.tv_mps == 0.3 and record.turn_axis == 0.0
    (frame,) = read_frames(path)
    np.testing.assert_allclose(frame.scan.angles, [-1.0, -0.5, 0.0, 0.5, 1.0])
    assert frame.scan.valid.tolist() == [True, True, False, True, False]
    assert frame.scan.max_range_m == 20.0
    mount = frame.scan.laser_pose
    assert mount.distance_to(Pose(0.2, 0.0, 0.0)) < 1e-12 and abs(mount.theta) < 1e-12
    assert frame.odom_pose == Pose(1.0, 2.0, math.pi / 2)
    again = _write(tmp_path, format_record(record, EXACT) + "\n", "again.clf")
    (copy,) = read_carmen(again)
    assert format_record(copy, EXACT) == format_record(record, EXACT)


def test_writer_rejects_what_flaser_cannot_record(
    tmp_path,
):
    frames = list(read_frames(_write(tmp_path, _flaser([1.0, 2.0, 3.0]) + "\n")))
    scan = frames[0].scan
    skewed = type(scan)(scan.ranges, scan.angles + 0.1, scan.valid, scan.max_range_m)
    bad = type(frames[0])(0, 0.0, skewed, Pose(), Pose())
    with pytest.raises(InputError, match="not a uniform counter-clockwise sweep"):
        write_carmen(tmp_path / "out.clf", [bad])
    other = type(scan)(scan.ranges, scan.angles, scan.valid, 5.0)
    mixed = [frames[0], type(frames[0])(1, 1.0, other, Pose(), Pose())]
    with pytest.raises(InputError, match="frame 1: laser geometry"):
        write_carmen(tmp_path / "out.clf", mixed)
    with pytest.raises(InputError, match=r"params\['bad'\]: cannot write object"):
        write_carmen(tmp_path / "out.clf", frames, params={"bad": object()})
    assert not list(tmp_path.glob("out.clf*")) and not list(tmp_path.glob(".out.clf*"))


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"even_beam_convention": "fov"}, "even_beam_convention must be"),
        ({"fov_deg": 0.0}, r"fov_deg must be a number in \(0, 360\], got 0.0"),
        ({"max_range_m": math.nan}, "max_range_m must be"),
        ({"no_return_threshold_m": -5}, "no_return_threshold_m must be"),
    ],
)
def test_bad_read_options_fail_before_reading(tmp_path, options, message):
    with pytest.raises(InputError, match=message):
        read_frames(tmp_path / "never-opened.clf", **options)


@pytest.mark.parametrize(
    ("param", "message"),
    [
        (
            "robot_front_laser_max -3",
            "PARAM robot_front_laser_max value '-3' is not a number in (0, 1e+06]",
        ),
        ("laser_front_laser_fov 1e308", "PARAM laser_front_laser_fov value '1e308' is not a"),
        ("laser_front_laser_fov wide", "PARAM laser_front_laser_fov value 'wide'"),
        (
            "robot_frontlaser_offset nan",
            "PARAM robot_frontlaser_offset value 'nan' is not a number within ±1e+06",
        ),
    ],
)
def test_bad_geometry_params(tmp_path, param, message):
    path = _write(tmp_path, f"PARAM {param}\n" + _flaser([1.0]) + "\n")
    with pytest.raises(InputError) as info:
        list(read_frames(path))
    assert str(info.value).startswith(f"{path}:1: {message}")
    # Non-geometry PARAMs may hold any text.
    assert len(list(read_frames(_write(tmp_path, "PARAM laser_dev /dev/ttyS0\n", "b.clf")))) == 0
