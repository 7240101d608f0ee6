"""Scan-matching baseline benchmark: ``ScanMatchingSLAM`` over 200 simulated office views.

Run: ``python -m pytest benchmarks/test_slam.py --benchmark-only``. Skips without the
``[slam]`` extra. Per view: surface extraction, one KISS-ICP registration (181 beams lifted
to 3 layers), one map insert.
"""

from __future__ import annotations

from typing import Any

import pytest

from albot2d.evaluation.experiment import plan_tour
from albot2d.frames import Frame
from albot2d.mapping.slam import ScanMatchingSLAM
from albot2d.sim.simulator import Simulator
from worldgen.generate import generate

pytest.importorskip("kiss_icp", reason="kiss-icp is not installed (pip install -e '.[slam]')")

N_VIEWS = 200


@pytest.fixture(scope="module")
def frames() -> list[Frame]:
    world = generate("office", seed=0, width_m=30, height_m=24)
    tour = plan_tour(world, "loop", 30.0)
    return list(Simulator(world, seed=0).drive(tour, "dataset3"))[:N_VIEWS]


def map_all(frames: list[Frame]) -> ScanMatchingSLAM:
    mapper = ScanMatchingSLAM()
    for f in frames:
        mapper.observe(f)
    return mapper


@pytest.mark.benchmark(group="slam")
def test_slam_200_views(benchmark: Any, frames: list[Frame]) -> None:
    mapper = benchmark.pedantic(map_all, args=(frames,), rounds=3, iterations=1)
    assert mapper.counts().views == N_VIEWS
