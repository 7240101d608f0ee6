"""Gymnasium environments on albot2d's simulator (the ``gym`` extra: ``pip install
'albot2d[gym]'``).

- ``albot2d/Explore-v0`` (``ExploreEnv``): a fresh procedural world per ``reset(seed=...)``;
  reward is the new reachable floor area the laser shows (m²).
- ``albot2d/GoTo-v0`` (``GoToEnv``): reach a goal pose given relative to odometry.

Importing this package registers both ids with Gymnasium. Gymnasium 1.x no longer loads
plugins from entry points, so import it first (``import albot2d.envs``) or name the module
in the id: ``gymnasium.make("albot2d.envs:albot2d/Explore-v0")``. Imports gymnasium, the
simulation and control layers; rendering imports matplotlib lazily (``albot2d.viz.env_render``).
"""

import gymnasium

from albot2d.envs.base import AlbotEnv
from albot2d.envs.explore import ExploreEnv
from albot2d.envs.goto import GoToEnv

__all__ = ["ENV_IDS", "AlbotEnv", "ExploreEnv", "GoToEnv", "register_envs"]

#: The registered ids and their entry points.
ENV_IDS = {
    "albot2d/Explore-v0": ("albot2d.envs.explore:ExploreEnv", 6000),
    "albot2d/GoTo-v0": ("albot2d.envs.goto:GoToEnv", 1200),
}


def register_envs() -> None:
    """Register every albot2d environment with Gymnasium (once; idempotent)."""
    for env_id, (entry_point, steps) in ENV_IDS.items():
        if env_id not in gymnasium.registry:
            gymnasium.register(id=env_id, entry_point=entry_point, max_episode_steps=steps)


register_envs()
