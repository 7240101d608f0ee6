"""Region labelling (isovists) and moves per update by region kind (Fig. 14)."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from albot2d.errors import InputError
from albot2d.evaluation.metrics.updates import (
    albot1_update_flags,
    update_counts,
    updates_by_region,
)
from albot2d.geometry import Pose
from albot2d.mapping.albot1.mapper import StepRecord
from worldgen import make_world
from worldgen.regions import RegionParams, isovist_ranges, region_kind_at


def t_shaped_world():
    """A 2 m wide, 20 m long corridor opening into a 14 x 14 m hall, and a 3 x 3 m room
    off the corridor through a 1 m door."""
    corridor = shapely.box(0.0, 0.0, 20.0, 2.0)
    hall = shapely.box(20.0, -6.0, 34.0, 8.0)
    room = shapely.box(5.0, 2.2, 8.0, 5.2)
    door = shapely.box(6.0, 1.9, 7.0, 2.3)
    free = shapely.union_all([corridor, hall, room, door])
    return make_world(free, start=Pose(2.0, 1.0, 0.0))


def test_isovist_ranges_in_a_box():
    walls = np.array([[0, 0, 4, 0], [4, 0, 4, 2], [4, 2, 0, 2], [0, 2, 0, 0]], float)
    r = isovist_ranges(walls, [1.0, 1.0], 4, 30.0)
    assert r == pytest.approx([3.0, 1.0, 1.0, 1.0])
    assert isovist_ranges(np.zeros((0, 4)), [0, 0], 4, 30.0) == pytest.approx([30.0] * 4)


def test_corridor_room_hall_and_outside_are_told_apart():
    world = t_shaped_world()
    pts = [[10.0, 1.0], [27.0, 1.0], [6.5, 4.0], [-5.0, -5.0]]
    assert region_kind_at(world, pts).tolist() == ["corridor", "hall", "room", "outside"]
    # a single point works too, and the thresholds are options
    assert region_kind_at(world, [10.0, 1.0]).tolist() == ["corridor"]
    narrow = RegionParams(corridor_max_width_m=1.5)
    assert region_kind_at(world, [10.0, 1.0], narrow).tolist() != ["corridor"]


def test_region_params_validated():
    with pytest.raises(InputError, match="rays"):
        RegionParams(rays=7)
    with pytest.raises(InputError, match="hall_min_area_m2"):
        RegionParams(hall_min_area_m2=0.0)


def test_update_counts_by_region_known_answer():
    # 9 frames: moves of 3 m along x, then two turn-only frames in the hall
    xy = np.array(
        [[0, 0], [3, 0], [6, 0], [9, 0], [12, 0], [12, 0], [12, 0], [15, 0], [18, 0]], float
    )
    updated = np.array([1, 0, 1, 1, 0, 0, 1, 0, 1], bool)
    regions = np.array(["corridor"] * 4 + ["hall"] * 5)
    instructions, moves = update_counts(xy, updated, regions)
    # the first view is not an update; rows 2, 3 in the corridor; 6, 8 in the hall
    assert instructions == {"corridor": [2, 1], "hall": [3, 2]}
    assert moves == {"corridor": [2, 1], "hall": [1, 2]}
    summary = updates_by_region(xy, updated, regions)
    assert summary["corridor"]["updates"] == 2
    assert summary["corridor"]["instructions_per_update"]["mean"] == 1.5
    assert summary["hall"]["instructions_per_update"]["share_at_least_2"] == 1.0
    assert summary["all"]["updates"] == 4
    with pytest.raises(InputError, match="one of each per frame"):
        updates_by_region(xy, updated[:-1], regions)


def test_albot1_update_flags_follow_the_step_records():
    steps = [
        StepRecord(10, 0, False, (10,), ("start",)),
        StepRecord(11, 5, False, (), ()),
        StepRecord(12, 2, False, (11, 12), ("triangulation", "triangulation")),
    ]
    flags = albot1_update_flags(steps, [10, 11, 12, 13])
    assert flags.tolist() == [True, False, True, False]


def test_isovist_ranges_many_equal_one_point_at_a_time():
    """The angle-pruned batch gives isovist_ranges' numbers bit for bit: on a generated
    office, at random points, at wall endpoints and midpoints (the point on the segment's
    line), and against a degenerate (point) wall."""
    from worldgen.generate import generate
    from worldgen.regions import isovist_ranges_many

    world = generate("office", seed=0, width_m=30, height_m=24)
    rng = np.random.default_rng(4)
    walls = np.vstack([world.walls, [[5.0, 5.0, 5.0, 5.0]]])
    ends = walls[rng.integers(0, len(walls), 40)]
    pts = np.vstack([
        rng.uniform(-2.0, 32.0, (300, 2)), ends[:, :2], (ends[:, :2] + ends[:, 2:]) / 2.0,
        [[5.0, 5.0], [5.0, 4.0]],
    ])  # fmt: skip
    for rays in (72, 8):
        many = isovist_ranges_many(walls, pts, rays, 30.0)
        one = np.array([isovist_ranges(walls, p, rays, 30.0) for p in pts])
        np.testing.assert_array_equal(many, one)
    assert isovist_ranges_many(np.zeros((0, 4)), pts[:3], 4, 30.0).tolist() == [[30.0] * 4] * 3
