"""``albot2d fuzz`` end to end: files, printed summary, exit codes, --resume, bad input."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from albot2d.cli import main

ROOT = Path(__file__).resolve().parents[1]
SMALL = [
    "--kinds",
    "rooms",
    "corridors",
    "--world-size",
    "12",
    "15",
    "--tour-length",
    "12",
    "15",
    "--seed",
    "7",
]


def albot2d(
    *args: str,
    extra_path: Path | None = None,
    code: str | None = None,
) -> subprocess.CompletedProcess[str]:
    paths = [str(ROOT)] + ([str(extra_path)] if extra_path else [])
    command = ["-c", code, *args] if code else ["-m", "albot2d", *args]
    return subprocess.run(
        [sys.executable, *command], capture_output=True, text=True, timeout=120,
        env={**os.environ, "PYTHONPATH": os.pathsep.join(paths)}, check=False,
    )  # fmt: skip


@pytest.mark.slow  # a whole (small) campaign with its figures
def test_fuzz_writes_the_stream_summary_and_histograms(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    out = tmp_path / "out"
    assert main(["fuzz", "--episodes", "3", "--workers", "1", *SMALL, "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "3 episodes: 3 ok, 0 with violations, 0 crashes" in printed
    assert "episodes/min" in printed and "mean heading error" in printed
    lines = (out / "episodes.jsonl").read_text().splitlines()
    assert sorted(json.loads(line)["episode"] for line in lines) == [0, 1, 2]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["ok"] == 3 and summary["params"]["seed"] == 7
    assert summary["params"]["kinds"] == ["rooms", "corridors"]
    assert (out / "histograms.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not (out / "reproducers").exists()

    # --resume with more episodes runs only the new ones.
    resume_to_5 = ("fuzz", "--episodes", "5", "--workers", "1", *SMALL, "--resume", "--no-figures")
    assert main([*resume_to_5, "--out", str(out)]) == 0
    assert "ran 2 here" in capsys.readouterr().out
    lines = (out / "episodes.jsonl").read_text().splitlines()
    assert sorted(json.loads(line)["episode"] for line in lines) == [0, 1, 2, 3, 4]

    # --json prints summary.json itself instead of the table.
    assert (
        main(
            [
                *resume_to_5,
                "--json",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    printed = json.loads(capsys.readouterr().out)
    assert printed == json.loads((out / "summary.json").read_text())


def test_failures_exit_1_with_reproducers(tmp_path: Path) -> None:
    (tmp_path / "bad_plugin.py").write_text(
        "from albot2d.mapping.baselines import NaiveIntegration\n\n\n"
        "class Explodes(NaiveIntegration):\n"
        "    def observe(self, frame):\n"
        "        raise ValueError('boom')\n"
    )
    out = tmp_path / "out"
    done = albot2d(
        "fuzz",
        "--episodes",
        "2",
        "--workers",
        "1",
        *SMALL,
        "--no-figures",
        "--mapper",
        "bad_plugin:Explodes",
        "--out",
        str(out),
        extra_path=tmp_path,
    )
    assert done.returncode == 1, done.stderr
    assert "0 ok, 0 with violations, 2 crashes" in done.stdout
    assert "crash ValueError 2" in done.stdout
    assert sorted(p.name for p in (out / "reproducers").iterdir()) == [
        "episode-0.json",
        "episode-1.json",
    ]


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--kinds", "caves"], "unknown world kind 'caves'"),
        (["--mapper", "nope"], "unknown mapper 'nope'"),
        (["--profile", "sprint"], "unknown driving profile 'sprint'"),
        (["--noise", "loud"], "unknown odometry noise preset 'loud'"),
        (["--episodes", "0"], "--episodes must be a positive integer"),
        (["--workers", "-1"], "--workers must be a positive integer"),
        (["--world-size", "30", "20"], "--world-size: MIN 30 is larger than MAX 20"),
        (["--backend", "slurm"], "unknown backend 'slurm'"),
        (["--address", "tcp://127.0.0.1:1"], "--address is for --backend dask"),
        (["--resume"], "--resume: "),
    ],
)
def test_bad_input_is_one_line_and_exit_2(
    args: list[str], message: str, tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    out = tmp_path / "out"
    argv = ["fuzz", "--episodes", "2", *args, "--out", str(out)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1 and err.startswith("albot2d fuzz: error:")
    assert not out.exists()


def test_an_unwritable_out_dir_is_one_line_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    assert main(["fuzz", "--episodes", "2", "--out", str(blocker / "out")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err


def test_an_unreachable_dask_scheduler_is_one_line_and_exit_2(tmp_path: Path) -> None:
    pytest.importorskip("dask.distributed")
    out = tmp_path / "out"
    done = albot2d(
        "fuzz",
        "--episodes",
        "2",
        "--backend",
        "dask",
        "--address",
        "tcp://127.0.0.1:1",
        "--out",
        str(out),
    )
    assert done.returncode == 2
    assert done.stderr.count("\n") == 1 and "no dask scheduler reachable" in done.stderr
    assert not out.exists()


def test_the_dask_backend_without_dask_is_one_line_and_exit_2(tmp_path: Path) -> None:
    # sys.modules[name] = None makes `import name` fail: dask "not installed" here.
    code = (
        "import sys; sys.modules['dask'] = sys.modules['dask.distributed'] = None; "
        "from albot2d.cli import main; sys.exit(main(sys.argv[1:]))"
    )
    done = albot2d(
        "fuzz", "--episodes", "2", "--backend", "dask", "--out", str(tmp_path / "out"), code=code
    )
    assert done.returncode == 2
    assert done.stderr.count("\n") == 1
    assert "--backend dask needs dask.distributed: pip install 'albot2d[dask]'" in done.stderr
