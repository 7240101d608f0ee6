"""``GoToEnv`` (``albot2d/GoTo-v0``): drive to a goal pose given relative to odometry.

At ``reset`` a goal is drawn (from ``np_random``) among the world's roadmap nodes between
``min_goal_m`` and ``max_goal_m`` from the start (so it is reachable), with a random
heading. The observation adds ``goal``: the goal pose ``[x, y, theta]`` in the robot's
frame *as odometry sees it* (odometry pose⁻¹ ⊕ goal), so with odometry noise the goal
drifts as a real robot's would. Reward: the decrease of the true distance to the goal
(m) per step, minus ``collision_penalty`` on a collision, plus ``success_reward`` on
arrival. Terminated on arrival: the true position within ``goal_tolerance_m`` and heading
within ``heading_tolerance_rad`` of the goal. The registered id truncates after 1200 steps.

The baseline policy is ``albot2d.control.GoalSeeker`` (``baseline_policy``): it plans on
what its laser showed, in its odometry frame, and never reads the truth in ``info``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from albot2d.control.goal_seeker import GoalSeeker, GoalSeekerParams
from albot2d.control.knowledge import GridSpec
from albot2d.envs.base import AlbotEnv, clip_to_pose_space, pose_space
from albot2d.errors import InputError
from albot2d.geometry import Pose, wrap_angle
from albot2d.sim.commands import Observation

__all__ = ["GoToEnv", "baseline_policy"]


class GoToEnv(AlbotEnv):
    """Reach a goal pose given relative to odometry."""

    def __init__(
        self,
        *,
        min_goal_m: float = 2.0,
        max_goal_m: float = 10.0,
        goal_tolerance_m: float = 0.3,
        heading_tolerance_rad: float = 0.5,
        success_reward: float = 10.0,
        collision_penalty: float = 0.1,
        **kwargs: Any,
    ) -> None:
        if not 0.0 <= min_goal_m < max_goal_m:
            raise InputError(
                f"need 0 <= min_goal_m < max_goal_m, got {min_goal_m!r} and {max_goal_m!r}"
            )
        if not (goal_tolerance_m > 0 and heading_tolerance_rad > 0):
            raise InputError(
                f"goal tolerances must be positive, got {goal_tolerance_m!r}, "
                f"{heading_tolerance_rad!r}"
            )
        super().__init__(**kwargs)
        self.min_goal_m = float(min_goal_m)
        self.max_goal_m = float(max_goal_m)
        self.goal_tolerance_m = float(goal_tolerance_m)
        self.heading_tolerance_rad = float(heading_tolerance_rad)
        self.success_reward = float(success_reward)
        self.collision_penalty = float(collision_penalty)
        self.goal = Pose()
        self._distance = 0.0

    def _observation_spaces(self) -> dict[str, spaces.Space[Any]]:
        out = super()._observation_spaces()
        out["goal"] = pose_space()
        return out

    def _observation(self, obs: Observation) -> dict[str, NDArray[Any]]:
        out = super()._observation(obs)
        out["goal"] = clip_to_pose_space(obs.odom_pose.between(self.goal).as_array())
        return out

    def _draw_goal(self) -> Pose:
        assert self.world is not None
        start = self.world.start
        nodes = self.world.roadmap.nodes
        d = np.hypot(nodes[:, 0] - start.x, nodes[:, 1] - start.y)
        ok = np.flatnonzero((d >= self.min_goal_m) & (d <= self.max_goal_m))
        if len(ok) == 0:  # a small world: the farthest node within reach
            ok = np.array([int(np.argmax(np.where(d <= self.max_goal_m, d, -1.0)))])
        x, y = nodes[int(self.np_random.choice(ok))]
        return Pose(float(x), float(y), float(self.np_random.uniform(-math.pi, math.pi)))

    def _arrived(self, pose: Pose) -> bool:
        heading = abs(float(wrap_angle(pose.theta - self.goal.theta)))
        return pose.distance_to(self.goal) <= self.goal_tolerance_m and (
            heading <= self.heading_tolerance_rad
        )

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, NDArray[Any]], dict[str, Any]]:
        obs = self._begin(seed, options)
        self.goal = self._draw_goal()
        self._distance = obs.true_pose.distance_to(self.goal)
        if self.render_mode == "human":
            self.render()
        info = self._info(obs) | {"goal_true": self.goal.as_array(), "distance_m": self._distance}
        return self._observation(obs), info

    def step(
        self, action: Any
    ) -> tuple[dict[str, NDArray[Any]], float, bool, bool, dict[str, Any]]:
        obs = self._advance(action)
        distance = obs.true_pose.distance_to(self.goal)
        reward = self._distance - distance
        self._distance = distance
        if obs.collided:
            reward -= self.collision_penalty
        terminated = self._arrived(obs.true_pose)
        if terminated:
            reward += self.success_reward
        if self.render_mode == "human":
            self.render()
        info = self._info(obs) | {"goal_true": self.goal.as_array(), "distance_m": distance}
        return self._observation(obs), float(reward), terminated, False, info

    def _render_layers(self) -> dict[str, Any]:
        return {"goal": self.goal}


def baseline_policy(env: GoToEnv, params: GoalSeekerParams | None = None) -> Any:
    """The goal seeker as a policy for ``env`` (after its ``reset``): a callable
    ``policy(observation, info) -> action`` that reads the observation's odometry and goal,
    the latest scan and the bumper (``collided``), never the true pose."""
    if env.world is None or env.last is None:
        raise RuntimeError("reset the environment before making its baseline policy")
    params = params if params is not None else GoalSeekerParams()
    # The odometry frame's grid: the goal lies within max_goal_m; detours and drift within
    # a sensing range more.
    half_m = env.max_goal_m + params.sensing_range_m
    spec = GridSpec.covering(-half_m, -half_m, half_m, half_m, params.resolution_m)
    seeker = GoalSeeker(spec, env.robot_params.radius_m, params)

    def policy(observation: dict[str, NDArray[Any]], info: dict[str, Any]) -> NDArray[np.float32]:
        last = env.last
        assert last is not None
        pose = Pose.from_array(observation["odometry"])
        seeker.observe(pose, last.scan, last.collided)
        goal = pose.compose(Pose.from_array(observation["goal"]))
        v, w = seeker.command(pose, goal, last.time_s)
        return np.clip(
            np.array([v, w], dtype=np.float32), env.action_space.low, env.action_space.high
        )

    return policy
