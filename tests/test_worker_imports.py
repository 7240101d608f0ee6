"""Worker processes import the installed albot2d whatever folder the command starts in.

A folder named ``albot2d`` in the current directory (an empty one, or the checkout one level
down, as in the folder above an editable install's checkout) must not replace the
installed package in the spawned workers of ``fuzz`` and ``experiments``: nothing puts the
current folder on ``sys.path``; plugins found there are imported by file location
(``albot2d.plugins``). The commands run through the ``albot2d`` console script with
albot2d found the way an installed one is (``tests/hostile.py``: ``installed_env``).
"""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from tests.hostile import console_script, installed_env


def _folder_with_an_albot2d_folder(tmp_path: Path) -> Path:
    cwd = tmp_path / "work"
    (cwd / "albot2d").mkdir(parents=True)  # empty: a namespace package if it were on sys.path
    return cwd


def _run(tmp_path: Path, cwd: Path, *args: str, timeout_s: float) -> subprocess.CompletedProcess:
    env = installed_env(tmp_path / "site")
    return subprocess.run(
        [sys.executable, str(console_script()), *args],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        timeout=timeout_s,
    )


SMALL_FUZZ = ["--kinds", "corridors", "--world-size", "12", "14", "--tour-length", "10", "12"]


def test_fuzz_workers_import_the_installed_package(tmp_path: Path) -> None:
    cwd = _folder_with_an_albot2d_folder(tmp_path)
    out = tmp_path / "fuzz"
    proc = _run(
        tmp_path, cwd, "fuzz", "--episodes", "2", "--workers", "2", *SMALL_FUZZ,
        "--no-figures", "--json", "--out", str(out), timeout_s=600,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-3000:]
    summary = json.loads(proc.stdout)
    assert (summary["episodes"], summary["ok"], summary["crashes"]) == (2, 2, 0)
    assert summary["workers"] == 2


def test_a_plugin_in_the_current_folder_reaches_the_workers_by_its_location(
    tmp_path: Path,
) -> None:
    """The plugin is found in the current folder (not on sys.path) and every worker imports
    that same file; the ``albot2d`` folder beside it is ignored."""
    cwd = _folder_with_an_albot2d_folder(tmp_path)
    (cwd / "here_mappers.py").write_text(
        textwrap.dedent("""
        from albot2d.mapping.baselines import NaiveIntegration

        class Here(NaiveIntegration):
            name = "here"
        """)
    )
    out = tmp_path / "fuzz"
    proc = _run(
        tmp_path, cwd, "fuzz", "--episodes", "2", "--workers", "2", *SMALL_FUZZ,
        "--mapper", "here_mappers:Here", "--no-figures", "--json", "--out", str(out),
        timeout_s=600,
    )  # fmt: skip
    assert proc.returncode in (0, 1), proc.stderr[-3000:]  # naive may violate invariants
    summary = json.loads(proc.stdout)
    assert summary["episodes"] == 2 and summary["crashes"] == 0, summary["failing_episodes"]


@pytest.mark.slow
def test_experiments_workers_import_the_installed_package(tmp_path: Path) -> None:
    cwd = _folder_with_an_albot2d_folder(tmp_path)
    out = tmp_path / "exp"
    proc = _run(
        tmp_path, cwd, "experiments", "--quick", "--only", "counts", "--seeds", "0",
        "--workers", "2", "--no-figures", "--out", str(out), timeout_s=900,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-3000:]
    doc = json.loads((out / "experiments.json").read_text())
    assert "counts" in json.dumps(doc)
