"""Speed of the simulator on a generated office world.

- one full step (move + scan + odometry), the unit of every simulated run;
- the robot's swept-disc move alone, and one laser scan alone, to split the step;
- frames per second driving a dataset1 tour (with moving obstacles too).

Run: ``python -m pytest benchmarks/test_simulator.py --benchmark-only``.
"""

from __future__ import annotations

import dataclasses
import itertools

import pytest

from albot2d.seeding import make_rng
from albot2d.sim.laser import Laser
from albot2d.sim.odometry import NOISE_PRESETS
from albot2d.sim.robot import KinematicRobot
from albot2d.sim.simulator import Simulator
from worldgen.generate import generate
from worldgen.space import build_space
from worldgen.tours import make_tour


@pytest.fixture(scope="module")
def office():
    world = generate("office", seed=11)
    return dataclasses.replace(world, dynamic_obstacles=())


@pytest.fixture(scope="module")
def long_tour(office):
    return make_tour(office, make_rng(1), kind="loop", min_length_m=400.0)


def test_simulator_step(benchmark, office, long_tour) -> None:
    """One dataset1 step: a 10 cm move or 1° turn, odometry noise, a 181-beam noisy scan."""
    sim = Simulator(office, seed=3, odometry=NOISE_PRESETS["typical"])
    frames = sim.drive(long_tour, "dataset1")
    next(frames)
    frame = benchmark.pedantic(lambda: next(frames), rounds=3000, iterations=1, warmup_rounds=50)
    # Timed: 50 warm-up steps and 3000 rounds; under --benchmark-disable (CI): one step.
    assert frame.index == (3050 if benchmark.stats is not None else 1)


def test_robot_move_10cm(benchmark, office) -> None:
    robot = KinematicRobot(build_space(office), pose=office.start)
    steps = itertools.cycle([0.1] * 10 + [-0.1] * 10)
    result = benchmark(lambda: robot.move(next(steps)))
    assert result.distance_m > 0.0 or result.collided


@pytest.mark.parametrize("noise_backend", ["numpy", "numba"])
def test_laser_scan_181(benchmark, office, noise_backend: str) -> None:
    """A noisy scan: the noise model as numpy calls (today's) or one compiled call."""
    if noise_backend == "numba":
        pytest.importorskip("numba")
    benchmark.group = "laser scan 181 beams"
    laser = Laser(office.obstacle_segments, noise_backend=noise_backend)
    rng = make_rng(0)
    laser.scan(office.start, rng)  # compile (or load the cache) first
    scan = benchmark(laser.scan, office.start, rng)
    assert scan.valid.any()


@pytest.mark.benchmark(group="simulator + albot1, 1,500 steps of a 60 m loop")
@pytest.mark.parametrize("lookahead", [1, 32])
def test_simulator_with_albot1_steps_per_second(benchmark, office, lookahead: int) -> None:
    """Simulator + Albot1 (extraction included) per step: the unit of a mapping run. With
    ``lookahead=32`` the simulator computes 32 frames at a time (the same frames): the two
    working sets then share the cache in turns, not at every step."""
    from albot2d.mapping import Albot1

    tour = make_tour(office, make_rng(1), kind="loop", min_length_m=60.0)
    sim = Simulator(office, seed=3, odometry=NOISE_PRESETS["typical"])
    frames = list(itertools.islice(sim.drive(tour, "dataset1"), 5))
    Albot1().observe(frames[0])  # compile (or load the cache) first

    def run() -> int:
        mapper, count = Albot1(), 0
        for frame in itertools.islice(sim.drive(tour, "dataset1", lookahead=lookahead), 1500):
            mapper.observe(frame)
            count += 1
        return count

    # One untimed round first: the first map updates load the tracking, triangulation and
    # deletion kernels from numba's cache (~40 ms, 6 % of a round), which is not a step.
    count = benchmark.pedantic(run, rounds=5, iterations=1, warmup_rounds=1)
    assert count == 1500
    if benchmark.stats is None:  # --benchmark-disable (CI): run once, untimed
        return
    stats = benchmark.stats.stats
    benchmark.extra_info["steps_per_s"] = count / stats.mean
    benchmark.extra_info["steps_per_s_median"] = count / stats.median
    benchmark.extra_info["steps_per_s_best"] = count / stats.min


@pytest.mark.parametrize("with_obstacles", [False, True])
def test_dataset1_frames_per_second(benchmark, office, with_obstacles: bool) -> None:
    world = generate("office", seed=11, dynamic_obstacles=6) if with_obstacles else office
    tour = make_tour(world, make_rng(1), kind="loop", min_length_m=100.0)
    sim = Simulator(world, seed=3, odometry=NOISE_PRESETS["typical"])
    count = benchmark.pedantic(
        lambda: sum(1 for _ in sim.drive(tour, "dataset1")), rounds=3, iterations=1
    )
    assert count > 1000
    if benchmark.stats is None:  # --benchmark-disable (CI): run once, untimed
        return
    benchmark.extra_info["frames"] = count
    benchmark.extra_info["frames_per_s"] = count / benchmark.stats.stats.mean
    assert count > 1000
