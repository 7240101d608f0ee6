"""Fuzz campaigns as real processes, shared by the tests that start, signal and resume them
(``tests/test_campaign_processes.py``, ``tests/test_sigterm.py``).

``start_fuzz`` starts ``albot2d fuzz`` on tiny corridor worlds (two pool workers), its
output to files; a module that starts campaigns imports the autouse fixture
``_no_campaign_left_running`` too, so that a failing test leaves none running.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from albot2d.evaluation.fuzz.campaign import EPISODES_NAME

__all__ = [
    "EPISODES",
    "MARKER",
    "ROOT",
    "TINY_ARGS",
    "_no_campaign_left_running",
    "assert_whole_lines",
    "output",
    "start_fuzz",
    "wait_for",
    "wait_for_first_episode",
]

ROOT = Path(__file__).resolve().parents[1]
EPISODES = 6
TINY_ARGS = [
    "--kinds",
    "corridors",
    "--world-size",
    "12",
    "14",
    "--tour-length",
    "8",
    "12",
    "--profile",
    "dataset3",
]


# Set in the environment of every campaign started here, and so of all its processes:
# how the test finds them all, even those started after it last looked.
MARKER = "ALBOT2D_CAMPAIGN_TEST"


def start_fuzz(
    out: Path,
    *extra: str,
    episodes: int = EPISODES,
    seed: int = 21,
) -> subprocess.Popen[str]:
    """``albot2d fuzz`` in the background, its output to files (not pipes: orphaned workers
    would hold a pipe open, and reading it would wait for them)."""
    logs = out.parent / "logs"
    logs.mkdir(exist_ok=True)
    n = len(list(logs.iterdir())) // 2
    with open(logs / f"{n}.out", "w") as stdout, open(logs / f"{n}.err", "w") as stderr:
        proc = subprocess.Popen(
            [sys.executable, "-m", "albot2d", "fuzz", "--episodes", str(episodes), "--seed",
             str(seed), "--workers", "2", *TINY_ARGS, "--no-figures", "--out", str(out),
             *extra],
            stdout=stdout, stderr=stderr, text=True,
            env={**os.environ, "PYTHONPATH": str(ROOT), MARKER: str(out)},
        )  # fmt: skip
    proc.logs = (logs / f"{n}.out", logs / f"{n}.err")  # type: ignore[attr-defined]
    _STARTED.append(proc)
    return proc


_STARTED: list[subprocess.Popen[str]] = []


@pytest.fixture(autouse=True)
def _no_campaign_left_running() -> Iterator[None]:
    """A test that fails half-way must not leave its campaign running (nor a Popen whose
    ResourceWarning would then fail whichever test happens to collect it)."""
    yield
    while _STARTED:
        proc = _STARTED.pop()
        if proc.poll() is None:
            proc.kill()
        proc.wait(timeout=30)


def output(proc: subprocess.Popen[str], timeout_s: float) -> tuple[str, str]:
    """Wait for ``proc``; its stdout and stderr."""
    proc.wait(timeout=timeout_s)
    out, err = proc.logs  # type: ignore[attr-defined]
    return out.read_text(), err.read_text()


def wait_for(predicate: Callable[[], object], timeout_s: float, what: str) -> None:
    """Poll ``predicate`` every 50 ms until it holds; fail after ``timeout_s``."""
    deadline = time.monotonic() + timeout_s
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout_s} s waiting for {what}")
        time.sleep(0.05)


def wait_for_first_episode(proc: subprocess.Popen[str], out: Path, timeout_s: float) -> None:
    """Until the campaign in ``out`` has written an episode (or ended)."""
    path = out / EPISODES_NAME
    wait_for(
        lambda: (path.exists() and path.stat().st_size > 0) or proc.poll() is not None,
        timeout_s,
        "a first episode",
    )


def assert_whole_lines(path: Path) -> list[dict]:
    """The JSON lines of ``path``, which must not end in a cut-off line."""
    data = path.read_bytes()
    assert data == b"" or data.endswith(b"\n"), f"a cut-off line in {path}: {data[-80:]!r}"
    return [json.loads(line) for line in data.splitlines()]
