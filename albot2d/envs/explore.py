"""``ExploreEnv`` (``albot2d/Explore-v0``): see as much of the reachable floor as you can.

Each step's reward is the reachable floor area (m², ``albot2d.control.floor``) the laser
showed for the first time (``KnowledgeGrid`` ray-cast from the true pose, up to
``sensing_range_m``), minus ``collision_penalty`` when the robot ran into something. The
episode terminates when ``done_coverage`` of the reachable floor has been seen; the
registered id truncates it after 6000 steps (10 simulated minutes at the default 0.1 s).
``info`` adds ``coverage`` (the fraction seen) and ``explored_m2``.

The baseline policy is ``albot2d.control.FrontierExplorer`` (``baseline_policy``), which
reads the true pose from ``info`` as the paper's human operator watched the robot.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from albot2d.control.exploration import explorer_grid
from albot2d.control.explorer import ExplorerParams, FrontierExplorer
from albot2d.control.floor import ReachableFloor, reachable_floor
from albot2d.control.knowledge import KnowledgeGrid
from albot2d.envs.base import AlbotEnv
from albot2d.errors import InputError
from albot2d.geometry import Pose
from albot2d.sim.commands import Observation

__all__ = ["ExploreEnv", "baseline_policy"]


class ExploreEnv(AlbotEnv):
    """Explore a procedural world; reward = new reachable floor seen (m²)."""

    def __init__(
        self,
        *,
        resolution_m: float = 0.1,
        sensing_range_m: float = 10.0,
        done_coverage: float = 0.95,
        collision_penalty: float = 0.0,
        **kwargs: Any,
    ) -> None:
        if not 0.0 < done_coverage <= 1.0:
            raise InputError(f"done_coverage must be in (0, 1], got {done_coverage!r}")
        if not collision_penalty >= 0.0:
            raise InputError(f"collision_penalty must be >= 0, got {collision_penalty!r}")
        super().__init__(**kwargs)
        self.resolution_m = float(resolution_m)
        self.sensing_range_m = float(sensing_range_m)
        self.done_coverage = float(done_coverage)
        self.collision_penalty = float(collision_penalty)
        self.floor: ReachableFloor | None = None
        self.knowledge: KnowledgeGrid | None = None
        self._seen = 0

    def _take_in(self, obs: Observation) -> float:
        """Integrate the scan; the new reachable floor area it showed (m²)."""
        assert self.knowledge is not None and self.floor is not None
        if obs.scan is None:
            return 0.0
        new = self.knowledge.integrate(obs.true_pose, obs.scan)
        cells = int(np.count_nonzero(self.floor.mask.reshape(-1)[new]))
        self._seen += cells
        return cells * self.floor.spec.cell_area_m2

    @property
    def coverage(self) -> float:
        return 0.0 if self.floor is None else self._seen / max(self.floor.cells, 1)

    def _info_with_coverage(self, obs: Observation) -> dict[str, Any]:
        info = self._info(obs)
        info["coverage"] = self.coverage
        info["explored_m2"] = (
            0.0 if self.floor is None else self._seen * self.floor.spec.cell_area_m2
        )
        return info

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, NDArray[Any]], dict[str, Any]]:
        obs = self._begin(seed, options)
        assert self.world is not None
        spec = explorer_grid(self.world, self.resolution_m)
        self.floor = reachable_floor(self.world, spec, self.robot_params.radius_m)
        self.knowledge = KnowledgeGrid(spec, sensing_range_m=self.sensing_range_m)
        self._seen = 0
        self._take_in(obs)
        if self.render_mode == "human":
            self.render()
        return self._observation(obs), self._info_with_coverage(obs)

    def step(
        self, action: Any
    ) -> tuple[dict[str, NDArray[Any]], float, bool, bool, dict[str, Any]]:
        obs = self._advance(action)
        reward = self._take_in(obs) - (self.collision_penalty if obs.collided else 0.0)
        terminated = self.coverage >= self.done_coverage
        if self.render_mode == "human":
            self.render()
        return (
            self._observation(obs),
            float(reward),
            terminated,
            False,
            self._info_with_coverage(obs),
        )

    def _render_layers(self) -> dict[str, Any]:
        if self.knowledge is None:
            return {}
        return {"seen": self.knowledge.seen, "grid": self.knowledge.spec}


def baseline_policy(env: ExploreEnv, params: ExplorerParams | None = None) -> Any:
    """The frontier explorer as a policy for ``env`` (after its ``reset``): a callable
    ``policy(observation, info) -> action``; it returns a stop ``[0, 0]`` once finished."""
    if env.world is None or env.last is None:
        raise RuntimeError("reset the environment before making its baseline policy")
    explorer = FrontierExplorer(
        explorer_grid(env.world, env.resolution_m), env.robot_params.radius_m, params
    )
    state = {"last": env.last}

    def policy(observation: dict[str, NDArray[Any]], info: dict[str, Any]) -> NDArray[np.float32]:
        obs = env.last
        assert obs is not None
        pose = Pose.from_array(info["true_pose"])
        explorer.observe(pose, obs.scan, bool(info.get("collided", False)))
        state["last"] = obs
        command = explorer.command(pose, float(info["time_s"]))
        v, w = (0.0, 0.0) if command is None else command
        return np.clip(
            np.array([v, w], dtype=np.float32), env.action_space.low, env.action_space.high
        )

    return policy
