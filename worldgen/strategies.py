"""Hypothesis strategies for random procedural worlds (needs the ``test`` extra).

``worlds()`` draws a kind, a seed, a size and a few parameters, and generates the World,
so users and tests can fuzz anything that consumes worlds::

    @given(worlds(kinds=("rooms", "office"), max_size_m=40.0))
    def test_something(world): ...
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from hypothesis import strategies as st

from worldgen.generate import generate, kind_names
from worldgen.kinds import get_kind
from worldgen.world import World

__all__ = ["world_specs", "worlds"]

_DECIMETRES = 10


def _size(draw: st.DrawFn, low_m: float, high_m: float) -> float:
    high_m = max(low_m, high_m)
    dm = draw(st.integers(int(low_m * _DECIMETRES + 0.999), int(high_m * _DECIMETRES)))
    return max(low_m, dm / _DECIMETRES)


@st.composite
def world_specs(
    draw: st.DrawFn,
    kinds: Sequence[str] | None = None,
    max_size_m: float = 30.0,
    dynamic: bool = False,
) -> dict[str, Any]:
    """Keyword arguments for ``generate``: kind, seed, size and a few parameters.

    Sizes run from the kind's minimum up to ``max_size_m`` (or the minimum, if larger)."""
    kind = draw(st.sampled_from(list(kind_names() if kinds is None else kinds)))
    cls = get_kind(kind).params
    low = float(cls.min_size_m)
    spec: dict[str, Any] = {
        "kind": kind,
        "seed": draw(st.integers(0, 2**32 - 1)),
        "width_m": _size(draw, low, max_size_m),
        "height_m": _size(draw, low, max_size_m),
        "clutter_per_10m2": draw(st.sampled_from([0.0, 0.1, 0.3, 0.6])),
    }
    if kind == "rooms":
        spec["extra_door_fraction"] = draw(st.sampled_from([0.0, 0.3, 0.8]))
    if kind == "open":
        spec["hall_parts"] = draw(st.integers(1, 5))
        spec["partition_walls"] = draw(st.integers(0, 3))
    if kind == "mixed":
        spec["regions"] = draw(st.integers(2, 4))
    if kind == "corridors":
        spec["extra_link_fraction"] = draw(st.sampled_from([0.0, 0.2, 0.6]))
    if dynamic:
        spec["dynamic_obstacles"] = draw(st.integers(0, 3))
    return spec


@st.composite
def worlds(
    draw: st.DrawFn,
    kinds: Sequence[str] | None = None,
    max_size_m: float = 30.0,
    dynamic: bool = False,
) -> World:
    """A generated World of one of ``kinds``, no bigger than ``max_size_m`` where the kind
    allows (offices need 24 m, mixed worlds 30 m)."""
    spec = draw(world_specs(kinds=kinds, max_size_m=max_size_m, dynamic=dynamic))
    kind = spec.pop("kind")
    return generate(kind, **spec)
