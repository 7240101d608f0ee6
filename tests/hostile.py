"""Running albot2d the way an attacker's input meets it: a real process, a memory limit, a
time limit, hostile files generated at test time (small on disk, huge when read).

- :func:`limited_run` runs a command under ``RLIMIT_AS`` (address space, default 3 GiB)
  with a timeout (default 60 s): an input that made albot2d materialise gigabytes ends in
  a ``MemoryError`` traceback or a kill here instead of taking the machine down;
- :func:`assert_refused`: exit 2, one stderr line ``albot2d CMD: error: …``, no traceback;
- :func:`gzip_bomb` writes a gzip file of ``copies`` identical members, each ``chunk``
  compressed once: a 1 GiB expansion costs about a megabyte on disk and milliseconds;
- :func:`installed_env` makes ``albot2d`` importable the way an editable install does
  (a finder consulted after ``sys.path``), so a folder named ``albot2d`` in the current
  directory would win if anything put the current directory on ``sys.path``.
"""

from __future__ import annotations

import gzip
import os
import resource
import subprocess
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import pytest

__all__ = [
    "GIB",
    "MIB",
    "ROOT",
    "assert_refused",
    "console_script",
    "gzip_bomb",
    "installed_env",
    "limited_run",
    "run_cli",
    "simulate_world_args",
]

ROOT = Path(__file__).resolve().parents[1]
MIB = 1024 * 1024
GIB = 1024 * MIB


def _env(extra: dict[str, str] | None = None) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in ("MPLBACKEND", "ALBOT2D_PLUGINS")}
    env["PYTHONPATH"] = str(ROOT)
    env.update(extra or {})
    return env


def limited_run(
    argv: Sequence[str],
    *,
    cwd: Path,
    address_space: int = 3 * GIB,
    timeout_s: float = 60.0,
    env: dict[str, str] | None = None,
) -> subprocess.CompletedProcess[str]:
    """``argv`` in a child process limited to ``address_space`` bytes and ``timeout_s``."""

    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (address_space, address_space))

    return subprocess.run(
        list(argv),
        cwd=cwd,
        env=env if env is not None else _env(),
        capture_output=True,
        text=True,
        timeout=timeout_s,
        preexec_fn=limit,
    )


def run_cli(
    *args: str,
    cwd: Path,
    env: dict[str, str] | None = None,
    address_space: int = 3 * GIB,
    timeout_s: float = 60.0,
) -> subprocess.CompletedProcess[str]:
    """``python -m albot2d ARGS`` under the limits (``env``: extra variables)."""
    return limited_run(
        [sys.executable, "-m", "albot2d", *args],
        cwd=cwd,
        env=_env(env),
        address_space=address_space,
        timeout_s=timeout_s,
    )


def assert_refused(proc: subprocess.CompletedProcess[str], command: str, *expected: str) -> str:
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2, (proc.returncode, proc.stderr[-3000:])
    assert len(lines) == 1, proc.stderr[-3000:]
    assert "Traceback" not in proc.stderr
    assert lines[0].startswith(f"albot2d {command}: error: "), lines[0]
    for text in expected:
        assert text in lines[0], lines[0]
    return lines[0]


def gzip_bomb(path: Path, chunk: bytes, copies: int) -> Path:
    """A gzip file expanding to ``chunk * copies`` (``copies`` members of one compressed
    ``chunk``; readers of gzip read every member)."""
    member = gzip.compress(chunk, compresslevel=9, mtime=0)
    with open(path, "wb") as out:
        for _ in range(copies):
            out.write(member)
    return path


_SITECUSTOMIZE = '''
"""Test harness: albot2d and worldgen found after sys.path, as an editable install does."""
import sys
from importlib.machinery import PathFinder


class _Installed:
    @classmethod
    def find_spec(cls, name, path=None, target=None):
        if name in ("albot2d", "worldgen"):
            return PathFinder.find_spec(name, [{root!r}])
        return None


sys.meta_path.insert(sys.meta_path.index(PathFinder) + 1, _Installed)
'''


def installed_env(folder: Path) -> dict[str, str]:
    """An environment where this checkout's albot2d is found the way an installed one is:
    by a finder after ``sys.path`` (a ``sitecustomize`` in ``folder``), not on it."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "sitecustomize.py").write_text(_SITECUSTOMIZE.format(root=str(ROOT)))
    env = {k: v for k, v in os.environ.items() if k not in ("MPLBACKEND", "ALBOT2D_PLUGINS")}
    env["PYTHONPATH"] = str(folder)
    return env


def console_script() -> Path:
    """The ``albot2d`` script of this environment (skips the test where there is none)."""
    script = Path(sys.executable).parent / "albot2d"
    if not script.is_file():
        pytest.skip(f"no albot2d console script beside {sys.executable} (pip install -e .)")
    return script


# A bad-input case builds its inputs in a folder and returns the command line (with OUT
# for the output) and extra environment variables.
Case = Callable[[Path], tuple[list[str], dict[str, str]]]


def replay_args(log: Path, *extra: str) -> list[str]:
    """``albot2d replay LOG ... --out OUT`` without figures."""
    return ["replay", str(log), "--no-figures", *extra, "--out", "OUT"]


def write_log(tmp: Path) -> Path:
    """A small valid CARMEN log with its relations file in ``tmp``."""
    from tests import bad_inputs as bi

    path = tmp / "log.clf"
    path.write_text(bi.carmen_text())
    (tmp / "log.relations").write_text(bi.relations_text())
    return path


def simulate_world_args(tmp: Path, mutate: Callable[[dict[str, Any]], None]) -> list[str]:
    """``albot2d simulate --world W --out OUT`` on the small valid world document changed
    by ``mutate`` (in place), written to ``tmp``."""
    from tests import bad_inputs as bi

    doc = bi.world_doc()
    mutate(doc)
    path = tmp / "w.json"
    path.write_text(bi.world_text(doc))
    return ["simulate", "--world", str(path), "--out", "OUT"]
