"""``albot2d replay`` on a log written by ``write_run`` and on the shared MIT CSAIL log."""

from __future__ import annotations

import gzip
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from albot2d.cli import main
from albot2d.evaluation import run_experiment
from albot2d.evaluation.run.replay import find_relations, log_stem
from albot2d.geometry import Pose
from albot2d.logs import read_frames, read_relations, read_run, write_run
from albot2d.seeding import RUN_STREAMS, stream_seed
from albot2d.sim.odometry import noise_preset
from albot2d.sim.simulator import Simulator
from tests.runs import small_run
from worldgen import plan_tour
from worldgen.generate import generate

ROOT = Path(__file__).resolve().parents[1]
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A short simulated run (rooms world, dataset3, typical odometry noise) on disk."""
    world = generate("rooms", seed=5, width_m=15.0, height_m=15.0)
    sim = Simulator(
        world, seed=stream_seed(5, RUN_STREAMS, "simulator"), odometry=noise_preset("typical")
    )
    out = tmp_path_factory.mktemp("run")
    tour = plan_tour(world, "loop", 20.0, at_least=True)  # a long loop: homing stops on it
    write_run(out, sim.drive(tour, "dataset3"), params={"seed": 5})
    return out


def _odometry_rpe_by_hand(frames: list, relations: object) -> tuple[float, int]:
    """Mean translational error of raw odometry over the relations both of whose
    timestamps are among ``frames`` (matched to 1 ms)."""
    stamps = np.array([f.timestamp for f in frames])
    errors = []
    for t1, t2, motion in zip(relations.t1, relations.t2, relations.motion, strict=True):
        i, j = np.argmin(abs(stamps - t1)), np.argmin(abs(stamps - t2))
        if abs(stamps[i] - t1) > 1e-3 or abs(stamps[j] - t2) > 1e-3:
            continue
        est = frames[i].odom_pose.inverse() @ frames[j].odom_pose
        err = Pose.from_array(motion).inverse() @ est
        errors.append(math.hypot(err.x, err.y))
    return float(np.mean(errors)), len(errors)


def test_replay_a_simulated_log(
    run_dir: Path, tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    out = tmp_path / "replay"
    assert main(["replay", str(run_dir / "log.clf"), "--stop-every", "5", "--out", str(out)]) == 0
    assert "albot1" in capsys.readouterr().out
    report = json.loads((out / "report.json").read_text())
    run = read_run(run_dir)
    assert report["command"] == "replay" and report["seed"] is None and report["world"] is None
    assert report["run"]["relations_path"] == str(run_dir / "log.relations")  # found beside
    assert report["run"]["frames"] == len(run.frames)
    assert list(report["mappers"]) == ["albot1", "naive"]
    trans, n = _odometry_rpe_by_hand(list(run.frames), run.relations)
    rpe = report["odometry"]["rpe"]
    assert rpe["relations"] == n == len(run.relations) == report["run"]["relations_used"]
    assert rpe["trans_m_mean"] == pytest.approx(trans, rel=1e-9)
    albot1 = report["mappers"]["albot1"]
    assert albot1["counts"]["views"] == len(run.frames)
    assert albot1["rpe"]["relations"] == n and albot1["rpe"]["short"]["relations"] > 0
    # Without the truth: no map quality, homing estimates only.
    assert all(albot1["map"][k] is None for k in ("accuracy_m_mean", "completeness"))
    assert albot1["homing"] and all(
        h["bearing_true_deg"] is None and h["bearing_est_deg"] is not None for h in albot1["homing"]
    )
    assert albot1["end_pose_error"] is None
    for name in report["figures"]:
        assert (out / name).read_bytes().startswith(PNG_MAGIC)
    assert {"paths.png", "maps.png", "albot1_map.png", "albot1_route.png"} <= set(report["figures"])


def test_replay_agrees_with_the_run_that_made_the_log(run_dir: Path, tmp_path: Path) -> None:
    spec = small_run(5, tour_length_is_minimum=True, mappers=("naive",))  # the fixture's run
    live = run_experiment(spec).report
    out = tmp_path / "replay"
    assert (
        main(
            [
                "replay",
                str(run_dir / "log.clf"),
                "--mapper",
                "naive",
                "--no-figures",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    replayed = json.loads((out / "report.json").read_text())
    a, b = live["odometry"]["rpe"], replayed["odometry"]["rpe"]
    assert a["relations"] == b["relations"]
    # The log stores poses rounded to its precision; nothing else differs.
    assert b["trans_m_mean"] == pytest.approx(a["trans_m_mean"], abs=1e-4)
    assert b["rot_deg_mean"] == pytest.approx(a["rot_deg_mean"], abs=1e-2)


def test_max_frames_and_an_explicit_relations_file(run_dir: Path, tmp_path: Path) -> None:
    rel = tmp_path / "elsewhere.relations"
    rel.write_bytes((run_dir / "log.relations").read_bytes())
    out = tmp_path / "o"
    assert (
        main(
            [
                "replay",
                str(run_dir / "log.clf"),
                "--relations",
                str(rel),
                "--max-frames",
                "25",
                "--no-figures",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    report = json.loads((out / "report.json").read_text())
    assert report["run"]["frames"] == 25 and report["params"]["max_frames"] == 25
    frames = list(read_frames(run_dir / "log.clf"))[:25]
    trans, n = _odometry_rpe_by_hand(frames, read_relations(rel))
    assert report["odometry"]["rpe"]["relations"] == n < report["run"]["relations"]
    assert report["odometry"]["rpe"]["trans_m_mean"] == pytest.approx(trans, rel=1e-9)


def test_no_relations_means_null_rpe(
    run_dir: Path, tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    log = tmp_path / "alone.clf.gz"
    with gzip.open(log, "wb") as handle:
        handle.write((run_dir / "log.clf").read_bytes())
    assert find_relations(log) is None and log_stem(log) == "alone"
    out = tmp_path / "o"
    assert main(["replay", str(log), "--max-frames", "10", "--no-figures", "--out", str(out)]) == 0
    assert "no relations file" in capsys.readouterr().err
    report = json.loads((out / "report.json").read_text())
    assert report["odometry"]["rpe"] is None and report["mappers"]["albot1"]["rpe"] is None


def test_malformed_log_line_in_a_subprocess(run_dir: Path, tmp_path: Path) -> None:
    lines = (run_dir / "log.clf").read_text().splitlines()
    k = next(i for i, line in enumerate(lines) if line.startswith("FLASER"))
    lines[k + 40] = "FLASER 181 1.0 2.0 oops"
    bad = tmp_path / "bad.clf"
    bad.write_text("\n".join(lines) + "\n")
    out = tmp_path / "never"
    proc = subprocess.run(
        [sys.executable, "-m", "albot2d", "replay", str(bad), "--out", str(out)],
        capture_output=True, text=True, cwd=tmp_path, timeout=120,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
    )  # fmt: skip
    assert proc.returncode == 2
    err = proc.stderr.strip().splitlines()
    assert len(err) == 1 and f"{bad}:{k + 41}" in err[0], proc.stderr
    assert "Traceback" not in proc.stderr and not out.exists()


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["missing.clf"], "no such log file"),
        (["LOG", "--mapper", "truth"], "needs the true pose"),
        (["LOG", "--mapper", "nope"], "unknown mapper"),
        (["LOG", "--relations", "missing.relations"], "missing.relations"),
        (["LOG", "--relations", "LOG"], "relation has"),
        (["LOG", "--max-frames", "0"], "--max-frames"),
    ],
)
def test_bad_input_is_one_line_and_no_output(
    run_dir: Path, tmp_path: Path, capsys: pytest.CaptureFixture, args: list, message: str
) -> None:
    args = [str(run_dir / "log.clf") if a == "LOG" else a for a in args]
    out = tmp_path / "out"
    assert main(["replay", *args, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err
    assert not out.exists()


def test_mit_csail_first_frames(shared_data: Path, tmp_path: Path) -> None:
    log = shared_data / "raw" / "mit-csail.clf.gz"
    out = tmp_path / "mit"
    assert main(["replay", str(log), "--max-frames", "200", "--out", str(out)]) == 0
    report = json.loads((out / "report.json").read_text())
    assert report["run"]["relations_path"].endswith("mit-csail.relations")
    assert report["run"]["frames"] == 200 and report["run"]["relations"] == 1172
    frames = []
    for frame in read_frames(log):
        frames.append(frame)
        if len(frames) == 200:
            break
    trans, n = _odometry_rpe_by_hand(frames, read_relations(report["run"]["relations_path"]))
    rpe = report["odometry"]["rpe"]
    assert 40 < rpe["relations"] == n < 1172
    assert rpe["trans_m_mean"] == pytest.approx(trans, rel=1e-9)
    albot1 = report["mappers"]["albot1"]
    assert albot1["counts"]["views"] == 200 and albot1["rpe"]["relations"] == n
    assert 0 < albot1["counts"]["local_maps"] <= 200
    assert (out / "albot1_history.png").read_bytes().startswith(PNG_MAGIC)


def test_a_log_is_found_in_the_data_folder(
    run_dir: Path,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """ALBOT2D_DATA (or --data) is the data folder: LOG is looked up in it and in raw/,
    and the relations in its relations/ folder (the shared data's layout)."""
    data = tmp_path / "data"
    (data / "raw").mkdir(parents=True)
    (data / "relations").mkdir()
    (data / "raw" / "mine.clf").write_bytes((run_dir / "log.clf").read_bytes())
    (data / "relations" / "mine.relations").write_bytes((run_dir / "log.relations").read_bytes())
    monkeypatch.chdir(tmp_path)
    assert main(["replay", "mine.clf", "--out", "a", "--no-figures"]) == 2
    assert "set ALBOT2D_DATA or --data" in capsys.readouterr().err
    monkeypatch.setenv("ALBOT2D_DATA", str(data))
    assert (
        main(["replay", "mine.clf", "--max-frames", "40", "--no-figures", "--json", "--out", "b"])
        == 0
    )
    report = json.loads(capsys.readouterr().out)
    assert report["params"]["log"].endswith("raw/mine.clf")
    assert report["run"]["relations"] > 0
    monkeypatch.delenv("ALBOT2D_DATA")
    assert (
        main(
            [
                "replay",
                "raw/mine.clf",
                "--data",
                str(data),
                "--max-frames",
                "40",
                "--no-figures",
                "--out",
                "c",
            ]
        )
        == 0
    )
