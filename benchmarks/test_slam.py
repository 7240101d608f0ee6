"""SLAM cost per view beside Albot₁'s: the paper's point that SLAM is the heavier robot.

Run: ``python -m pytest benchmarks/test_slam.py --benchmark-only --benchmark-group-by=group``.
Skips without the ``[slam]`` extra. All three map the same ~30 m office loop (dataset3,
typical noise, ≈ 500 views, the loop closed at the end), so the means divided by the view
count are the cost per view, side by side in one run:

- ``albot1``: tracking, triangulation, the transient global map;
- ``scan_odometry``: surface extraction, one KISS-ICP registration per view (181 beams
  lifted to 3 layers), one map insert;
- ``slam``: the same front end, plus keyframes, proximity loop candidates and short-range
  constraints verified by registering local maps, Hessian-shaped chain factors, and GNC
  on the GTSAM pose graph (its defaults);
- ``slam_previous``: the previous defaults (no short-range constraints, fixed chain
  information, Levenberg–Marquardt with Cauchy kernels);
- ``slam_gnc_all``: the defaults with every registration-verified closure admitted
  (``LoopClosureParams(gate="none")``) for GNC to weigh.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import pytest

from albot2d.frames import Frame
from albot2d.mapping import Albot1, Mapper
from albot2d.mapping.slam import LoopClosingSLAM, ScanMatchingSLAM, SlamParams
from albot2d.mapping.slam.loop_closure import LoopClosureParams
from albot2d.mapping.slam.pose_graph import PoseGraphParams
from albot2d.sim.odometry import noise_preset
from albot2d.sim.simulator import Simulator
from worldgen import plan_tour
from worldgen.generate import generate

pytest.importorskip("kiss_icp", reason="kiss-icp is not installed (pip install -e '.[slam]')")
pytest.importorskip("gtsam", reason="gtsam is not installed (pip install -e '.[slam]')")


@pytest.fixture(scope="module")
def frames() -> list[Frame]:
    world = generate("office", seed=0, width_m=30, height_m=24)
    tour = plan_tour(world, "loop", 30.0)
    sim = Simulator(world, seed=0, odometry=noise_preset("typical"))
    return list(sim.drive(tour, "dataset3"))


def map_all(factory: Callable[[], Mapper], frames: list[Frame]) -> Mapper:
    mapper = factory()
    for f in frames:
        mapper.observe(f)
    return mapper


def slam_previous() -> LoopClosingSLAM:
    return LoopClosingSLAM(
        SlamParams(loops=LoopClosureParams(local_separation_m=None),
                   graph=PoseGraphParams(optimizer="lm", odom_information="fixed"))
    )  # fmt: skip


def slam_gnc_all() -> LoopClosingSLAM:
    return LoopClosingSLAM(SlamParams(loops=LoopClosureParams(gate="none")))


@pytest.mark.benchmark(group="slam-vs-albot1-per-loop")
@pytest.mark.parametrize(
    "factory",
    [Albot1, ScanMatchingSLAM, LoopClosingSLAM, slam_previous, slam_gnc_all],
    ids=["albot1", "scan_odometry", "slam", "slam_previous", "slam_gnc_all"],
)
def test_cost_of_one_loop(
    benchmark: Any, factory: Callable[[], Mapper], frames: list[Frame]
) -> None:
    mapper = benchmark.pedantic(map_all, args=(factory, frames), rounds=3, iterations=1)
    benchmark.extra_info["views"] = len(frames)
    benchmark.extra_info["ms_per_view"] = benchmark.stats.stats.mean * 1e3 / len(frames)
    assert mapper.counts().views == len(frames)
    if isinstance(mapper, LoopClosingSLAM):
        assert mapper.slam_stats()["loop_closures_accepted"] >= 1
