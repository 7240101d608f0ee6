"""Speed of world files, pymunk spaces and world pictures for a large generated office.

Run with ``python -m pytest benchmarks/test_worldgen_io_bench.py --benchmark-only``.
"""

from __future__ import annotations

import pytest

from worldgen.generate import generate
from worldgen.io import world_from_json, world_to_json
from worldgen.space import build_space

SIZE_M = 200.0


@pytest.fixture(scope="module")
def big_office():
    return generate("office", seed=1, width_m=SIZE_M, height_m=SIZE_M)


@pytest.mark.benchmark(group="worldgen-io")
def test_world_to_json(benchmark, big_office) -> None:
    text = benchmark(world_to_json, big_office)
    benchmark.extra_info["json_bytes"] = len(text.encode())
    benchmark.extra_info["walls"] = len(big_office.walls)


@pytest.mark.benchmark(group="worldgen-io")
def test_world_from_json(benchmark, big_office) -> None:
    text = world_to_json(big_office)
    world = benchmark(world_from_json, text)
    assert len(world.walls) == len(big_office.walls)


@pytest.mark.benchmark(group="worldgen-io")
def test_build_space(benchmark, big_office) -> None:
    space = benchmark(build_space, big_office)
    benchmark.extra_info["shapes"] = len(space.shapes)


@pytest.mark.benchmark(group="worldgen-io")
def test_render_world_png(benchmark, big_office) -> None:
    pytest.importorskip("matplotlib")
    from albot2d.viz.world import render_world_png

    png = benchmark.pedantic(render_world_png, args=(big_office,), rounds=2, iterations=1)
    benchmark.extra_info["png_bytes"] = len(png)
