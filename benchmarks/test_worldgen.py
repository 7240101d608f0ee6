"""Speed of world generation per kind at 50x50 m and 200x200 m, and of tour planning.

Run: ``python -m pytest benchmarks/test_worldgen.py --benchmark-only --benchmark-group-by=group``.
Goal: a 200x200 m office well under a second.
"""

from __future__ import annotations

import pytest

from albot2d.seeding import make_rng
from worldgen import generate
from worldgen.kinds import world_kinds
from worldgen.tours import make_tour

SIZES_M = (50.0, 200.0)
KINDS = tuple(world_kinds())


@pytest.mark.parametrize("size_m", SIZES_M)
@pytest.mark.parametrize("kind", KINDS)
def test_generate_speed(benchmark, kind: str, size_m: float) -> None:
    benchmark.group = f"generate {size_m:.0f}x{size_m:.0f} m"
    rounds = 5 if size_m <= 50.0 else 3
    world = benchmark.pedantic(
        generate,
        args=(kind,),
        kwargs={"seed": 1, "width_m": size_m, "height_m": size_m},
        rounds=rounds,
        iterations=1,
        warmup_rounds=1,
    )
    benchmark.extra_info.update(
        walls=len(world.walls),
        clutter=len(world.clutter),
        roadmap_nodes=len(world.roadmap.nodes),
    )
    assert world.width_m == size_m


@pytest.mark.parametrize("tour_kind", ["loop", "out_and_back", "backtracking"])
def test_tour_speed_in_a_200m_office(benchmark, tour_kind: str) -> None:
    benchmark.group = "tour 200x200 m office, 500 m"
    world = generate("office", seed=1, width_m=200.0, height_m=200.0)
    tour = benchmark.pedantic(
        make_tour,
        args=(world, make_rng(0)),
        kwargs={"kind": tour_kind, "min_length_m": 500.0},
        rounds=3,
        iterations=1,
    )
    benchmark.extra_info["length_m"] = round(tour.length_m, 1)
    assert tour.length_m >= 500.0
