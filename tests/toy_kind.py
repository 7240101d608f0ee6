"""A world kind defined outside worldgen, as a user's module would: one record, registered.

``tests/test_world_kinds.py`` imports it in a fresh process and drives the real CLI.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from worldgen.kinds import Layout, WorldKind, register_kind
from worldgen.params import CommonParams


@dataclass(frozen=True)
class ToyParams(CommonParams):
    """One empty hall: the smallest kind there can be."""

    width_m: float = 12.0
    height_m: float = 8.0
    min_size_m = 6.0


def layout_toy(rect: np.ndarray, p: ToyParams, rng: np.random.Generator) -> Layout:
    """The whole rectangle, less a wall's thickness, is floor."""
    import shapely

    x0, y0, x1, y1 = rect + np.array([0.2, 0.2, -0.2, -0.2])
    return Layout(floor=[shapely.box(x0, y0, x1, y1)], links=None)


KIND = register_kind(
    WorldKind(name="toy", params=ToyParams, layout=layout_toy, summary="one empty hall")
)
