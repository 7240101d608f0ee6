"""Which kernels ran is recorded, and the compiled ones can be switched off from outside:
``ALBOT2D_KERNELS=numpy`` runs every numpy reference path; a bad value is one line, exit 2."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def _run(tmp_path: Path, kernels: str | None, *argv: str) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if k != "ALBOT2D_KERNELS"}
    if kernels is not None:
        env["ALBOT2D_KERNELS"] = kernels
    return subprocess.run(
        [sys.executable, "-m", "albot2d", *argv], cwd=tmp_path, env=env,
        capture_output=True, text=True, timeout=300, check=False,
    )  # fmt: skip


def test_the_report_names_the_kernels_that_ran(tmp_path: Path) -> None:
    pytest.importorskip("numba")
    args = ("run", "--max-frames", "150", "--no-figures", "--mapper", "albot1")
    compiled = _run(tmp_path, None, *args, "--out", "a")
    reference = _run(tmp_path, "numpy", *args, "--out", "b")
    assert compiled.returncode == 0 and reference.returncode == 0, reference.stderr
    a = json.loads((tmp_path / "a" / "report.json").read_text())
    b = json.loads((tmp_path / "b" / "report.json").read_text())
    assert a["kernels"].startswith("numba ") and b["kernels"] == "numpy"
    # the same run either way: the numpy paths are the references the kernels equal
    assert a["mappers"]["albot1"]["counts"] == b["mappers"]["albot1"]["counts"]


def test_a_bad_kernels_value_is_one_line_before_any_work(tmp_path: Path) -> None:
    done = _run(tmp_path, "fortran", "run", "--max-frames", "5", "--out", "c")
    assert done.returncode == 2
    assert done.stderr.strip().splitlines() == [
        "albot2d run: error: ALBOT2D_KERNELS='fortran': expected one of numba, numpy"
    ]
    assert not (tmp_path / "c").exists()
