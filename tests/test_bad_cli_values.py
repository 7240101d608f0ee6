"""Bad command-line values, and a few cases through the installed CLI in a subprocess.

Part of the bad-input corpus: every case starts from a valid input (``tests/bad_inputs.py``)
and breaks one thing; the real CLI must exit 2 with one stderr line naming the place and the
value, no traceback and no output (``tests/bad_input_checks.py``).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from tests import bad_inputs as bi
from tests.bad_input_checks import (
    frame_line,
    nothing_written,
    obstacle,
    refused,
    replace_text,
    set_field,
    write_log,
)

ROOT = Path(__file__).resolve().parents[1]

# ------------------------------------------------------------------ command-line values

# (id, argv after the command with OUT for the output, texts the error line must hold)
CLI_CASES = [
    ("world-seed-negative", ["world", "--kind", "rooms", "--seed", "-1"], ("--seed", "'-1'")),
    ("world-seed-float", ["world", "--kind", "rooms", "--seed", "1e3"], ("--seed", "'1e3'")),
    ("world-width-nan", ["world", "--kind", "rooms", "--width", "nan"], ("--width", "'nan'")),
    (
        "world-width-1e5",
        ["world", "--kind", "rooms", "--width", "1e5"],
        ("width_m", "500", "100000.0"),
    ),
    ("world-height-negative", ["world", "--kind", "rooms", "--height", "-3"], ("--height", "-3")),
    (
        "world-100000-obstacles",
        ["world", "--kind", "rooms", "--param", "dynamic_obstacles=100000"],
        ("dynamic_obstacles", "200", "100000"),
    ),
    (
        "world-param-inf",
        ["world", "--kind", "rooms", "--param", "width_m=1e400"],
        ("width_m", "finite", "inf"),
    ),
    (
        "world-param-radius",
        ["world", "--kind", "rooms", "--param", "robot_radius_m=1e300"],
        ("robot_radius_m", "1e+300"),
    ),
    (
        "world-param-clutter",
        ["world", "--kind", "open", "--param", "clutter_per_10m2=1e6"],
        ("clutter_per_10m2", "1000000.0"),
    ),
    (
        "world-param-door",
        ["world", "--kind", "rooms", "--param", "door_width_max_m=1e9"],
        ("door_width_max_m", "1000000000.0", "500"),
    ),
    ("world-param-unknown", ["world", "--kind", "rooms", "--param", "colour=1"], ("colour",)),
    ("world-param-no-value", ["world", "--kind", "rooms", "--param", "x"], ("--param", "'x'")),
    (
        "world-tour-1e300",
        ["world", "--kind", "rooms", "--tour-length", "1e300"],
        ("length_m", "1e+300"),
    ),
    (
        "world-min-tour-1e300",
        ["world", "--kind", "rooms", "--min-tour-length", "1e300"],
        ("min_length_m", "1e+300"),
    ),
    (
        "run-both-tour-lengths",
        ["run", "--tour-length", "50", "--min-tour-length", "50"],
        ("--tour-length or --min-tour-length",),
    ),
    ("world-kind-unknown", ["world", "--kind", "castle"], ("'castle'",)),
    ("run-max-frames-0", ["run", "--kind", "rooms", "--max-frames", "0"], ("--max-frames", "'0'")),
    (
        "run-last-k-huge",
        ["run", "--kind", "rooms", "--last-k-views", "1" + "0" * 20],
        ("last_k_views", "1" + "0" * 20),
    ),
    (
        "run-snapshots-huge",
        ["run", "--kind", "rooms", "--snapshots", "1000000000"],
        ("snapshots", "1000000000"),
    ),
    (
        "run-stop-every-nan",
        ["run", "--kind", "rooms", "--stop-every", "nan"],
        ("--stop-every", "'nan'"),
    ),
    (
        "run-min-start-inf",
        ["run", "--kind", "rooms", "--min-start-distance", "inf"],
        ("--min-start-distance", "'inf'"),
    ),
    ("run-width-1e5", ["run", "--kind", "rooms", "--width", "1e5"], ("width_m", "100000.0")),
    ("run-mapper-unknown", ["run", "--kind", "rooms", "--mapper", "oracle"], ("'oracle'",)),
    ("run-profile-unknown", ["run", "--kind", "rooms", "--profile", "fast"], ("'fast'",)),
    ("fuzz-episodes-0", ["fuzz", "--episodes", "0"], ("--episodes", "'0'")),
    ("fuzz-workers-0", ["fuzz", "--episodes", "2", "--workers", "0"], ("--workers", "'0'")),
    (
        "fuzz-world-size-inverted",
        ["fuzz", "--episodes", "2", "--world-size", "30", "10"],
        ("--world-size", "30", "10"),
    ),
    (
        "fuzz-address-not-a-port",
        ["fuzz", "--episodes", "2", "--backend", "dask", "--address", "tcp://127.0.0.1:notaport"],
        ("--address", "notaport"),
    ),
    (
        "fuzz-tour-length-huge",
        ["fuzz", "--episodes", "2", "--tour-length", "1e300", "2e300"],
        ("tour_length_max_m", "2e+300"),
    ),
    (
        "fuzz-world-size-over-cap",
        ["fuzz", "--episodes", "2", "--world-size", "10", "1e5"],
        ("world_size_max_m", "100000.0"),
    ),
    (
        "fuzz-workers-huge",
        ["fuzz", "--episodes", "2", "--workers", "100000"],
        ("--workers", "100000"),
    ),
    (
        "fuzz-address-port-range",
        ["fuzz", "--episodes", "2", "--backend", "dask", "--address", "tcp://127.0.0.1:99999"],
        ("--address", "99999"),
    ),
]


@pytest.mark.parametrize(
    ("argv", "expected"), [c[1:] for c in CLI_CASES], ids=[c[0] for c in CLI_CASES]
)
def test_bad_command_line_value(argv, expected, tmp_path, capsys) -> None:
    out = tmp_path / ("w.json" if argv[0] == "world" else "out")
    refused(capsys, [*argv, "--out", str(out)], *expected)
    nothing_written(out)


def test_replay_command_line_values(tmp_path: Path, capsys: Any) -> None:
    log = write_log(tmp_path, bi.carmen_lines())
    out = tmp_path / "out"
    for option, value in (("--max-frames", "1e3"), ("--stop-every", "-1"), ("--mapper", "truth")):
        refused(capsys, ["replay", str(log), option, value, "--out", str(out)], value)
        nothing_written(out)


# ------------------------------------------------------------------ the installed CLI

SUBPROCESS_CASES = [
    ("world", lambda d: set_field("walls.0.0", 1e308)(d), ("walls[0]", "limit")),
    ("world", obstacle(speed_m_s=1e12), ("speed_m_s", "1000000000000.0")),
    ("log", frame_line(3, x="1e308"), (":7:", "x '1e308'")),
    (
        "log",
        replace_text("laser_front_laser_fov 180.0", "laser_front_laser_fov 1e308"),
        (":1:", "laser_front_laser_fov value '1e308'"),
    ),
]


@pytest.mark.parametrize(("what", "mutate", "expected"), SUBPROCESS_CASES)
def test_installed_cli_refuses_in_one_line(what, mutate, expected, tmp_path) -> None:
    out = tmp_path / "out"
    if what == "world":
        doc = bi.world_doc()
        mutate(doc)
        path = tmp_path / "w.json"
        path.write_text(bi.world_text(doc))
        argv = ["simulate", "--world", str(path), "--out", str(out)]
    else:
        lines = bi.carmen_lines()
        mutate(lines)
        path = write_log(tmp_path, lines)
        argv = ["replay", str(path), "--out", str(out)]
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.run(
        [sys.executable, "-m", "albot2d", *argv],
        capture_output=True,
        text=True,
        cwd=ROOT,
        env=env,
        timeout=120,
    )
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and len(lines) == 1, proc.stderr
    assert "Traceback" not in proc.stderr and str(path) in lines[0]
    assert all(text in lines[0] for text in expected), lines[0]
    nothing_written(out)
