"""Speed of ``Simulator.step``: one velocity command held for 0.1 s with a 181-beam scan
(the laser at 10 Hz fires every step), side by side with IR-SIM's ``env.step()`` and its
2D lidar (181 beams, 30 m) when ``ir-sim`` is installed.

Two scenes, each simulated by both: albot2d's default office world (60 × 40 m, 1,032 wall
and clutter segments; in IR-SIM one ``linestring`` obstacle per segment) and IR-SIM's own
kind of scene (a 10 × 10 m world, four boundary walls, three round and three box
obstacles, as in its lidar examples; in albot2d the same walls, the circles as 24-gons).
The robot drives a 0.5 m/s, 0.3 rad/s arc (it stops at walls and keeps being commanded).
The target is ≥ 10,000 steps per CPU-second on one core for albot2d in the office.

Each round is one step (so pytest-benchmark's ratios are per step); ``extra_info``
``steps_per_cpu_s`` is steps per second of this process's CPU time over all rounds (what
the target counts: on a shared machine wall time also counts other processes' turns).

Run: ``python -m pytest benchmarks/test_step.py --benchmark-only``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
import shapely

from albot2d.geometry import Pose, polygon_ring_segments
from albot2d.sim import Simulator, VelocityCommand, noise_preset
from albot2d.sim.laser import LaserParams
from worldgen.generate import generate
from worldgen.world import Roadmap, World

STEPS = 2000
DT_S = 0.1
COMMAND = (0.5, 0.3)
CIRCLES = [(3.0, 7.0, 0.5), (7.0, 3.0, 0.6), (6.5, 7.5, 0.4)]
BOXES = [(2.0, 3.0, 1.0, 0.6), (5.0, 5.0, 0.8, 0.8), (8.0, 6.0, 0.5, 1.2)]  # x, y, w, h


def small_scene() -> World:
    """IR-SIM's kind of scene as an albot2d World."""
    room = shapely.box(0.0, 0.0, 10.0, 10.0)
    clutter = tuple(shapely.Point(x, y).buffer(r, quad_segs=6) for x, y, r in CIRCLES) + tuple(
        shapely.box(x - w / 2, y - h / 2, x + w / 2, y + h / 2) for x, y, w, h in BOXES
    )
    free = room
    for c in clutter:
        free = free.difference(c)
    return World(
        walls=polygon_ring_segments(np.asarray(room.exterior.coords)),
        clutter=clutter,
        free_space=free,
        bounds=(0.0, 0.0, 10.0, 10.0),
        start=Pose(1.0, 1.0, 0.0),
        roadmap=Roadmap(np.array([[1.0, 1.0], [9.0, 1.0]]), np.array([[0, 1]])),
        kind="irsim-scene",
        seed=0,
    )


SCENES: dict[str, Callable[[], World]] = {
    "office": lambda: generate("office", seed=0),
    "irsim_scene": small_scene,
}


def _per_step(benchmark, step: Callable[[], object], steps: int) -> int:
    """Time ``steps`` single steps (each a round, so the stats are per step and the
    ratios between simulators are per step), and their process CPU time; returns how many
    steps ran (untimed, as CI runs it, pytest-benchmark calls ``step`` once)."""
    for _ in range(10):
        step()  # warm up (compiled kernels, caches)
    t0 = time.process_time()
    benchmark.pedantic(step, rounds=steps, iterations=1)
    cpu = time.process_time() - t0
    if benchmark.disabled:  # untimed: one step ran, there is nothing to time
        return 10 + 1
    benchmark.extra_info["steps_per_cpu_s"] = round(steps / cpu)
    benchmark.extra_info["steps_per_s_median"] = round(1.0 / benchmark.stats.stats.median)
    return 10 + steps


@pytest.mark.parametrize("odometry", ["none", "pioneer3dx"])
@pytest.mark.parametrize("scene", list(SCENES))
def test_albot2d_step_with_scan(benchmark, scene: str, odometry: str) -> None:
    """The default laser noise (SICK LMS200-like); perfect or ``pioneer3dx`` odometry."""
    benchmark.group = f"step + 181-beam scan, {scene}"
    world = SCENES[scene]()
    sim = Simulator(
        world,
        seed=0,
        laser=LaserParams(n_beams=181, max_range_m=30.0),
        odometry=noise_preset(odometry),
    )
    command = VelocityCommand(*COMMAND)
    sim.reset()
    scans = 0

    def step() -> None:
        nonlocal scans
        scans += sim.step(command, DT_S).scan is not None

    ran = _per_step(benchmark, step, STEPS)
    assert scans == ran  # a scan every step


def _irsim_world(path: Path, world: World) -> Path:
    import yaml

    x0, y0, x1, y1 = world.bounds
    start = world.start
    if world.kind == "irsim-scene":
        obstacles = [
            {"shape": {"name": "circle", "radius": r}, "state": [x, y, 0.0]} for x, y, r in CIRCLES
        ] + [
            {"shape": {"name": "rectangle", "length": w, "width": h}, "state": [x, y, 0.0]}
            for x, y, w, h in BOXES
        ]
        segments = world.walls
    else:
        obstacles = []
        segments = world.obstacle_segments
    obstacles += [
        {
            "shape": {"name": "linestring", "vertices": [s[:2].tolist(), s[2:].tolist()]},
            "state": [0.0, 0.0, 0.0],
        }
        for s in np.asarray(segments, dtype=float)
    ]
    spec = {
        "world": {
            "height": float(y1 - y0),
            "width": float(x1 - x0),
            "step_time": DT_S,
            "sample_time": DT_S,
            "offset": [float(x0), float(y0)],
            "collision_mode": "stop",
            "control_mode": "auto",
        },
        "robot": [
            {
                "kinematics": {"name": "diff"},
                "shape": {"name": "circle", "radius": 0.25},
                "state": [start.x, start.y, start.theta],
                "vel_max": [1.2, math.radians(300.0)],
                "sensors": [
                    {
                        "name": "lidar2d",
                        "range_min": 0.05,
                        "range_max": 30.0,
                        "angle_range": math.pi,
                        "number": 181,
                        "noise": False,
                    }
                ],
            }
        ],
        "obstacle": obstacles,
    }
    path.write_text(yaml.safe_dump(spec), encoding="utf-8")
    return path


@pytest.mark.parametrize("scene", list(SCENES))
def test_irsim_step_with_lidar(benchmark, scene: str, tmp_path: Path) -> None:
    irsim = pytest.importorskip(
        "irsim", reason="ir-sim is not installed (pip install ir-sim to compare)"
    )
    benchmark.group = f"step + 181-beam scan, {scene}"
    world = SCENES[scene]()
    yaml_path = _irsim_world(tmp_path / f"{scene}.yaml", world)
    # IR-SIM is some hundred times slower in the office: fewer steps keep the run short.
    steps = 100 if scene == "office" else 500
    env = irsim.make(str(yaml_path), headless=True, log_level="ERROR")
    action = list(COMMAND)
    _per_step(benchmark, lambda: env.step(action), steps)
    ranges = np.asarray(env.robot.get_lidar_scan()["ranges"])
    assert len(ranges) == 181
