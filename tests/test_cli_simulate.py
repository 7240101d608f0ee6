"""``albot2d simulate`` end to end in a subprocess: files, log read-back, bad input."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from albot2d.cli import main
from albot2d.logs import read_frames, read_run

ROOT = Path(__file__).resolve().parents[1]
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def simulate(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "albot2d", "simulate", *args],
        capture_output=True, text=True, cwd=cwd, timeout=120,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
    )  # fmt: skip


# A short, low-noise dataset 3 run through a rooms world (seed 4).
ROOMS_RUN = ("--kind", "rooms", "--seed", "4", "--profile", "dataset3", "--tour-length", "15",
             "--noise", "low")  # fmt: skip


def test_simulate_writes_a_run_that_reads_back(tmp_path: Path) -> None:
    out = tmp_path / "run"
    proc = simulate(
        *ROOMS_RUN,
        "--out",
        str(out),
        cwd=tmp_path,
    )
    assert proc.returncode == 0, proc.stderr
    assert "dataset3" in proc.stdout and str(out) in proc.stdout
    names = {p.name for p in out.iterdir()}
    assert names == {"log.clf", "truth.txt", "log.relations", "run.json", "paths.png"}
    assert (out / "paths.png").read_bytes().startswith(PNG_MAGIC)
    run = read_run(out)
    assert len(run.frames) == run.manifest["counts"]["frames"] > 10
    assert run.params["profile"] == "dataset3" and run.params["seed"] == 4
    logged = list(read_frames(out / "log.clf"))
    assert len(logged) == len(run.frames)
    # The log carries the odometry, the truth file the true poses: with noise they differ.
    odom = np.array([f.odom_pose.as_array() for f in logged])
    truth = np.array([f.true_pose.as_array() for f in run.frames])
    assert np.allclose(odom[0, :2], truth[0, :2], atol=1e-3)
    assert not np.allclose(odom[-1, :2], truth[-1, :2], atol=1e-3)
    assert np.all(np.diff([f.timestamp for f in logged]) > 0)
    # Same arguments again: identical files (deterministic runs).
    again = tmp_path / "again"
    proc = simulate(
        *ROOMS_RUN,
        "--no-png",
        "--out",
        str(again),
        cwd=tmp_path,
    )
    assert proc.returncode == 0, proc.stderr
    for name in ("log.clf", "truth.txt", "log.relations"):
        assert (out / name).read_bytes() == (again / name).read_bytes()


def test_simulate_from_a_world_file(tmp_path: Path) -> None:
    world = tmp_path / "w.json"
    made = subprocess.run(
        [sys.executable, "-m", "albot2d", "world", "--kind", "corridors", "--seed", "2",
         "--out", str(world)],
        capture_output=True, text=True, cwd=tmp_path, env={**os.environ, "PYTHONPATH": str(ROOT)},
    )  # fmt: skip
    assert made.returncode == 0, made.stderr
    out = tmp_path / "run"
    proc = simulate(
        "--world",
        str(world),
        "--profile",
        "start_stop",
        "--tour-length",
        "20",
        "--no-png",
        "--laser-noise",
        "zero",
        "--out",
        str(out),
        cwd=tmp_path,
    )
    assert proc.returncode == 0, proc.stderr
    assert not (out / "paths.png").exists()
    manifest = json.loads((out / "run.json").read_text())
    assert manifest["params"]["world_source"] == str(world)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--kind", "bogus"], "unknown world kind 'bogus'"),
        (["--kind", "rooms", "--profile", "fast"], "valid: dataset1, dataset2, dataset3"),
        (["--kind", "rooms", "--noise", "loud"], "valid: none, low, typical, high"),
        (["--kind", "rooms", "--laser-noise", "x"], "valid: sick_lms200, zero"),
        (["--kind", "rooms", "--seed", "-1"], "--seed must be a non-negative integer"),
        (["--kind", "rooms", "--tour-length", "0"], "--tour-length must be a positive"),
        (["--kind", "rooms", "--tour-kind", "spiral"], "unknown tour kind 'spiral'"),
        (["--world", "missing.json"], "missing.json"),
        (["--world", "w.json", "--kind", "rooms"], "not both"),
        (["--kind", "rooms", "--max-frames", "0"], "--max-frames must be a positive integer"),
    ],
)
def test_bad_input_is_one_line_exit_2_and_writes_nothing(
    tmp_path: Path,
    args: list[str],
    message: str,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "run"
    assert main(["simulate", *args, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err, err
    assert not out.exists()


def test_bad_input_in_a_subprocess_has_no_traceback(tmp_path: Path) -> None:
    out = tmp_path / "run"
    proc = simulate("--kind", "rooms", "--profile", "fast", "--out", str(out), cwd=tmp_path)
    assert proc.returncode == 2
    assert proc.stderr.count("\n") == 1 and "Traceback" not in proc.stderr
    assert not out.exists()


def test_out_is_required_and_must_be_a_directory(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["simulate", "--kind", "rooms"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "the following arguments are required: --out" in err
    afile = tmp_path / "file"
    afile.write_text("x")
    assert main(["simulate", "--kind", "rooms", "--out", str(afile)]) == 2
    assert "not a directory" in capsys.readouterr().err
    assert afile.read_text() == "x"


def test_render_paths_png_handles_drift_and_empty_paths() -> None:
    from albot2d.viz.paths import render_paths_png
    from tests.test_simulator import room_world

    world = room_world()
    true_xy = np.array([[1.0, 1.0], [5.0, 1.0]])
    odom_xy = np.array([[1.0, 1.0], [20.0, -9.0]])  # far outside the world
    png = render_paths_png(
        world, true_xy=true_xy, odom_xy=odom_xy, collided=[False, True], title="t"
    )
    assert png.startswith(PNG_MAGIC)
    assert render_paths_png(world, true_xy=np.zeros((0, 3)), odom_xy=[]).startswith(PNG_MAGIC)


def test_simulate_logs_exactly_the_frames_run_maps(tmp_path: Path) -> None:
    """Same options, same defaults (office world, typical noise): the same frames."""
    from albot2d.cli import build_parser
    from albot2d.cli.common import spec_from_args
    from albot2d.evaluation import run_experiment

    options = ["--seed", "3", "--tour-length", "20", "--max-frames", "60"]
    out = tmp_path / "sim"
    assert main(["simulate", *options, "--no-png", "--out", str(out)]) == 0
    run = read_run(out)
    assert run.params["odometry_preset"] == "typical"
    assert run.params["world_source"] == "generate('office', seed=3)"
    logged = list(read_frames(out / "log.clf"))
    spec = spec_from_args(build_parser().parse_args(["run", *options, "--out", "x"]))
    result = run_experiment(spec)
    trace = result.trace
    assert len(logged) == trace.n_frames == 60
    odom = np.array([f.odom_pose.as_array() for f in logged])
    truth = np.array([f.true_pose.as_array() for f in run.frames])
    # The log stores poses with 6 decimals; the odometry is noisy (typical), not the truth.
    assert np.allclose(odom, trace.odom_poses, atol=2e-6)
    assert np.allclose(truth, trace.true_poses, atol=2e-6)
    assert not np.allclose(odom, truth, atol=1e-3)
    assert np.allclose([f.timestamp for f in logged], trace.timestamps, atol=1e-6)
