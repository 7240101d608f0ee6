"""Bad CARMEN logs and relations files.

Part of the bad-input corpus: every case starts from a valid input (``tests/bad_inputs.py``)
and breaks one thing; the real CLI must exit 2 with one stderr line naming the place and the
value, no traceback and no output (``tests/bad_input_checks.py``).
"""

from __future__ import annotations

import gzip
import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from albot2d.cli import main
from tests import bad_inputs as bi
from tests.bad_input_checks import (
    frame_line,
    nothing_written,
    refused,
    replace_text,
    write_log,
)

ROOT = Path(__file__).resolve().parents[1]

# ------------------------------------------------------------------ CARMEN logs


def _append(line: str) -> Callable[[list[str]], None]:
    return lambda lines: lines.append(line)


def _ranges(index: int, value: str) -> list[str]:
    beams = ["2.0"] * bi.N_BEAMS
    beams[index] = value
    return beams


_ROBOTLASER = (
    "ROBOTLASER1 0 {start} {fov} 0.0174533 30.0 0.01 0 181 "
    + " ".join(["2.0"] * 181)
    + " 0 0 0 0 0 0 0 0 0 0 0 0 100.0 albot2d 100.0"
)


def _coarse_laser(lines: list[str]) -> None:
    """19 beams 20° apart: readable, but too coarse for the mappers' surface extraction."""
    lines[:] = [
        "PARAM laser_front_laser_fov 360.0",
        "PARAM laser_front_laser_resolution 20.0",
        *(bi.flaser_line(k, ranges=["2.0"] * 19) for k in range(10)),
    ]


# (id, mutation of the valid log's lines, texts the error line must hold; ``:N`` = line)
LOG_CASES: list[tuple[str, Callable[[list[str]], None], tuple[str, ...]]] = [
    ("pose-x-1e308", frame_line(3, x="1e308"), (":7:", "x '1e308'", "limit")),
    ("pose-x-inf", frame_line(3, x="inf"), (":7:", "x 'inf'", "not finite")),
    ("pose-x-text", frame_line(3, x="east"), (":7:", "x 'east'", "not a number")),
    ("timestamp-1e300", frame_line(5, stamp="1e300"), (":9:", "ipc_timestamp '1e300'", "limit")),
    ("timestamp-nan", frame_line(5, stamp="nan"), (":9:", "ipc_timestamp 'nan'")),
    ("range-text", frame_line(0, ranges=_ranges(7, "far")), (":4:", "range 7 'far'")),
    (
        "beam-count-huge",
        replace_text("FLASER 181", "FLASER 999999999999"),
        (":4:", "999999999999", "65536"),
    ),
    ("beam-count-negative", replace_text("FLASER 181", "FLASER -1"), (":4:", "n must be >= 0")),
    (
        "beam-count-mismatch",
        replace_text("FLASER 181", "FLASER 180"),
        (":4:", "n=180", "expected 191"),
    ),
    (
        "line-cut-short",
        lambda lines: lines.__setitem__(5, lines[5][:40]),
        (":6:", "FLASER", "fields"),
    ),
    (
        "param-fov-1e308",
        replace_text("laser_front_laser_fov 180.0", "laser_front_laser_fov 1e308"),
        (":1:", "PARAM laser_front_laser_fov value '1e308'", "(0, 360]"),
    ),
    (
        "param-fov-zero",
        replace_text("laser_front_laser_fov 180.0", "laser_front_laser_fov 0"),
        (":1:", "laser_front_laser_fov value '0'"),
    ),
    (
        "param-resolution-negative",
        replace_text("laser_front_laser_resolution 1.0", "laser_front_laser_resolution -1"),
        (":2:", "laser_front_laser_resolution value '-1'"),
    ),
    (
        "param-max-range-nan",
        replace_text("robot_front_laser_max 30.0", "robot_front_laser_max nan"),
        (":3:", "robot_front_laser_max value 'nan'"),
    ),
    (
        "param-max-range-1e9",
        replace_text("robot_front_laser_max 30.0", "robot_front_laser_max 1e9"),
        (":3:", "robot_front_laser_max value '1e9'", "1e+06"),
    ),
    (
        "param-angular-offset-100",
        _append("PARAM robot_frontlaser_angular_offset 100"),
        (":44:", "robot_frontlaser_angular_offset value '100'"),
    ),
    (
        "param-offset-1e308",
        _append("PARAM robot_frontlaser_offset 1e308"),
        (":44:", "robot_frontlaser_offset value '1e308'"),
    ),
    ("param-no-value", _append("PARAM robot_frontlaser_offset"), (":44:", "PARAM", "value")),
    (
        "robotlaser-start-1e308",
        _append(_ROBOTLASER.format(start="1e308", fov="3.14159")),
        (":44:", "start_angle '1e308'"),
    ),
    (
        "robotlaser-fov-100",
        _append(_ROBOTLASER.format(start="-1.5708", fov="100")),
        (":44:", "fov '100'"),
    ),
    ("odom-1e308", _append("ODOM 1e308 0 0 0 0 0 100.0 albot2d 100.0"), (":44:", "ODOM", "x")),
    ("odom-short", _append("ODOM 1 2 3"), (":44:", "ODOM has 4 fields")),
    ("neff-text", _append("NEFF many"), (":44:", "NEFF", "'many'")),
    ("coarse-laser", _coarse_laser, ("beams are 20 deg apart", "less than 10 deg")),
    ("no-laser-lines", lambda lines: lines.__setitem__(slice(3, None), []), ("no laser scans",)),
]


def _refuse_log(capsys: Any, path: Path, tmp_path: Path, *expected: str, strict: bool = False):
    out = tmp_path / "out"
    argv = ["replay", str(path), "--no-figures", "--out", str(out)]
    refused(capsys, [*argv, "--strict"] if strict else argv, str(path), *expected)
    nothing_written(out)


def test_the_valid_log_replays_strictly(tmp_path: Path, capsys: Any) -> None:
    path = write_log(tmp_path, bi.carmen_lines())
    assert (
        main(["replay", str(path), "--no-figures", "--strict", "--out", str(tmp_path / "o")]) == 0
    )
    report = json.loads((tmp_path / "o" / "report.json").read_text())
    assert report["log"]["anomalies"]["frames_kept"] == 40
    assert report["run"]["relations_used"] == 39
    assert "warning" not in capsys.readouterr().err


@pytest.mark.parametrize(
    ("mutate", "expected"), [c[1:] for c in LOG_CASES], ids=[c[0] for c in LOG_CASES]
)
def test_bad_log(mutate, expected, tmp_path, capsys) -> None:
    lines = bi.carmen_lines()
    mutate(lines)
    _refuse_log(capsys, write_log(tmp_path, lines), tmp_path, *expected)


def test_truncated_gzip_log(tmp_path: Path, capsys: Any) -> None:
    data = gzip.compress(bi.carmen_text().encode())
    path = tmp_path / "log.clf.gz"
    path.write_bytes(data[: len(data) // 2])
    _refuse_log(capsys, path, tmp_path, "corrupt or truncated gzip")


# Anomalies a real log may hold: accepted with a warning, refused with --strict.
ANOMALY_CASES = [
    ("nan-range", frame_line(2, ranges=_ranges(10, "nan")), "1 non-finite range"),
    ("inf-range", frame_line(2, ranges=_ranges(10, "inf")), "1 non-finite range"),
    ("negative-range", frame_line(2, ranges=_ranges(10, "-0.5")), "1 negative range"),
    ("duplicate-timestamp", frame_line(2, stamp="0.5"), "1 duplicate timestamp"),
    ("shuffled", lambda lines: lines.insert(10, lines.pop(20)), "1 out-of-order timestamp"),
    (
        "reversed",
        lambda lines: lines.__setitem__(slice(3, None), lines[3:][::-1]),
        "39 out-of-order timestamps",
    ),
]


@pytest.mark.parametrize(
    ("mutate", "summary"), [c[1:] for c in ANOMALY_CASES], ids=[c[0] for c in ANOMALY_CASES]
)
def test_log_anomaly_is_refused_with_strict(mutate, summary, tmp_path, capsys) -> None:
    lines = bi.carmen_lines()
    mutate(lines)
    _refuse_log(capsys, write_log(tmp_path, lines), tmp_path, summary, "strict", strict=True)


# ------------------------------------------------------------------ relations files

RELATION_CASES = [
    ("t1-nan", "nan 0.5 0.1 0 0 0 0 0", ("relation field t1 'nan'", "not a finite number")),
    ("x-1e308", "0 0.5 1e308 0 0 0 0 0", ("relation field x '1e308'", "limit")),
    ("t2-1e300", "0 1e300 0.1 0 0 0 0 0", ("relation field t2 '1e300'", "limit")),
    ("yaw-1e7", "0 0.5 0.1 0 0 0 0 1e7", ("relation field yaw '1e7'", "limit")),
    ("seven-fields", "0 0.5 0.1 0 0 0 0", ("relation has 7 fields", "expected 8")),
    ("text-field", "0 0.5 north 0 0 0 0 0", ("relation field x 'north'",)),
    ("nine-fields", "0 0.5 0.1 0 0 0 0 0 0", ("relation has 9 fields",)),
]


@pytest.mark.parametrize(
    ("row", "expected"), [c[1:] for c in RELATION_CASES], ids=[c[0] for c in RELATION_CASES]
)
def test_bad_relations(row, expected, tmp_path, capsys) -> None:
    log = write_log(tmp_path, bi.carmen_lines())
    relations = tmp_path / "bad.relations"
    relations.write_text(bi.relations_text(["0 0.5 0.1 0 0 0 0 0", row]))
    out = tmp_path / "out"
    argv = ["replay", str(log), "--relations", str(relations), "--no-figures", "--out", str(out)]
    refused(capsys, argv, f"{relations}:2:", *expected)
    nothing_written(out)


def test_missing_relations_file(tmp_path: Path, capsys: Any) -> None:
    log = write_log(tmp_path, bi.carmen_lines())
    out = tmp_path / "out"
    missing = tmp_path / "none.relations"
    argv = ["replay", str(log), "--relations", str(missing), "--out", str(out)]
    refused(capsys, argv, str(missing), "No such file")
    nothing_written(out)
