"""``GoalSeeker``: a scripted driver to a goal pose in its own odometry frame.

It is ``albot2d/GoTo-v0``'s baseline policy and knows only what the robot knows: its
odometry pose, the laser's scans, a bumper (``collided``) and the goal in the odometry
frame. It keeps a ``KnowledgeGrid`` in that frame (odometry drift smears the walls there,
as it would on a real robot), plans optimistically through cells it has not seen (a
person walking to an address does the same) with Dijkstra to the cells within
``position_tolerance_m`` of the goal, and follows the path corner to corner
(``navigation.steer``). It plans again every ``replan_period_s``, when the laser shows
something in the strip the disc would sweep in the next ``stop_distance_m``, and after a
collision (first backing off for ``back_off_s``). At the goal's position it turns on the
spot to the goal's heading and stops. When no path is left (drift has smeared walls
across the way in its grid, or the goal lies inside what it has seen to be a wall) it
clears its grid once, as ROS's navigation stack clears its costmaps to recover, and plans
again from the next scan; if that fails too it stops and says so (``finished``) until a
later plan finds a way.

Whether it arrives in truth depends on the odometry's drift over the way: the environment
judges arrival by the true pose, the seeker by its odometry.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from albot2d.control.knowledge import GridSpec, KnowledgeGrid
from albot2d.control.navigation import (
    blocked_ahead,
    cost_grid,
    plan_path,
    search_seeds,
    steer,
)
from albot2d.frames import Scan
from albot2d.geometry import Pose, wrap_angle
from albot2d.validation import check_non_negative, check_positive

__all__ = ["GoalSeeker", "GoalSeekerParams"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class GoalSeekerParams:
    """The goal seeker's settings (see the module docstring); the pace and the margins are
    the frontier explorer's (``ExplorerParams``)."""

    resolution_m: float = 0.1
    sensing_range_m: float = 10.0
    speed_mps: float = 0.5
    turn_rate_radps: float = 1.0
    wall_margin_m: float = 0.05
    comfort_margin_m: float = 0.3
    comfort_cost: float = 4.0
    corner_tolerance_m: float = 0.15
    position_tolerance_m: float = 0.1
    heading_tolerance_rad: float = 0.1
    turn_in_place_rad: float = 0.3
    heading_gain: float = 2.0
    replan_period_s: float = 1.0
    stop_distance_m: float = 0.15
    back_off_s: float = 0.5
    back_off_speed_mps: float = 0.2
    control_period_s: float = 0.1
    #: How far from the goal a stand-in goal cell may be when the goal's own cells are
    #: impassable (odometry drift put the goal against a wall the robot has seen).
    fallback_radius_m: float = 0.6

    def __post_init__(self) -> None:
        check_positive(
            self, "resolution_m", "sensing_range_m", "speed_mps", "turn_rate_radps",
            "corner_tolerance_m", "position_tolerance_m", "heading_tolerance_rad",
            "turn_in_place_rad", "heading_gain", "replan_period_s", "comfort_cost",
            "control_period_s",
        )  # fmt: skip
        check_non_negative(
            self, "wall_margin_m", "comfort_margin_m", "stop_distance_m", "back_off_s",
            "back_off_speed_mps", "fallback_radius_m",
        )  # fmt: skip


class GoalSeeker:
    """Drives a robot of ``radius_m`` to goal poses on the grid ``spec`` (odometry frame);
    call ``observe`` with each observation and ``command`` for the next velocity."""

    def __init__(self, spec: GridSpec, radius_m: float, params: GoalSeekerParams | None = None):
        self.params = params if params is not None else GoalSeekerParams()
        self.spec = spec
        self.radius_m = float(radius_m)
        self.knowledge = KnowledgeGrid(spec, sensing_range_m=self.params.sensing_range_m)
        self.finished = False
        self.arrived = False
        self.plans = 0
        self._xs, self._ys = spec.centres()
        self._path: FloatArray | None = None
        self._next_plan_s = 0.0
        self._replan = True
        self._backing_s = 0.0
        self._cleared = False
        self.clears = 0

    def observe(self, pose: Pose, scan: Scan | None, collided: bool = False) -> None:
        """Take in an observation (``pose`` is the odometry pose)."""
        self.knowledge.mark_footprint(pose, self.radius_m)
        if collided:
            self._replan = True
            self._backing_s = self.params.back_off_s
        if scan is None:
            return
        if self._path is not None and blocked_ahead(
            scan, self.radius_m, self.params.stop_distance_m
        ):
            self._replan = True
        self.knowledge.integrate(pose, scan)

    def command(self, pose: Pose, goal: Pose, time_s: float) -> tuple[float, float]:
        """The velocity ``(v_mps, omega_radps)`` to hold next towards ``goal`` (both poses
        in the odometry frame); a stop once arrived or given up."""
        p = self.params
        self.arrived = False
        if self._backing_s > 0.0:
            self._backing_s -= p.control_period_s
            return -p.back_off_speed_mps, 0.0
        if math.hypot(goal.x - pose.x, goal.y - pose.y) <= p.position_tolerance_m:
            err = float(wrap_angle(goal.theta - pose.theta))
            if abs(err) <= p.heading_tolerance_rad:
                self.arrived = True
                return 0.0, 0.0
            return 0.0, float(np.clip(p.heading_gain * err, -p.turn_rate_radps, p.turn_rate_radps))
        if self._replan or self._path is None or time_s >= self._next_plan_s:
            self._plan(pose, goal, time_s)
        if self._path is None:
            return 0.0, 0.0
        step = steer(
            self._path, pose, speed_mps=p.speed_mps, turn_rate_radps=p.turn_rate_radps,
            corner_tolerance_m=p.corner_tolerance_m, goal_tolerance_m=p.position_tolerance_m,
            turn_in_place_rad=p.turn_in_place_rad, heading_gain=p.heading_gain,
        )  # fmt: skip
        self._path = None if step.arrived else step.path
        return step.command

    def _plan(self, pose: Pose, goal: Pose, time_s: float) -> None:
        p = self.params
        self.plans += 1
        self._replan = False
        self._next_plan_s = time_s + p.replan_period_s
        cost = cost_grid(
            self.knowledge, self.radius_m, wall_margin_m=p.wall_margin_m,
            comfort_margin_m=p.comfort_margin_m, comfort_cost=p.comfort_cost,
            unknown_passable=True,
        )  # fmt: skip
        passable = np.isfinite(cost)
        d2 = (self._xs - goal.x) ** 2 + (self._ys - goal.y) ** 2
        reach = max(p.position_tolerance_m, 0.5 * self.spec.resolution_m)
        goals = passable & (d2 <= reach**2)
        exact = bool(goals.any())
        if not exact:
            goals = passable & (d2 <= max(p.fallback_radius_m, reach) ** 2)
        seeds, seed_dist = search_seeds(self.knowledge, pose, self.radius_m, passable)
        path = (
            plan_path(self.spec, cost, goals, seeds, seed_dist, pose)
            if goals.any() and len(seeds)
            else None
        )
        if path is None:
            self._path = None
            if self._cleared:
                self.finished = True
            else:  # recover: forget the grid, see afresh, plan again
                self.knowledge = KnowledgeGrid(self.spec, sensing_range_m=p.sensing_range_m)
                self.knowledge.mark_footprint(pose, self.radius_m)
                self._cleared, self._replan = True, True
                self.clears += 1
            return
        if exact:
            path[-1] = (goal.x, goal.y)  # within the goal cell's reach: drive to the goal itself
        self.finished = self._cleared = False
        self._path = path
