"""SIGTERM (``kill``, a scheduler, ``docker stop``) is handled like Ctrl-C.

A campaign sent SIGTERM stops handing out episodes, lets the running ones finish and be
written down, releases its lock and shuts its pool down (no "leaked semaphore" warning),
exits 130 and resumes to the uninterrupted result; ``albot2d run`` sent SIGTERM leaves no
output behind. Real processes, as in ``tests/test_campaign_processes.py`` (helpers shared in
``tests/fuzz_processes.py``).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from albot2d.evaluation.fuzz.campaign import EPISODES_NAME
from albot2d.evaluation.fuzz.lock import LOCK_NAME
from tests.fuzz_processes import (  # noqa: F401  (the fixture is used by name)
    ROOT,
    _no_campaign_left_running,
    assert_whole_lines,
    output,
    start_fuzz,
    wait_for,
    wait_for_first_episode,
)


def test_sigterm_stops_a_campaign_cleanly_and_it_resumes(tmp_path: Path) -> None:
    out = tmp_path / "fuzz"
    proc = start_fuzz(out, episodes=8)
    path = out / EPISODES_NAME
    wait_for_first_episode(proc, out, 120)
    proc.send_signal(signal.SIGTERM)
    _, stderr = output(proc, 120)
    assert proc.returncode == 130, stderr
    assert "finishing the running episodes" in stderr, stderr
    assert "Traceback" not in stderr and "leaked semaphore" not in stderr, stderr
    assert not (out / LOCK_NAME).exists()
    records = assert_whole_lines(path)
    assert 1 <= len(records) <= 8
    again = start_fuzz(out, "--resume", episodes=8)
    _, stderr = output(again, 300)
    assert again.returncode in (0, 1), stderr
    assert sorted(r["episode"] for r in assert_whole_lines(path)) == list(range(8))


def test_sigterm_during_a_run_leaves_no_output(tmp_path: Path) -> None:
    out = tmp_path / "run"
    proc = subprocess.Popen(
        [sys.executable, "-m", "albot2d", "run", "--kind", "office", "--out", str(out)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
    )
    try:
        wait_for(lambda: out.exists() or proc.poll() is not None, 120, "the run to start")
        time.sleep(1.0)
        if proc.poll() is not None:
            pytest.skip("the run finished before it could be interrupted")
        proc.send_signal(signal.SIGTERM)
        _, stderr = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 130, stderr
    assert stderr.strip().splitlines() == ["albot2d run: interrupted"], stderr
    assert not out.exists()
