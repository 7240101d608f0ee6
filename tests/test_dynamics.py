"""Moving obstacles vs the robot: people keep clear, step aside or turn back; pushed boxes never
overlap the robot or what they are pushed into; every limit is named; ClearanceChecker
measures overlaps itself. Real pymunk spaces throughout."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from albot2d.errors import InputError
from albot2d.evaluation.checks.invariants import InvariantError
from albot2d.evaluation.checks.simulator import ClearanceChecker
from albot2d.geometry import Pose
from albot2d.seeding import make_rng
from albot2d.sim.dynamics import MAX_MOVING_OBSTACLES, Dynamics, PhysicsParams
from albot2d.sim.laser import LaserNoise
from albot2d.sim.robot import KinematicRobot, MoveResult
from albot2d.sim.simulator import Simulator
from tests.test_simulator import LOOP, MOVERS, box, person, room_world
from worldgen.space import build_space
from worldgen.world import DynamicObstacle, Tour, World


class Scene:
    """A room world, its space, the robot and the dynamics, every sub-step checked."""

    def __init__(self, world: World, robot_pose: Pose, params: PhysicsParams | None = None) -> None:
        self.world = world
        self.space = build_space(world)
        self.robot = KinematicRobot(self.space, pose=robot_pose)
        self.checker = ClearanceChecker.for_world(
            world, 0.25, moving_tolerance_m=0.0, raise_at_once=False
        )
        self.poses: list[np.ndarray] = []
        self.dyn = Dynamics(world, self.space, make_rng(0), params, observer=self.observe)

    def observe(self, pose: Pose, poses: np.ndarray) -> None:
        self.checker.add(pose, poses)
        self.poses.append(poses)

    def move(self, distance_m: float, duration_s: float) -> MoveResult:
        n, h = self.dyn.substeps(duration_s)
        return self.robot.move(
            distance_m, substeps=n, on_substep=lambda a, b: self.dyn.step(h, self.robot, a, b)
        )

    def finish(self) -> np.ndarray:
        assert self.checker.finish() == []
        return np.array(self.poses)


def test_person_steps_around_a_robot_standing_on_its_path() -> None:
    walk = np.array([[2.0, 1.5], [10.0, 1.5]])
    scene = Scene(room_world((person(walk),)), Pose(6.0, 1.5, 0.0))
    scene.dyn.advance(14.0, scene.robot)
    xs = scene.finish()[:, 0, 0]
    assert xs.max() > 9.0  # got past the robot to the far end of its path
    assert scene.checker.max_moving_overlap_m <= -0.05 + 1e-9  # kept its clearance
    assert scene.robot.pose == Pose(6.0, 1.5, 0.0)


def test_person_who_cannot_step_aside_stops_and_turns_back() -> None:
    walk = np.array([[2.0, 1.5], [10.0, 1.5]])
    params = PhysicsParams(person_max_sidestep_m=0.0, person_speed_jitter=0.0)
    scene = Scene(room_world((person(walk),)), Pose(6.0, 1.5, 0.0), params)
    scene.dyn.advance(12.0, scene.robot)
    xs = scene.finish()[:, 0, 0]
    stop = 6.0 - 0.25 - 0.05 - 0.15  # the robot's edge, the clearance, half the person
    assert xs.max() == pytest.approx(stop, abs=0.06)  # stood just short of the robot
    assert xs[int(np.argmax(xs)) :].min() < stop - 3.0  # then turned back (after its patience)
    assert scene.checker.max_moving_overlap_m <= -0.05 + 1e-9


def test_robot_and_person_heading_for_each_other_never_overlap() -> None:
    walk = np.array([[10.0, 1.5], [2.0, 1.5]])
    scene = Scene(room_world((person(walk, speed=1.4),)), Pose(2.5, 1.5, 0.0))
    result = scene.move(7.0, 7.0 / 0.3)
    scene.finish()
    assert scene.checker.max_moving_overlap_m <= -0.05 + 1e-9
    assert result.distance_m > 3.0  # the person made way at some point


def test_box_pushed_in_the_open_moves_ahead_without_overlap() -> None:
    scene = Scene(room_world((box(4.0, 1.5),)), Pose(1.5, 1.5, 0.0))
    result = scene.move(4.0, 4.0 / 0.3)
    poses = scene.finish()
    assert not result.collided
    assert poses[-1, 0, 0] - 4.0 > 1.9  # pushed along once the robot reached it (x = 3.55)
    gap = poses[-1, 0, 0] - 0.2 - (scene.robot.pose.x + 0.25)
    assert 0.0 <= gap < 0.03  # just ahead of the robot (it slides on a little)
    assert scene.checker.max_moving_overlap_m <= 0.0


@pytest.mark.parametrize("angle", [0.0, 0.3, math.pi / 4])
def test_box_pinned_against_a_wall_stops_the_robot_without_overlap(angle: float) -> None:
    pinned = dataclasses.replace(box(3.0, 1.5), pose=Pose(3.0, 1.5, angle))
    scene = Scene(room_world((pinned,)), Pose(3.0, 2.5, -math.pi / 2))
    result = scene.move(3.0, 10.0)
    poses = scene.finish()
    assert result.collided and result.distance_m < 2.0
    assert scene.checker.max_moving_overlap_m <= 0.0
    assert scene.robot.pose == Pose(3.0, 2.5, -math.pi / 2).compose(result.increment)
    _, y, theta = poses[-1, 0]
    corners = np.array([[-0.2, -0.2], [0.2, -0.2], [0.2, 0.2], [-0.2, 0.2]])
    ys = y + math.sin(theta) * corners[:, 0] + math.cos(theta) * corners[:, 1]
    assert ys.min() >= -PhysicsParams().push_overlap_limit_m  # hardly into the wall (y = 0)


def test_box_squeezed_against_a_person_stops_the_robot() -> None:
    shape = person(np.array([[6.0, 1.5], [6.0, 2.0]])).shape
    standing = DynamicObstacle("person", shape, Pose(6.0, 1.5, 0.0))  # no path: stands
    scene = Scene(room_world((box(4.0, 1.5), standing)), Pose(2.0, 1.5, 0.0))
    result = scene.move(6.0, 20.0)
    scene.finish()
    assert result.collided
    assert scene.checker.max_moving_overlap_m <= 0.0


def test_frames_carry_obstacle_poses_and_runs_repeat_bit_for_bit() -> None:
    world = room_world(MOVERS)

    def run() -> list:
        sim = Simulator(world, seed=3, laser_noise=LaserNoise.zero())
        return list(sim.drive(Tour(LOOP, "loop"), "dataset3"))

    a, b = run(), run()
    assert all(f.obstacle_poses is not None and f.obstacle_poses.shape == (2, 3) for f in a)
    assert not a[-1].obstacle_poses.flags.writeable
    assert all(
        np.array_equal(f.obstacle_poses, g.obstacle_poses) for f, g in zip(a, b, strict=True)
    )
    checker = ClearanceChecker.for_world(world, 0.25, moving_tolerance_m=0.0)
    for f in a:
        checker(f)
    assert checker.finish() == [] and checker.poses_checked == len(a)
    walked = np.ptp(np.array([f.obstacle_poses[0, :2] for f in a]), axis=0)
    assert walked.max() > 1.0


# -- the checker measures overlaps itself --------------------------------------------------


def test_clearance_checker_finds_moving_and_static_overlaps() -> None:
    world = room_world((box(4.0, 4.0),))
    checker = ClearanceChecker.for_world(world, 0.25, raise_at_once=False)
    at = np.array([[4.0, 4.0, 0.3]])
    checker.add(Pose(4.0, 4.0 + 0.2 + 0.25 + 0.02, 0.0), at)  # 2 cm clear of the box
    checker.add(Pose(4.0 + 0.2 + 0.25 - 0.02, 4.0, 0.0), np.array([[4.0, 4.0, 0.0]]))  # 2 cm in
    checker.add(Pose(4.0, 4.0, 0.0), at)  # centre inside: the whole radius and more
    checker.add(Pose(0.1, 4.0, 0.0), np.full((1, 3), np.nan))  # into the wall; box unknown
    messages = checker.finish()
    assert checker.moving_overlaps == 2 and checker.static_overlaps == 1
    assert checker.max_moving_overlap_m == pytest.approx(0.25 + 0.2)
    assert any("dynamic_obstacles[0] (box)" in m and "row 2" in m for m in messages)
    assert any("wall or clutter" in m for m in messages)
    strict = ClearanceChecker.for_world(world, 0.25)
    strict.add(Pose(4.0, 4.0, 0.0), at)
    with pytest.raises(InvariantError, match="robot_clear_of_obstacles"):
        strict.finish()


# -- bounded work: every limit named -------------------------------------------------------


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"speed_m_s": 1e300}, "MAX_OBSTACLE_SPEED_M_S"),
        ({"speed_m_s": math.nan}, "speed_m_s must be finite"),
        ({"mass_kg": 0.0}, "MAX_OBSTACLE_MASS_KG"),
        ({"shape": [[0, 0], [1, 1], [2, 2]]}, "positive area"),
        ({"shape": [[0, 0], [1, 0]]}, "positive area"),
        ({"path": [[0, 0], [math.inf, 0]]}, "path point 1 must be finite"),
        ({"path": np.zeros((10_001, 2))}, "MAX_OBSTACLE_POINTS"),
        ({"kind": "cat"}, "kind must be one of"),
    ],
)
def test_dynamic_obstacle_values_are_checked(changes: dict, message: str) -> None:
    base = person(np.array([[2.0, 7.0], [4.0, 7.0]]))
    fields = {f.name: getattr(base, f.name) for f in dataclasses.fields(base)} | changes
    with pytest.raises(InputError, match=message):
        DynamicObstacle(**fields)


def test_walking_person_on_a_micrometre_path_is_refused_by_name() -> None:
    tiny = person(np.array([[2.0, 7.0], [2.0 + 1e-6, 7.0]]))
    world = room_world((tiny,))
    with pytest.raises(InputError, match=r"dynamic_obstacles\[0\].*MIN_WALK_PATH_M"):
        Dynamics(world, build_space(world), make_rng(0))
    sim = Simulator(world, seed=0)
    with pytest.raises(InputError, match="MIN_WALK_PATH_M"):
        next(sim.drive(Tour(LOOP, "loop"), "dataset3"))


def test_too_many_moving_obstacles_are_refused_by_name() -> None:
    crowd = (box(8.0, 6.5),) * (MAX_MOVING_OBSTACLES + 1)
    world = room_world(crowd)
    with pytest.raises(InputError, match="MAX_MOVING_OBSTACLES"):
        Dynamics(world, build_space(world, include_dynamic=False), make_rng(0))


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("step_s", 1e-6),
        ("step_s", 1.0),
        ("person_clearance_m", -0.1),
        ("push_overlap_limit_m", 0.0),
        ("contact_slop_m", 0.5),
        ("person_patience_s", math.inf),
    ],
)
def test_physics_limits_are_named(field: str, value: float) -> None:
    with pytest.raises(InputError, match=f"PhysicsParams.{field}"):
        PhysicsParams(**{field: value})


def test_fastest_person_on_shortest_path_stays_bounded_and_clear() -> None:
    from worldgen.world import MAX_OBSTACLE_SPEED_M_S, MIN_WALK_PATH_M

    walk = np.array([[3.0, 1.5], [3.0 + MIN_WALK_PATH_M, 1.5]])
    runner = person(walk, speed=MAX_OBSTACLE_SPEED_M_S)
    scene = Scene(
        room_world((runner,)),
        Pose(3.5, 1.5, 0.0),
        PhysicsParams(step_s=0.1, person_speed_jitter=0.9),
    )
    scene.dyn.advance(30.0, scene.robot)  # 300 steps, each at most a few turns
    scene.finish()
    assert scene.checker.max_moving_overlap_m < 0.0
