"""``AlbotEnv``: what albot2d's Gymnasium environments share.

One episode is one world: ``reset(seed=...)`` seeds ``np_random`` (Gymnasium's convention)
and draws from it the world's seed (``worldgen.generate(kind, seed=...)``, unless a fixed
``world`` is given) and the simulator's seed, so the same seed gives the same world, noise
and episode. ``step(action)`` holds the action ``(v_mps, omega_radps)`` for ``dt_s``
simulated seconds (``Simulator.step``); an action outside the ``Box`` is clipped to it by
the simulator's limits, a NaN or infinite one is refused (``InputError`` naming it).

Observations are a ``Dict``: ``ranges`` (the laser's ranges, float32, invalid beams at the
maximum range; the latest scan when the laser did not fire in a step) and ``odometry``
(the odometry pose ``[x, y, theta]`` relative to where the episode began, float64).
``info`` carries the truth for evaluation and baselines (``true_pose``), never needed to act.
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from albot2d.errors import InputError
from albot2d.geometry import Pose
from albot2d.sim import LaserParams, OdometryNoise, RobotParams, Simulator, VelocityCommand
from albot2d.sim.commands import Observation
from albot2d.sim.laser import laser_noise_preset
from albot2d.sim.odometry import noise_preset
from worldgen.world import World

__all__ = ["POSE_BOUND_M", "AlbotEnv", "clip_to_pose_space", "pose_space"]

_SEED_BOUND = 2**31 - 1
#: Bound of the pose observations' x and y (m): far beyond any building, but finite.
POSE_BOUND_M = 1000.0


def pose_space() -> spaces.Box:
    """``[x, y, theta]``: metres within ``POSE_BOUND_M``, theta in [-π, π]."""
    high = np.array([POSE_BOUND_M, POSE_BOUND_M, math.pi])
    return spaces.Box(-high, high, dtype=np.float64)


def _finite_action(action: Any) -> tuple[float, float]:
    arr = np.asarray(action, dtype=np.float64).reshape(-1)
    if arr.shape != (2,):
        raise InputError(f"action must be [v_mps, omega_radps], got {action!r}")
    bad = ~np.isfinite(arr)
    if bad.any():
        name = ("v_mps", "omega_radps")[int(np.flatnonzero(bad)[0])]
        raise InputError(f"action {name} must be finite, got {action!r}")
    return float(arr[0]), float(arr[1])


def clip_to_pose_space(pose: NDArray[np.float64]) -> NDArray[np.float64]:
    """A pose inside ``pose_space`` (theta is wrapped already; x, y beyond the bound only
    after kilometres of odometry drift)."""
    return np.clip(pose, -np.array([POSE_BOUND_M, POSE_BOUND_M, math.pi]),
                   np.array([POSE_BOUND_M, POSE_BOUND_M, math.pi]))  # fmt: skip


class AlbotEnv(gymnasium.Env[dict[str, NDArray[Any]], NDArray[np.float32]]):
    """Base class: world, simulator, action and observation spaces, rendering."""

    metadata = {"render_modes": ["human", "rgb_array"], "render_fps": 10}  # noqa: RUF012

    def __init__(
        self,
        *,
        kind: str = "office",
        world_params: dict[str, Any] | None = None,
        world: World | None = None,
        dt_s: float = 0.1,
        noise: str = "typical",
        laser_noise: str = "sick_lms200",
        robot: RobotParams | None = None,
        laser: LaserParams | None = None,
        render_mode: str | None = None,
    ) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise InputError(
                f"render_mode must be one of {self.metadata['render_modes']}, got {render_mode!r}"
            )
        if not (isinstance(dt_s, int | float) and math.isfinite(dt_s) and dt_s > 0):
            raise InputError(f"dt_s must be a positive number, got {dt_s!r}")
        if world is None:
            from worldgen.generate import make_params

            make_params(kind, **(world_params or {}))  # a bad kind or parameter fails here
        self.kind = kind
        self.world_params = dict(world_params or {})
        self.fixed_world = world
        self.dt_s = float(dt_s)
        self.odometry_noise: OdometryNoise = noise_preset(noise)
        self.laser_noise = laser_noise_preset(laser_noise)
        self.robot_params = robot if robot is not None else RobotParams()
        self.laser_params = laser if laser is not None else LaserParams()
        self.render_mode = render_mode
        v = self.robot_params.max_speed_m_s
        w = math.radians(self.robot_params.max_turn_rate_deg_s)
        self.action_space: spaces.Box = spaces.Box(  # type: ignore[assignment]
            low=np.array([-v, -w], dtype=np.float32), high=np.array([v, w], dtype=np.float32)
        )
        self.observation_space = spaces.Dict(self._observation_spaces())  # type: ignore[assignment]
        self.world: World | None = None
        self.simulator: Simulator | None = None
        self.last: Observation | None = None
        self._ranges = np.full(self.laser_params.n_beams, self.laser_params.max_range_m, np.float32)
        self._start = Pose()
        self._renderer: Any = None

    # -- spaces and observations -------------------------------------------------------

    def _observation_spaces(self) -> dict[str, spaces.Space[Any]]:
        lp = self.laser_params
        return {
            "ranges": spaces.Box(0.0, lp.max_range_m, shape=(lp.n_beams,), dtype=np.float32),
            "odometry": pose_space(),
        }

    def _observation(self, obs: Observation) -> dict[str, NDArray[Any]]:
        if obs.scan is not None:
            self._ranges = np.clip(
                np.where(obs.scan.valid, obs.scan.ranges, self.laser_params.max_range_m),
                0.0, self.laser_params.max_range_m,
            ).astype(np.float32)  # fmt: skip
        odom = self._start.between(obs.odom_pose).as_array()
        return {"ranges": self._ranges.copy(), "odometry": clip_to_pose_space(odom)}

    def _info(self, obs: Observation) -> dict[str, Any]:
        return {
            "time_s": obs.time_s,
            "true_pose": obs.true_pose.as_array(),
            "collided": obs.collided,
            "world_seed": None if self.world is None else self.world.seed,
        }

    # -- episode -----------------------------------------------------------------------

    def _new_world(self) -> World:
        if self.fixed_world is not None:
            return self.fixed_world
        from worldgen.generate import generate

        seed = int(self.np_random.integers(_SEED_BOUND))
        return generate(self.kind, seed=seed, **self.world_params)

    def _begin(self, seed: int | None, options: dict[str, Any] | None) -> Observation:
        """Seed, make the episode's world and simulator, reset it; the first observation."""
        super().reset(seed=seed, options=options)
        self.world = self._new_world()
        self.simulator = Simulator(
            self.world, seed=int(self.np_random.integers(_SEED_BOUND)),
            robot=self.robot_params, laser=self.laser_params,
            laser_noise=self.laser_noise, odometry=self.odometry_noise,
        )  # fmt: skip
        self._start = self.world.start
        self._ranges = np.full(self.laser_params.n_beams, self.laser_params.max_range_m, np.float32)
        self.last = self.simulator.reset()
        return self.last

    def _advance(self, action: Any) -> Observation:
        if self.simulator is None:
            raise RuntimeError("call reset() before step()")
        v, w = _finite_action(action)
        self.last = self.simulator.step(VelocityCommand(v, w), self.dt_s)
        return self.last

    # -- rendering ---------------------------------------------------------------------

    def _render_layers(self) -> dict[str, Any]:
        """What the renderer draws beyond the world, the robot and its scan."""
        return {}

    def render(self) -> NDArray[np.uint8] | None:
        if self.render_mode is None or self.world is None or self.last is None:
            return None
        from albot2d.viz.env_render import EnvRenderer

        if self._renderer is None:
            self._renderer = EnvRenderer(human=self.render_mode == "human")
        image = self._renderer.draw(self.world, self.last, **self._render_layers())
        return image if self.render_mode == "rgb_array" else None

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
