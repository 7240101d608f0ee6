"""Speed of log I/O: reading the real MIT CARMEN log, and writing a simulated-size log.

Run: ``python -m pytest benchmarks/test_logs.py --benchmark-only``.
"""

from __future__ import annotations

from collections import deque
from pathlib import Path

import numpy as np
import pytest

from albot2d.frames import Frame, Scan, beam_angles
from albot2d.geometry import Pose
from albot2d.logs import CarmenReader, read_frames, write_carmen

MIT_LOG = (
    Path(__file__).resolve().parents[1].parent / "shared" / "data" / "raw" / "mit-csail.clf.gz"
)

needs_mit = pytest.mark.skipif(not MIT_LOG.is_file(), reason=f"shared data not found: {MIT_LOG}")


@needs_mit
def test_read_mit_records_speed(benchmark) -> None:
    reader = CarmenReader(MIT_LOG)
    benchmark(deque, reader, 0)
    assert reader.stats.counts == {"FLASER": 1988}


@needs_mit
def test_read_mit_frames_speed(benchmark) -> None:
    frames = benchmark(lambda: list(read_frames(MIT_LOG)))
    assert len(frames) == 1988


def test_write_log_speed(benchmark, tmp_path) -> None:
    rng = np.random.default_rng(1)
    angles = beam_angles(361)
    frames = [
        Frame(k, 0.2 * k, Scan(rng.uniform(0.1, 30.0, 361), angles, rng.random(361) < 0.9, 30.0),
              Pose(0.1 * k, 0.0, 0.0), Pose(0.1, 0.0, 0.0))
        for k in range(2000)
    ]  # fmt: skip
    written = benchmark(write_carmen, tmp_path / "log.clf", frames)
    assert written == 2000
