"""A long drive over generated worlds with moving obstacles, the robot's clearance checked at
every physics sub-step (shared by ``tests/test_dynamics_drive.py`` and
``benchmarks/test_obstacles.py``).

Each world is generated from its own seed (kinds in turn) with many moving obstacles, plus
``route_boxes`` boxes put on the tour itself (the generator keeps its boxes off the
roadmap), so the robot pushes boxes along, into walls, people and each other; the robot
drives a loop tour with the given profile while ``ClearanceChecker`` receives the
true robot pose and the obstacles' true poses after every physics sub-step (the
simulator's ``physics_observer``) and at every frame. Worlds follow one another until the
requested number of driving steps (turns and moves of the profile) is reached.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from albot2d.evaluation.checks.simulator import ClearanceChecker
from albot2d.geometry import Pose
from albot2d.sim.laser import LaserNoise
from albot2d.sim.simulator import Simulator
from worldgen.generate import generate
from worldgen.tours import make_tour
from worldgen.world import DynamicObstacle, Tour, World

__all__ = ["DriveStats", "drive_with_moving_obstacles", "with_route_boxes"]

KINDS = ("rooms", "corridors", "open", "office", "mixed")
_MIN_SIZE_M = {"office": 24.0, "mixed": 32.0}


@dataclass
class DriveStats:
    """What a drive saw: counts, the deepest overlaps (m; < 0: a gap) and violations."""

    worlds: int = 0
    steps: int = 0
    substeps: int = 0
    frames: int = 0
    collided_frames: int = 0
    moving_obstacles: int = 0
    pushed_boxes: int = 0  # boxes that ended more than 5 cm from where they started
    people_walked: int = 0  # people who moved more than 1 m from where they started
    max_static_overlap_m: float = -np.inf
    max_moving_overlap_m: float = -np.inf
    static_overlaps: int = 0
    moving_overlaps: int = 0
    violations: list[str] = field(default_factory=list)
    world_specs: list[tuple[str, int]] = field(default_factory=list)

    def absorb(self, checker: ClearanceChecker) -> None:
        self.max_static_overlap_m = max(self.max_static_overlap_m, checker.max_static_overlap_m)
        self.max_moving_overlap_m = max(self.max_moving_overlap_m, checker.max_moving_overlap_m)
        self.static_overlaps += checker.static_overlaps
        self.moving_overlaps += checker.moving_overlaps
        self.violations += checker.violations


def drive_with_moving_obstacles(
    steps: int,
    *,
    seed: int = 0,
    obstacles: int = 12,
    size_m: float = 20.0,
    profile: str = "dataset1",
    tour_m: float = 40.0,
    tolerance_m: float = 0.01,
    route_boxes: int = 4,
    kinds: tuple[str, ...] = KINDS,
) -> DriveStats:
    """Drive generated worlds (``obstacles`` moving obstacles each) for ``steps`` steps."""
    stats = DriveStats()
    k = 0
    while stats.steps < steps:
        kind = kinds[k % len(kinds)]
        size = max(size_m, _MIN_SIZE_M.get(kind, 0.0))
        world_seed = seed * 100_003 + k
        k += 1
        world = generate(
            kind, seed=world_seed, width_m=size, height_m=size, dynamic_obstacles=obstacles
        )
        tour = make_tour(world, np.random.default_rng(world_seed), kind="loop", min_length_m=tour_m)
        world = with_route_boxes(world, tour, route_boxes, np.random.default_rng(world_seed))
        checker = ClearanceChecker.for_world(
            world, moving_tolerance_m=tolerance_m, raise_at_once=False
        )
        substeps = 0
        first: list[np.ndarray] = []
        last: list[np.ndarray] = []

        def observe(
            pose: Pose,
            poses: np.ndarray,
            checker: ClearanceChecker = checker,
            first: list[np.ndarray] = first,
            last: list[np.ndarray] = last,
        ) -> None:
            nonlocal substeps
            substeps += 1
            checker.add(pose, poses)
            if not first:
                first.append(poses.copy())
            last[:] = [poses]

        sim = Simulator(
            world, seed=world_seed, laser_noise=LaserNoise.zero(), physics_observer=observe
        )
        for frame in sim.drive(tour, profile):
            checker.add(frame.true_pose, frame.obstacle_poses)
            stats.frames += 1
            stats.collided_frames += frame.collided
            stats.steps += frame.index > 0
            if stats.steps >= steps:
                break
        checker.finish()
        stats.absorb(checker)
        stats.worlds += 1
        stats.substeps += substeps
        stats.moving_obstacles += len(world.dynamic_obstacles)
        if first:
            moved = np.hypot(*(last[0][:, :2] - first[0][:, :2]).T)
            kind_of = np.array([o.kind for o in world.dynamic_obstacles])
            stats.pushed_boxes += int(((kind_of == "box") & (moved > 0.05)).sum())
            stats.people_walked += int(((kind_of == "person") & (moved > 1.0)).sum())
        stats.world_specs.append((kind, world_seed))
    return stats


_BOX_SIDE_M = 0.4  # half-diagonal 0.28 m: fits on a roadmap edge (clearance ≥ 0.35 m)


def with_route_boxes(world: World, tour: Tour, count: int, rng: np.random.Generator) -> World:
    """``world`` with ``count`` more boxes centred on points of the tour's legs, at least
    1 m from the start and 1 m apart."""
    legs = tour.legs
    lengths = np.hypot(legs[:, 2] - legs[:, 0], legs[:, 3] - legs[:, 1])
    long_legs = np.flatnonzero(lengths > 2.0)
    half = 0.5 * _BOX_SIDE_M
    square = np.array([[-half, -half], [half, -half], [half, half], [-half, half]])
    boxes: list[DynamicObstacle] = []
    start = np.array([world.start.x, world.start.y])
    placed: list[np.ndarray] = []
    for _ in range(8 * count):
        if len(boxes) == count or len(long_legs) == 0:
            break
        x1, y1, x2, y2 = legs[rng.choice(long_legs)]
        t = rng.uniform(0.3, 0.7)
        p = np.array([x1 + t * (x2 - x1), y1 + t * (y2 - y1)])
        if np.hypot(*(p - start)) < 1.0 or any(np.hypot(*(p - q)) < 1.0 for q in placed):
            continue
        placed.append(p)
        boxes.append(
            DynamicObstacle(
                "box",
                square,
                Pose(float(p[0]), float(p[1]), float(rng.uniform(-np.pi, np.pi))),
                mass_kg=float(rng.uniform(5.0, 20.0)),
            )
        )
    return dataclasses.replace(world, dynamic_obstacles=world.dynamic_obstacles + tuple(boxes))
