"""Driving profiles and the turn-then-move tour controller, on a real pymunk space."""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np
import pymunk
import pytest
from hypothesis import given
from hypothesis import strategies as st

from albot2d.errors import InputError
from albot2d.geometry import Pose
from albot2d.sim.driving import (
    PROFILES,
    DrivingProfile,
    Step,
    TourController,
    get_profile,
    merge_straight,
)
from albot2d.sim.robot import KinematicRobot

SIZE = 40.0


def open_space(walls: list[tuple[float, float, float, float]] = ()) -> pymunk.Space:
    space = pymunk.Space()
    corners = [(0, 0), (SIZE, 0), (SIZE, SIZE), (0, SIZE), (0, 0)]
    for a, b in itertools.pairwise(corners):
        space.add(pymunk.Segment(space.static_body, a, b, 0.0))
    for x1, y1, x2, y2 in walls:
        space.add(pymunk.Segment(space.static_body, (x1, y1), (x2, y2), 0.0))
    return space


def drive(
    waypoints: np.ndarray,
    profile: str | DrivingProfile,
    start: Pose,
    space: pymunk.Space | None = None,
) -> tuple[list[Step], KinematicRobot]:
    robot = KinematicRobot(space or open_space(), pose=start)
    controller = TourController(waypoints, profile)
    steps: list[Step] = []
    while (step := controller.next_step(robot.pose)) is not None:
        result = robot.turn(step.amount) if step.kind == "turn" else robot.move(step.amount)
        controller.report(step, result.collided)
        steps.append(step)
        assert len(steps) < 100_000
    return steps, robot


waypoint_lists = st.lists(
    st.tuples(st.floats(1.0, SIZE - 1.0), st.floats(1.0, SIZE - 1.0)), min_size=1, max_size=6
)


@pytest.mark.parametrize("name", ["dataset1", "dataset3", "start_stop", "start_stop_v1"])
@given(points=waypoint_lists, heading=st.floats(-math.pi, math.pi))
def test_steps_respect_profile_limits_and_reach_every_waypoint(
    name: str, points: list, heading: float
) -> None:
    profile = get_profile(name)
    wp = np.array(points)
    start = Pose(float(wp[0, 0]), float(wp[0, 1]), heading)
    steps, robot = drive(wp, profile, start)
    turns = [abs(s.amount) for s in steps if s.kind == "turn"]
    moves = [s.amount for s in steps if s.kind == "move"]
    assert max(turns, default=0.0) <= math.radians(profile.turn_step_deg) * (1 + 1e-9)
    assert all(0.0 < m <= profile.move_step_m * (1 + 1e-9) for m in moves)
    assert robot.pose.distance_to(Pose(*wp[-1])) <= profile.waypoint_tolerance_m
    assert all(s.view for s in steps if s.kind == "move")
    min_view = math.radians(profile.turn_view_min_deg)
    assert all(
        s.view == (profile.view_after_turn and abs(s.amount) >= min_view)
        for s in steps
        if s.kind == "turn"
    )
    # Each (merged) leg is driven in the fewest equal steps: ceil(length / move_step).
    legs = np.hypot(*np.diff(merge_straight(wp, profile.merge_offset_m), axis=0).T)
    legs = legs[legs > profile.waypoint_tolerance_m]
    expected = sum(math.ceil(length / profile.move_step_m - 1e-9) for length in legs)
    assert len(moves) == expected


def test_dataset1_splits_a_right_angle_into_90_one_degree_turns() -> None:
    wp = np.array([[5.0, 5.0], [6.0, 5.0], [6.0, 6.0]])
    steps, robot = drive(wp, "dataset1", Pose(5.0, 5.0, 0.0))
    turns = [s.amount for s in steps if s.kind == "turn"]
    moves = [s.amount for s in steps if s.kind == "move"]
    assert len(turns) == 90 and turns == pytest.approx([math.radians(1.0)] * 90)
    assert len(moves) == 20 and moves == pytest.approx([0.1] * 20)
    assert robot.pose.x == pytest.approx(6.0) and robot.pose.y == pytest.approx(6.0)


def test_start_stop_moves_are_about_three_metres() -> None:
    wp = np.array([[2.0, 2.0], [32.0, 2.0], [32.0, 20.0], [10.0, 20.0]])
    steps, _ = drive(wp, "start_stop", Pose(2.0, 2.0, 0.0))
    moves = np.array([s.amount for s in steps if s.kind == "move"])
    assert moves.max() <= 3.0 + 1e-9
    assert 2.5 <= moves.mean() <= 3.0
    # each 90° corner is two 45° turn instructions, each followed by a view
    turns = [s for s in steps if s.kind == "turn"]
    assert [s.amount for s in turns] == pytest.approx([math.radians(45.0)] * 4)
    assert all(s.view for s in steps)


def test_start_stop_drives_through_collinear_roadmap_legs() -> None:
    # a 12 m straight made of 1.5 m roadmap legs with 1 cm wiggles: four 3 m moves
    xs = np.arange(2.0, 14.01, 1.5)
    ys = 5.0 + 0.01 * (np.arange(len(xs)) % 2)
    wp = np.column_stack([xs, ys])
    steps, robot = drive(wp, "start_stop", Pose(2.0, 5.0, 0.0))
    moves = [s.amount for s in steps if s.kind == "move"]
    assert moves == pytest.approx([3.0] * 4, abs=1e-3)
    assert all(s.view for s in steps if s.kind == "move")
    assert robot.pose.distance_to(Pose(14.0, 5.0)) < 1e-6
    # the earlier reading stops at every roadmap waypoint
    old, _ = drive(wp, "start_stop_v1", Pose(2.0, 5.0, 0.0))
    assert len([s for s in old if s.kind == "move"]) == 8


def test_start_stop_u_turn_is_three_sixty_degree_steps_with_views() -> None:
    wp = np.array([[5.0, 5.0], [8.0, 5.0], [5.0, 5.0]])
    steps, robot = drive(wp, "start_stop", Pose(5.0, 5.0, 0.0))
    turns = [s for s in steps if s.kind == "turn"]
    assert len(turns) == 3
    assert [abs(s.amount) for s in turns] == pytest.approx([math.radians(60.0)] * 3)
    assert all(s.view for s in turns)
    assert robot.pose.distance_to(Pose(5.0, 5.0)) < 1e-6
    # the turn-back apex is never merged away, whatever the tolerance
    assert len(merge_straight(wp, 1.0)) == 3
    v1 = [s for s in drive(wp, "start_stop_v1", Pose(5.0, 5.0, 0.0))[0] if s.kind == "turn"]
    assert len(v1) == 1 and not v1[0].view


def test_small_turns_get_no_view_of_their_own() -> None:
    wp = np.array([[5.0, 5.0], [8.0, 5.0], [11.0, 5.5]])  # a 9.5° bend
    steps, _ = drive(wp, "start_stop", Pose(5.0, 5.0, 0.0))
    turns = [s for s in steps if s.kind == "turn"]
    assert len(turns) == 1 and math.degrees(abs(turns[0].amount)) < 10.0
    assert not turns[0].view


def test_merge_straight_bounds_the_offset() -> None:
    wp = np.array([[0.0, 0.0], [1.0, 0.04], [2.0, 0.0], [3.0, 0.2], [4.0, 0.0]])
    assert merge_straight(wp, 0.0) is wp
    kept = merge_straight(wp, 0.05)
    assert kept.tolist() == [[0.0, 0.0], [2.0, 0.0], [3.0, 0.2], [4.0, 0.0]]
    assert merge_straight(wp, 0.3).tolist() == [[0.0, 0.0], [4.0, 0.0]]


def test_blocked_waypoint_is_given_up_after_max_blocked_steps() -> None:
    space = open_space([(10.0, 0.0, 10.0, SIZE)])  # a wall cutting the room in two
    profile = dataclasses.replace(get_profile("dataset1"), max_blocked_steps=5)
    wp = np.array([[5.0, 5.0], [15.0, 5.0], [5.0, 8.0]])
    _, robot = drive(wp, profile, Pose(5.0, 5.0, 0.0), space)
    assert robot.pose.distance_to(Pose(5.0, 8.0)) < 1e-6
    assert robot.pose.x < 10.0


def test_dataset2_is_dataset1_with_induced_error() -> None:
    d1, d2 = PROFILES["dataset1"], PROFILES["dataset2"]
    assert (d2.move_step_m, d2.turn_step_deg) == (d1.move_step_m, d1.turn_step_deg)
    assert (d2.induced_step_m, d2.induced_step_deg) == (0.10, 1.0)
    assert (d1.induced_step_m, d1.induced_step_deg) == (0.0, 0.0)
    assert PROFILES["dataset3"].move_step_m == 1.0 and PROFILES["dataset3"].turn_step_deg == 10


def test_step_duration_uses_nominal_speeds() -> None:
    profile = DrivingProfile(
        "x", move_step_m=1.0, turn_step_deg=10.0, speed_m_s=0.5, turn_rate_deg_s=45.0
    )
    assert profile.step_duration_s("move", -1.0) == 2.0
    assert profile.step_duration_s("turn", math.radians(90.0)) == pytest.approx(2.0)


def test_unknown_profile_lists_valid_names() -> None:
    with pytest.raises(
        InputError, match="valid: dataset1, dataset2, dataset3, start_stop, start_stop_v1"
    ):
        get_profile("dataset4")
    assert get_profile(PROFILES["dataset3"]) is PROFILES["dataset3"]


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("move_step_m", 0.0),
        ("turn_step_deg", -1.0),
        ("speed_m_s", math.nan),
        ("max_blocked_steps", 0),
        ("view_after_turn", "yes"),
        ("stop_pause_s", -1.0),
        ("induced_along_motion", 1),
        ("turn_view_min_deg", -1.0),
        ("merge_offset_m", math.inf),
    ],
)
def test_profile_validated(field: str, value: object) -> None:
    with pytest.raises(InputError, match=field):
        dataclasses.replace(get_profile("dataset1"), **{field: value})


def test_bad_waypoints() -> None:
    with pytest.raises(InputError, match="waypoints"):
        TourController(np.zeros((3, 3)), "dataset1")
    with pytest.raises(InputError, match="waypoints"):
        TourController([[0.0, math.nan]], "dataset1")
