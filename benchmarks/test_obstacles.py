"""The long moving-obstacle drive: 200,000 driving steps (dataset1 turns and moves) through
generated worlds with 12 moving obstacles each plus 4 boxes on the tour, the robot's
clearance to walls, clutter, people and boxes checked at every physics sub-step.

Run: ``python -m pytest benchmarks/test_obstacles.py --benchmark-only -s`` (about 7 min
of CPU; with ``--benchmark-disable``, as CI runs it, only the first drive). The goal is 0
overlaps deeper than 1 cm, static or moving; ``extra_info`` holds
the counts and the deepest overlaps (m; negative: the robot never touched). The CI
profile of the same drive is ``tests/test_dynamics_drive.py``.
"""

from __future__ import annotations

from typing import Any

import pytest

from tests.dynamics_drive import DriveStats, drive_with_moving_obstacles

CHUNKS, CHUNK_STEPS = 10, 20_000  # 200,000 steps: ten drives of 20,000 (seeds 0-9)


def _long_drive(chunks: int) -> DriveStats:
    total = DriveStats()
    for seed in range(chunks):
        part = drive_with_moving_obstacles(CHUNK_STEPS, seed=seed)
        for name in (
            "worlds",
            "steps",
            "substeps",
            "frames",
            "collided_frames",
            "moving_obstacles",
            "pushed_boxes",
            "people_walked",
            "static_overlaps",
            "moving_overlaps",
        ):
            setattr(total, name, getattr(total, name) + getattr(part, name))
        total.max_static_overlap_m = max(total.max_static_overlap_m, part.max_static_overlap_m)
        total.max_moving_overlap_m = max(total.max_moving_overlap_m, part.max_moving_overlap_m)
        total.violations += part.violations
    return total


@pytest.mark.benchmark(group="moving-obstacles-drive")
def test_long_drive_among_moving_obstacles(benchmark: Any) -> None:
    # Untimed (--benchmark-disable, as CI runs it) the first of the ten drives checks the
    # same assertions in a tenth of the time; timed, all ten.
    chunks = 1 if benchmark.disabled else CHUNKS
    stats: DriveStats = benchmark.pedantic(_long_drive, args=(chunks,), rounds=1, iterations=1)
    info = {
        "steps": stats.steps,
        "substeps": stats.substeps,
        "worlds": stats.worlds,
        "moving_obstacles": stats.moving_obstacles,
        "pushed_boxes": stats.pushed_boxes,
        "people_walked": stats.people_walked,
        "collided_frames": stats.collided_frames,
        "max_static_overlap_m": stats.max_static_overlap_m,
        "max_moving_overlap_m": stats.max_moving_overlap_m,
        "overlaps_over_1cm": stats.moving_overlaps,
        "static_overlaps": stats.static_overlaps,
    }
    benchmark.extra_info.update(info)
    print(
        "\n"
        + ", ".join(f"{k} {v:.3g}" if isinstance(v, float) else f"{k} {v}" for k, v in info.items())
    )
    assert stats.violations == [] and stats.moving_overlaps == 0 and stats.static_overlaps == 0
