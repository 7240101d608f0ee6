"""The robot never overlaps a moving obstacle: drives through generated worlds with many people
and boxes (some put on the tour itself), the clearance checked at every physics sub-step.

This is the CI profile (a few seconds); the long one, 200,000 driving steps over many
worlds, is ``benchmarks/test_obstacles.py`` (same harness, ``tests/dynamics_drive.py``).
"""

from __future__ import annotations

import pytest

from tests.dynamics_drive import drive_with_moving_obstacles


@pytest.mark.parametrize(("kind", "seed"), [("corridors", 7), ("rooms", 11)])
def test_short_drive_among_people_and_boxes_never_overlaps_them(kind: str, seed: int) -> None:
    stats = drive_with_moving_obstacles(
        800, seed=seed, obstacles=10, size_m=14.0, profile="dataset1", tour_m=3.0, kinds=(kind,)
    )
    assert stats.steps == 800 and stats.substeps > 800
    assert stats.violations == []
    assert stats.static_overlaps == 0 and stats.moving_overlaps == 0
    assert stats.max_moving_overlap_m <= 0.01
    assert stats.pushed_boxes > 0 and stats.people_walked > 0  # the drive met both kinds
