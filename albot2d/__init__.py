"""albot2d: a fast 2D kinematic robot simulator for studying view-based cognitive mapping.

Layers, bottom up: ``albot2d.geometry`` → ``worldgen`` → simulation → perception →
mapping → evaluation → interfaces (CLI, ``albot2d.viz``). Import what you need from the
subpackages; this top level only re-exports the core value types.
"""

from albot2d.errors import InputError
from albot2d.geometry import Pose
from albot2d.seeding import make_rng, spawn_rngs, spawn_seeds

__version__ = "0.1.0"

__all__ = ["InputError", "Pose", "__version__", "make_rng", "spawn_rngs", "spawn_seeds"]
