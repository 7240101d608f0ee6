"""``albot2d run`` end to end: report + figures, --reproduce, plugins, bad input (exit 2)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from albot2d.cli import main

ROOT = Path(__file__).resolve().parents[1]
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
TINY = [
    "--kind",
    "rooms",
    "--width",
    "15",
    "--height",
    "15",
    "--tour-length",
    "20",
    "--profile",
    "dataset3",
    "--stop-every",
    "5",
]


def albot2d(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "albot2d", *args],
        capture_output=True, text=True, cwd=cwd, timeout=120,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
    )  # fmt: skip


@pytest.mark.filterwarnings("error")  # e.g. "No artists with labels found to put in legend"
def test_run_writes_report_and_figures(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "out"
    assert main(["run", *TINY, "--max-frames", "80", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "albot1" in printed and "naive" in printed and "odometry" in printed
    # The title says what ran: part of the tour (--max-frames), not the whole tour.
    assert " m of a loop tour " in printed.splitlines()[0] and "80 views" in printed
    assert max(len(x) for x in printed.splitlines()[1:] if not x.startswith("->")) <= 100
    report = json.loads((out / "report.json").read_text())
    assert report["command"] == "run" and report["run"]["frames"] == 80
    expected = {
        "paths.png",
        "maps.png",
        "homing.png",
        "albot1_map.png",
        "albot1_history.png",
        "albot1_route.png",
        "naive_map.png",
        "truth_map.png",
        "errors.png",
        "steps.png",
    }
    assert set(report["figures"]) == expected
    exports = {"groundtruth.tum", "odometry.tum"} | {
        f"{kind}_{name}.{ext}" for name in ("albot1", "naive", "truth")
        for kind, ext in (("traj", "tum"), ("map", "csv"))
    }  # fmt: skip
    assert set(report["exports"]) == exports
    assert {p.name for p in out.iterdir()} == expected | exports | {"report.json", "steps.csv"}
    umask = os.umask(0o022)
    os.umask(umask)
    for name in [*expected, *exports, "report.json"]:
        data = (out / name).read_bytes()
        assert data.startswith(PNG_MAGIC) or name not in expected
        assert len(data) < 400_000
        # Ordinary file permissions, not the private ones of a temporary file.
        assert (out / name).stat().st_mode & 0o777 == 0o666 & ~umask


def test_reproduce_gives_the_same_report(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    first = tmp_path / "first"
    assert (
        main(
            [
                "run",
                *TINY,
                "--seed",
                "2",
                "--noise",
                "high",
                "--mapper",
                "albot1",
                "--mapper",
                "naive",
                "--no-figures",
                "--out",
                str(first),
            ]
        )
        == 0
    )
    capsys.readouterr()
    again = tmp_path / "again"
    assert (
        main(
            ["run", "--reproduce", str(first / "report.json"), "--no-figures", "--out", str(again)]
        )
        == 0
    )
    assert "reproduce: identical" in capsys.readouterr().out
    a = json.loads((first / "report.json").read_text())
    b = json.loads((again / "report.json").read_text())
    assert a["params"]["spec"] == b["params"]["spec"]
    assert a["params"]["spec"]["noise"] == "high" and list(a["mappers"]) == ["albot1", "naive"]
    assert a["mappers"]["albot1"]["rpe"] == b["mappers"]["albot1"]["rpe"]


def test_a_plugin_mapper_runs_beside_the_builtins(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture
) -> None:
    (tmp_path / "my_mappers.py").write_text(
        textwrap.dedent("""
        from albot2d.mapping.baselines import NaiveIntegration

        class Odometer(NaiveIntegration):
            name = "odometer"
    """)
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    out = tmp_path / "out"
    assert (
        main(
            [
                "run",
                *TINY,
                "--max-frames",
                "40",
                "--mapper",
                "truth",
                "my_mappers:Odometer",
                "--no-figures",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    report = json.loads((out / "report.json").read_text())
    assert list(report["mappers"]) == ["truth", "odometer"]  # the class's name attribute
    mine, odometry = report["mappers"]["odometer"]["rpe"], report["odometry"]["rpe"]
    for key in ("trans_m_mean", "rot_deg_mean", "relations"):
        assert mine[key] == pytest.approx(odometry[key], rel=1e-9)
    assert report["mappers"]["odometer"]["snapshots"] is None  # no route map


def test_the_albot2d_script_imports_plugins_from_the_current_folder(tmp_path: Path) -> None:
    """The console script (unlike python -m) has no cwd on sys.path: main adds it."""
    (tmp_path / "cwd_mappers.py").write_text(
        textwrap.dedent("""
        from albot2d.mapping.baselines import NaiveIntegration

        class LastViewOnly(NaiveIntegration):
            name = "last_view"
    """)
    )
    script = "import sys; from albot2d.cli import main; sys.exit(main(sys.argv[1:]))"
    proc = subprocess.run(
        [sys.executable, "-I", "-c", f"import sys; sys.path.insert(0, {str(ROOT)!r}); {script}",
         "run", *TINY, "--max-frames", "20", "--mapper", "cwd_mappers:LastViewOnly",
         "--no-figures", "--json", "--out", "out"],
        capture_output=True, text=True, cwd=tmp_path, timeout=120,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert list(json.loads(proc.stdout)["mappers"]) == ["last_view"]


def test_unknown_mapper_in_a_subprocess_is_one_line_exit_2(tmp_path: Path) -> None:
    out = tmp_path / "never"
    proc = albot2d("run", *TINY, "--mapper", "albot1", "bogus", "--out", str(out), cwd=tmp_path)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "unknown mapper 'bogus'" in lines[0], proc.stderr
    assert "Traceback" not in proc.stderr and not out.exists()


@pytest.mark.parametrize(
    ("args", "message"),
    [
        ([*TINY, "--profile", "dataset9"], "unknown driving profile"),
        ([*TINY, "--noise", "awful"], "unknown odometry noise preset"),
        ([*TINY, "--tour-length", "-3"], "--tour-length"),
        ([*TINY, "--tour-kind", "spiral"], "unknown tour kind"),
        ([*TINY, "--stop-every", "0"], "--stop-every"),
        ([*TINY, "--param", "no_such_param=1"], "no_such_param"),
        ([*TINY, "--max-frames", "x"], "--max-frames"),
        (["--kind", "caves"], "caves"),
        (["--world", "missing.json"], "missing.json"),
        (["--reproduce", "missing-report.json"], "missing-report.json"),
    ],
)
def test_bad_input_is_one_line_and_no_output(
    tmp_path: Path, capsys: pytest.CaptureFixture, args: list, message: str
) -> None:
    out = tmp_path / "out"
    assert main(["run", *args, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err
    assert not out.exists()


def test_reproduce_refuses_other_settings_and_non_reports(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    fake = tmp_path / "report.json"
    fake.write_text(json.dumps({"format": "something-else"}))
    assert main(["run", "--reproduce", str(fake), "--out", str(tmp_path / "o")]) == 2
    assert "not an albot2d report" in capsys.readouterr().err
    assert main(["run", "--reproduce", str(fake), "--seed", "1", "--out", str(tmp_path / "o")]) == 2
    assert "drop --seed" in capsys.readouterr().err


def test_unusable_output_dirs(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    blocker = tmp_path / "file.txt"
    blocker.write_text("not a directory")
    assert main(["run", *TINY, "--out", str(blocker)]) == 2
    assert "not a directory" in capsys.readouterr().err
    assert main(["run", *TINY, "--out", str(blocker / "sub")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(blocker) in err[0]
    assert main(["run", *TINY]) == 2
    assert "--out" in capsys.readouterr().err


def test_run_profiles_every_view(tmp_path: Path) -> None:
    """steps.csv has a row per view, report.json per-view p50/p95/max, --cprofile a pstats."""
    import pstats

    from albot2d.viz.steps import read_steps_csv

    out, prof = tmp_path / "out", tmp_path / "run.prof"
    assert main(["run", *TINY, "--max-frames", "40", "--no-figures", "--cprofile", str(prof),
                 "--out", str(out)]) == 0  # fmt: skip
    steps = read_steps_csv(str(out / "steps.csv"))
    assert list(steps["view"]) == list(range(40))
    for column in ("simulation_ms", "extraction_ms", "albot1.tracking_ms", "albot1.total_ms",
                   "albot1.tracked", "albot1.remembered", "albot1.map_surfaces",
                   "naive.total_ms", "truth.global_map_ms"):  # fmt: skip
        assert column in steps, column
    assert steps["albot1.remembered"][0] == 1 and steps["albot1.map_surfaces"][-1] > 0
    # A mapper's total includes the shared extraction it was given.
    assert (steps["albot1.total_ms"] >= steps["extraction_ms"]).all()
    timing = json.loads((out / "report.json").read_text())["timing_ms"]
    stats = timing["albot1.total"]
    assert 0.0 < stats["p50"] <= stats["p95"] <= stats["max"]
    assert abs(stats["mean"] - steps["albot1.total_ms"].mean()) < 1e-3
    functions = {f for _, _, f in pstats.Stats(str(prof)).stats}
    assert "run_experiment" in functions and "extract_surfaces" in functions


def test_cprofile_into_a_missing_directory_is_rejected(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    assert (
        main(
            [
                "run",
                *TINY,
                "--max-frames",
                "5",
                "--no-figures",
                "--cprofile",
                str(tmp_path / "nowhere" / "x.prof"),
                "--out",
                str(tmp_path / "o"),
            ]
        )
        == 2
    )
    assert "--cprofile" in capsys.readouterr().err and not (tmp_path / "o").exists()
