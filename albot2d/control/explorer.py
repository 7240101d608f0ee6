"""``FrontierExplorer``: a scripted operator that drives to the nearest reachable frontier.

It knows its true pose (as the paper's human operator, who watched the robot, did) and keeps
its own ``KnowledgeGrid`` of what the laser has shown. Each plan:

1. the cost grid: impassable where the robot's disc (plus ``wall_margin_m``) would touch
   an occupied cell or its centre would come nearer than its radius to an unknown cell;
   ``comfort_cost`` times dearer within ``comfort_margin_m`` more of a wall (so it keeps to
   the middle of corridors and doorways);
2. the goals: passable cells near a frontier (a seen free cell next to an unknown one),
   minus the places already given up;
3. Dijkstra from the robot's cell (``grid_search.nearest_goal_path``) to the nearest goal,
   the path cut down to its corners.

It follows the path corner to corner with velocity commands (turn on the spot towards the
next corner when more than ``turn_in_place_rad`` off heading, else drive with a
proportional heading correction, at most
``speed_mps`` / ``turn_rate_radps``) and plans again every ``replan_period_s``, on arrival,
after a collision (first backing off for ``back_off_s`` along the way it came), or when
the laser shows something in the strip the disc would sweep in the next
``stop_distance_m``. When its own cell is impassable (hard against a wall) the search
starts from the passable cells within a diameter that it sees in a straight line. A goal
it arrives at without clearing its frontier, or makes no progress towards for
``stuck_time_s``, is given up. It begins by turning once on the spot (the laser sees only
forward). When frontiers are left but no path reaches any (its grid has walled it in: a
stray return, a mixed pixel at a door jamb, left an occupied cell in a doorway that no fan
of the laser has passed through since), it forgets the grid's obstacle evidence, as ROS's
navigation stack clears its costmaps to recover, and plans again; the walls in view come
back with the next scan. It is finished when no frontier is left, or when no path is
found right after such a clear (it clears again only once it has seen something new).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from albot2d.control.grid_search import dilate
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

__all__ = ["ExplorerParams", "FrontierExplorer"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class ExplorerParams:
    """The explorer's settings (see the module docstring). Speeds are a cautious indoor
    pace for a Pioneer 3-DX (its top speed is 1.2 m/s); the simulator's own limits clamp
    them further if lower."""

    resolution_m: float = 0.1
    sensing_range_m: float = 10.0
    speed_mps: float = 0.5
    turn_rate_radps: float = 1.0
    wall_margin_m: float = 0.05
    comfort_margin_m: float = 0.3
    comfort_cost: float = 4.0
    frontier_reach_m: float = 0.5
    corner_tolerance_m: float = 0.15
    turn_in_place_rad: float = 0.3
    heading_gain: float = 2.0
    goal_tolerance_m: float = 0.3
    replan_period_s: float = 2.0
    stop_distance_m: float = 0.15
    stuck_time_s: float = 15.0
    give_up_radius_m: float = 1.0
    back_off_s: float = 0.5
    back_off_speed_mps: float = 0.2
    control_period_s: float = 0.1
    initial_spin: bool = True

    def __post_init__(self) -> None:
        check_positive(
            self, "resolution_m", "sensing_range_m", "speed_mps", "turn_rate_radps",
            "corner_tolerance_m", "turn_in_place_rad", "heading_gain", "goal_tolerance_m",
            "replan_period_s", "stuck_time_s", "comfort_cost", "control_period_s",
        )  # fmt: skip
        check_non_negative(
            self, "wall_margin_m", "comfort_margin_m", "frontier_reach_m", "stop_distance_m",
            "give_up_radius_m", "back_off_s", "back_off_speed_mps",
        )  # fmt: skip


class FrontierExplorer:
    """Explores the grid ``spec`` with a robot of ``radius_m``; call ``observe`` with each
    observation and ``command`` for the next velocity (``None`` once finished)."""

    def __init__(self, spec: GridSpec, radius_m: float, params: ExplorerParams | None = None):
        self.params = params if params is not None else ExplorerParams()
        self.spec = spec
        self.radius_m = float(radius_m)
        self.knowledge = KnowledgeGrid(spec, sensing_range_m=self.params.sensing_range_m)
        self.finished = False
        self.plans = 0
        self.given_up: list[tuple[float, float]] = []
        self._given_up_mask = np.zeros(spec.shape, dtype=bool)
        self._centres = spec.centres()
        self._path: FloatArray | None = None  # world (x, y) corners still to drive
        self._goal: tuple[float, float] | None = None
        self._spin_left = 2.0 * math.pi if self.params.initial_spin else 0.0
        self._last_heading: float | None = None
        self._next_plan_s = 0.0
        self._replan = True
        self._backing_s = 0.0
        self._progress_s = 0.0
        self._best_goal_dist = math.inf
        self.clears = 0  # times the obstacle evidence was forgotten to recover
        self._cleared = False  # and no new cell seen since

    # -- sensing -----------------------------------------------------------------------

    def observe(self, pose: Pose, scan: Scan | None, collided: bool = False) -> NDArray[np.intp]:
        """Take in an observation; returns the flat cells seen for the first time."""
        self.knowledge.mark_footprint(pose, self.radius_m)
        if self._last_heading is not None and self._spin_left > 0.0:
            self._spin_left -= abs(float(wrap_angle(pose.theta - self._last_heading)))
        self._last_heading = pose.theta
        if collided:
            # Back off along the way it came (free: it was just there), then plan again.
            self._replan = True
            self._backing_s = self.params.back_off_s
        if scan is None:
            return np.zeros(0, dtype=np.intp)
        stop_m = self.params.stop_distance_m
        if self._path is not None and blocked_ahead(scan, self.radius_m, stop_m):
            self._replan = True
        new = self.knowledge.integrate(pose, scan)
        if len(new):
            self._cleared = False
        return new

    # -- acting ------------------------------------------------------------------------

    def command(self, pose: Pose, time_s: float) -> tuple[float, float] | None:
        """The velocity ``(v_mps, omega_radps)`` to hold next, or None when finished."""
        p = self.params
        if self.finished:
            return None
        if self._spin_left > 0.0:
            return 0.0, p.turn_rate_radps
        if self._backing_s > 0.0:
            self._backing_s -= p.control_period_s
            return -p.back_off_speed_mps, 0.0
        if self._path is not None and self._goal is not None:
            d = math.hypot(self._goal[0] - pose.x, self._goal[1] - pose.y)
            if d < self._best_goal_dist - 0.2:
                self._best_goal_dist, self._progress_s = d, time_s
            elif time_s - self._progress_s > p.stuck_time_s:
                self._give_up()
        if self._replan or self._path is None or time_s >= self._next_plan_s:
            self._plan(pose, time_s)
            if self.finished:
                return None
        assert self._path is not None
        return self._follow(pose)

    def _give_up(self) -> None:
        if self._goal is not None:
            self.given_up.append(self._goal)
            gx, gy = self._goal
            xs, ys = self._centres
            self._given_up_mask |= (xs - gx) ** 2 + (
                ys - gy
            ) ** 2 <= self.params.give_up_radius_m**2
        self._path, self._goal, self._replan = None, None, True

    def _costs(self) -> FloatArray:
        p = self.params
        return cost_grid(
            self.knowledge, self.radius_m, wall_margin_m=p.wall_margin_m,
            comfort_margin_m=p.comfort_margin_m, comfort_cost=p.comfort_cost,
            unknown_passable=False,
        )  # fmt: skip

    def _goals(self, passable: NDArray[np.bool_]) -> NDArray[np.bool_]:
        k = self.knowledge
        unknown = k.unknown
        near_unknown = np.zeros_like(unknown)
        near_unknown[1:, :] |= unknown[:-1, :]
        near_unknown[:-1, :] |= unknown[1:, :]
        near_unknown[:, 1:] |= unknown[:, :-1]
        near_unknown[:, :-1] |= unknown[:, 1:]
        frontier = k.seen & k.free & near_unknown
        reach = (self.radius_m + self.params.frontier_reach_m) / self.spec.resolution_m
        goals = dilate(frontier, reach) & passable
        return goals & ~self._given_up_mask

    def _plan(self, pose: Pose, time_s: float) -> None:
        p = self.params
        self.plans += 1
        self._replan = False
        self._next_plan_s = time_s + p.replan_period_s
        cost = self._costs()
        passable = np.isfinite(cost)
        goals = self._goals(passable)
        if not goals.any():
            self.finished = True
            self._path = None
            return
        seeds, seed_dist = search_seeds(self.knowledge, pose, self.radius_m, passable)
        path = plan_path(self.spec, cost, goals, seeds, seed_dist, pose) if len(seeds) else None
        if path is None:
            self._path = None
            if self._cleared:
                self.finished = True
                return
            # Walled in with frontiers left: forget the obstacles and plan again.
            self.knowledge.forget_obstacles()
            self._cleared = True
            self.clears += 1
            self._plan(pose, time_s)
            return
        goal = (float(path[-1, 0]), float(path[-1, 1]))
        if self._goal is None or math.hypot(goal[0] - self._goal[0], goal[1] - self._goal[1]) > 0.5:
            self._best_goal_dist, self._progress_s = math.inf, time_s
        self._goal = goal
        self._path = path

    def _follow(self, pose: Pose) -> tuple[float, float]:
        p = self.params
        assert self._path is not None
        step = steer(
            self._path, pose, speed_mps=p.speed_mps, turn_rate_radps=p.turn_rate_radps,
            corner_tolerance_m=p.corner_tolerance_m, goal_tolerance_m=p.goal_tolerance_m,
            turn_in_place_rad=p.turn_in_place_rad, heading_gain=p.heading_gain,
        )  # fmt: skip
        self._path = step.path
        if step.arrived:
            # Arrived: if its frontier is still there next plan, the goal is given up.
            self._give_up()
        return step.command
