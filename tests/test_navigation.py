"""Grid navigation shared by the controllers (``albot2d.control.navigation``) and the goal
seeker (GoTo-v0's baseline): hand-worked steering decisions and the costmap recovery."""

from __future__ import annotations

import math

import numpy as np
import pytest

from albot2d.control import GoalSeeker, GoalSeekerParams, GridSpec
from albot2d.control.navigation import steer
from albot2d.geometry import Pose

PACE = {
    "speed_mps": 0.5, "turn_rate_radps": 1.0, "corner_tolerance_m": 0.15,
    "goal_tolerance_m": 0.3, "turn_in_place_rad": 0.3, "heading_gain": 2.0,
}  # fmt: skip


def test_steer_drives_at_a_corner_ahead_and_drops_corners_reached() -> None:
    path = np.array([[0.1, 0.0], [3.0, 0.3]])  # the first corner lies within tolerance
    step = steer(path, Pose(0.0, 0.0, 0.0), **PACE)
    assert len(step.path) == 1 and not step.arrived
    bearing = math.atan2(0.3, 3.0)
    v, w = step.command
    assert w == pytest.approx(2.0 * bearing)
    # The last corner is 3 m away: no slow-down; the speed is cut by cos(heading error).
    assert v == pytest.approx(0.5 * math.cos(bearing))


def test_steer_turns_on_the_spot_when_far_off_heading_and_caps_the_turn_rate() -> None:
    step = steer(np.array([[0.0, 2.0]]), Pose(0.0, 0.0, 0.0), **PACE)
    assert step.command == (0.0, 1.0)  # 2 * 90° would be 3.14 rad/s; capped at 1


def test_steer_slows_into_the_goal_and_stops_on_arrival() -> None:
    v, w = steer(np.array([[0.35, 0.0]]), Pose(0.0, 0.0, 0.0), **PACE).command
    assert (v, w) == (pytest.approx(0.35), 0.0)
    step = steer(np.array([[0.25, 0.0]]), Pose(0.0, 0.0, 0.0), **PACE)
    assert step.arrived and step.command == (0.0, 0.0)


def test_goal_seeker_turns_to_the_goal_heading_at_the_goal() -> None:
    spec = GridSpec.covering(-5.0, -5.0, 5.0, 5.0, 0.1)
    seeker = GoalSeeker(spec, 0.25)
    v, w = seeker.command(Pose(1.0, 1.0, 0.0), Pose(1.05, 1.0, 1.0), 0.0)
    assert v == 0.0 and w == pytest.approx(1.0) and not seeker.arrived
    assert seeker.command(Pose(1.0, 1.0, 0.95), Pose(1.05, 1.0, 1.0), 0.1) == (0.0, 0.0)
    assert seeker.arrived


def test_goal_seeker_clears_a_grid_that_walls_it_in_once_then_gives_up() -> None:
    spec = GridSpec.covering(-5.0, -5.0, 5.0, 5.0, 0.1)
    seeker = GoalSeeker(spec, 0.25, GoalSeekerParams())
    # A ring of wall (as drift can smear one) between the robot and its goal.
    xs, ys = spec.centres()
    ring = np.abs(np.hypot(xs, ys) - 2.0) < 0.15
    seeker.knowledge.evidence[ring] = 3.0
    seeker.knowledge.known[ring] = True
    assert seeker.command(Pose(0.0, 0.0, 0.0), Pose(4.0, 0.0, 0.0), 0.0) == (0.0, 0.0)
    assert seeker.clears == 1 and not seeker.finished
    assert not seeker.knowledge.occupied.any()  # forgotten
    v, _w = seeker.command(Pose(0.0, 0.0, 0.0), Pose(4.0, 0.0, 0.0), 0.1)
    assert v > 0.0 and not seeker.finished  # the way is open again
    # A wall that is really there comes back with the next scans; walled in again after a
    # successful plan, it clears once more, and only a second failure in a row gives up.
    seeker.knowledge.evidence[ring] = 3.0
    seeker.knowledge.known[ring] = True
    seeker.command(Pose(0.0, 0.0, 0.0), Pose(4.0, 0.0, 0.0), 5.0)
    assert seeker.clears == 2 and not seeker.finished
    seeker.knowledge.evidence[ring] = 3.0
    seeker.knowledge.known[ring] = True
    seeker.command(Pose(0.0, 0.0, 0.0), Pose(4.0, 0.0, 0.0), 5.1)
    assert seeker.finished and seeker.clears == 2
