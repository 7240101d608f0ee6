"""Simulator: frames, odometry vs truth, profiles, determinism, streams, laser, dynamics."""

from __future__ import annotations

import dataclasses
import hashlib
import itertools
import math
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from albot2d.errors import InputError
from albot2d.frames import Frame
from albot2d.geometry import Pose, point_segment_distance, polygon_ring_segments
from albot2d.seeding import make_rng
from albot2d.sim.driving import PROFILES
from albot2d.sim.dynamics import Dynamics, PhysicsParams
from albot2d.sim.laser import LaserNoise
from albot2d.sim.odometry import NOISE_PRESETS, OdometryNoise
from albot2d.sim.robot import KinematicRobot
from albot2d.sim.simulator import Simulator
from tests.strategies import examples
from worldgen.space import build_space
from worldgen.tours import make_tour
from worldgen.world import DynamicObstacle, Roadmap, Tour, World

ROOT = Path(__file__).resolve().parents[1]
LOOP = np.array([[1.5, 1.5], [10.5, 1.5], [10.5, 6.5], [1.5, 6.5], [1.5, 1.5]])


def person(path: np.ndarray, speed: float = 1.0) -> DynamicObstacle:
    shape = np.array([[0.15, 0.2], [-0.15, 0.2], [-0.15, -0.2], [0.15, -0.2]])
    return DynamicObstacle("person", shape, Pose(*path[0], 0.0), path=path, speed_m_s=speed)


def box(x: float, y: float) -> DynamicObstacle:
    shape = np.array([[-0.2, -0.2], [0.2, -0.2], [0.2, 0.2], [-0.2, 0.2]])
    return DynamicObstacle("box", shape, Pose(x, y, 0.0), mass_kg=5.0)


MOVERS = (person(np.array([[3.0, 0.5], [3.0, 3.0]]), speed=0.5), box(8.0, 6.5))


def room_world(dynamic: tuple[DynamicObstacle, ...] = ()) -> World:
    """A 12 x 8 m room with a pillar in the middle and a loop around it."""
    room = shapely.box(0.0, 0.0, 12.0, 8.0)
    pillar = shapely.box(5.0, 3.0, 7.0, 5.0)
    walls = polygon_ring_segments(np.asarray(room.exterior.coords))
    edges = np.array([[0, 1], [1, 2], [2, 3], [0, 3]])
    return World(
        walls=walls,
        clutter=(pillar,),
        free_space=room.difference(pillar),
        bounds=(0.0, 0.0, 12.0, 8.0),
        start=Pose(1.5, 1.5, 0.0),
        roadmap=Roadmap(LOOP[:4], edges),
        kind="test-room",
        seed=0,
        dynamic_obstacles=dynamic,
    )


def drive(profile: str = "dataset1", *, movers: bool = False, **params: object) -> list[Frame]:
    world = room_world(MOVERS if movers else ())
    sim = Simulator(world, seed=params.pop("seed", 7), **params)  # type: ignore[arg-type]
    return list(sim.drive(Tour(LOOP, "loop"), profile))


def digest(frames: list[Frame]) -> str:
    h = hashlib.sha256()
    for f in frames:
        h.update(np.array([f.index, f.timestamp, f.collided], float).tobytes())
        for pose in (f.true_pose, f.odom_pose, f.odom_increment):
            h.update(pose.as_array().tobytes())
        h.update(f.scan.ranges.tobytes() + f.scan.valid.tobytes() + f.scan.angles.tobytes())
    return h.hexdigest()


def test_zero_noise_odometry_equals_truth_and_tour_closes() -> None:
    frames = drive("dataset1")
    assert [f.index for f in frames] == list(range(len(frames)))
    assert all(f.odom_pose == f.true_pose for f in frames)
    assert frames[0].odom_increment == Pose() and frames[0].true_pose == Pose(1.5, 1.5, 0.0)
    assert frames[-1].true_pose.distance_to(Pose(1.5, 1.5)) < 1e-6
    assert not any(f.collided for f in frames)
    # 28 m of loop in 10 cm steps, three 90° left turns in 1° steps (the last leg ends home).
    assert len(frames) == 1 + 280 + 3 * 90


@pytest.mark.parametrize("along_motion", [False, True])
def test_dataset2_adds_exactly_10cm_or_1deg_per_step_and_keeps_the_true_motion(
    along_motion: bool,
) -> None:
    # The loop driven both ways round: left turns, then (reversed) right turns.
    tour = Tour(np.vstack([LOOP, LOOP[::-1][1:]]), "loop")
    d2_profile = dataclasses.replace(PROFILES["dataset2"], induced_along_motion=along_motion)
    d1 = list(Simulator(room_world(), seed=7).drive(tour, "dataset1"))
    d2 = list(Simulator(room_world(), seed=7).drive(tour, d2_profile))
    assert [f.true_pose for f in d1] == [f.true_pose for f in d2]
    turns = set()
    for prev, f in itertools.pairwise(d2):
        inc = f.odom_increment
        true_inc = prev.true_pose.between(f.true_pose)
        if true_inc.x > 1e-9:  # a move step
            assert inc.y == 0.0 and inc.theta == 0.0
            assert inc.x - true_inc.x == pytest.approx(0.10, abs=1e-9)
        else:  # a turn step
            assert inc.x == 0.0 and inc.y == 0.0
            extra = math.radians(1.0)
            if along_motion and true_inc.theta < 0.0:
                extra = -extra
            assert inc.theta - true_inc.theta == pytest.approx(extra, abs=1e-9)
            turns.add(true_inc.theta > 0.0)
    assert turns == {False, True}
    assert d2[-1].odom_pose.distance_to(d2[-1].true_pose) > 1.0


def test_dataset3_views_are_at_most_1m_or_10deg_apart() -> None:
    frames = drive("dataset3")
    for prev, f in itertools.pairwise(frames):
        inc = prev.true_pose.between(f.true_pose)
        assert math.hypot(inc.x, inc.y) <= 1.0 + 1e-9
        assert abs(inc.theta) <= math.radians(10.0) + 1e-9
    assert len(frames) == 1 + 28 + 3 * 9


def test_start_stop_views_after_every_move_and_turn_instruction() -> None:
    frames = drive("start_stop")
    moved = np.array(
        [prev.true_pose.distance_to(f.true_pose) for prev, f in itertools.pairwise(frames)]
    )
    turned = np.degrees(
        [abs(prev.true_pose.between(f.true_pose).theta) for prev, f in itertools.pairwise(frames)]
    )
    is_move = moved > 1e-9
    assert (turned[~is_move] > 10.0).all() and (turned <= 60.0 + 1e-6).all()
    assert (~is_move).any()  # the corners are turn-only views
    assert moved.max() <= 3.0 + 1e-9 and moved[is_move].mean() > 2.0
    assert (np.diff([f.timestamp for f in frames]) > 1.0).all()


def test_start_stop_v1_views_about_3m_apart_with_turns_merged() -> None:
    frames = drive("start_stop_v1")
    steps = [prev.true_pose.distance_to(f.true_pose) for prev, f in itertools.pairwise(frames)]
    assert max(steps) <= 3.0 + 1e-9 and np.mean(steps) > 2.0
    assert min(steps) > 1.0  # every view follows a move: no turn-only views
    gaps = np.diff([f.timestamp for f in frames])
    assert (gaps > 1.0).all()


def test_timestamps_follow_nominal_speeds() -> None:
    frames = drive("dataset1")
    t = np.array([f.timestamp for f in frames])
    dt = np.diff(t)
    moved = np.array([a.true_pose.distance_to(b.true_pose) for a, b in itertools.pairwise(frames)])
    is_move = moved > 1e-9
    assert dt[is_move] == pytest.approx(moved[is_move] / 0.3)
    assert dt[~is_move] == pytest.approx(np.full((~is_move).sum(), 1.0 / 30.0))
    assert all(f.scan.timestamp == f.timestamp for f in frames)


def test_every_valid_hit_lies_on_an_obstacle() -> None:
    world = room_world()
    frames = drive("dataset3", laser_noise=LaserNoise.zero())
    for f in frames:
        pts = f.true_pose.transform_points(f.scan.points())
        assert len(pts) > 0
        assert point_segment_distance(pts, world.obstacle_segments).min(axis=1).max() < 1e-9


def test_noisy_run_is_deterministic_in_process() -> None:
    kw = {"odometry": NOISE_PRESETS["typical"], "movers": True}
    assert digest(drive("dataset3", **kw)) == digest(drive("dataset3", **kw))
    assert digest(drive("dataset3", seed=8, **kw)) != digest(drive("dataset3", **kw))


def test_noisy_run_is_deterministic_across_processes() -> None:
    script = textwrap.dedent("""
        import sys
        sys.path.insert(0, sys.argv[1])
        from tests.test_simulator import digest, drive
        from albot2d.sim.odometry import NOISE_PRESETS
        print(digest(drive("dataset3", movers=True, odometry=NOISE_PRESETS["typical"])))
    """)
    out = subprocess.run(
        [sys.executable, "-c", script, str(ROOT)],
        capture_output=True,
        text=True,
        check=True,
        cwd=ROOT,
    )
    here = drive("dataset3", movers=True, odometry=NOISE_PRESETS["typical"])
    assert out.stdout.strip() == digest(here)


def test_noise_streams_are_independent() -> None:
    typical = NOISE_PRESETS["typical"]
    noisy = drive("dataset3", odometry=typical)
    exact_odom = drive("dataset3", odometry=OdometryNoise())
    exact_laser = drive("dataset3", odometry=typical, laser_noise=LaserNoise.zero())
    for a, b, c in zip(noisy, exact_odom, exact_laser, strict=True):
        assert np.array_equal(a.scan.ranges, b.scan.ranges)  # laser draws unchanged
        assert a.odom_pose == c.odom_pose  # odometry draws unchanged
    assert any(a.odom_pose != a.true_pose for a in noisy)
    assert any(
        not np.array_equal(a.scan.ranges, c.scan.ranges)
        for a, c in zip(noisy, exact_laser, strict=True)
    )


def test_bad_profile_fails_before_the_first_frame() -> None:
    sim = Simulator(room_world(), seed=1)
    with pytest.raises(InputError, match="valid: dataset1"):
        sim.drive(Tour(LOOP, "loop"), "fast")


def test_robot_pushes_a_box_and_people_walk_back_and_forth() -> None:
    walk = np.array([[2.0, 7.0], [4.0, 7.0]])
    world = room_world((box(4.0, 1.5), person(walk)))
    space = build_space(world)
    robot = KinematicRobot(space, pose=Pose(1.5, 1.5, 0.0))
    dyn = Dynamics(world, space, make_rng(0), PhysicsParams(person_speed_jitter=0.0))
    n, h = dyn.substeps(10.0)
    result = robot.move(3.0, substeps=n, on_substep=lambda a, b: dyn.step(h, robot, a, b))
    assert not result.collided  # boxes do not block: they get pushed
    outline = dyn.outlines()
    assert outline.shape == (8, 4)
    box_x = outline[:4, [0, 2]].mean()
    # Pushed ahead of the robot (now at x = 4.5), touching it up to pymunk's contact slop.
    assert box_x - 0.2 == pytest.approx(robot.pose.x + robot.radius_m, abs=0.02)
    # After 10 s at 1 m/s on a 2 m path the person has turned back twice: at x = 2 + 2.
    person_x = outline[4:, [0, 2]].mean()
    assert person_x == pytest.approx(4.0, abs=0.05)


def test_laser_sees_moving_obstacles_and_run_stays_collision_free() -> None:
    world = room_world(MOVERS)
    frames = list(
        Simulator(world, seed=2, laser_noise=LaserNoise.zero()).drive(
            Tour(LOOP, "loop"), "dataset3"
        )
    )
    static = world.obstacle_segments
    off_static = 0
    for f in frames:
        pts = f.true_pose.transform_points(f.scan.points())
        off_static += int((point_segment_distance(pts, static).min(axis=1) > 1e-6).sum())
        d = point_segment_distance([[f.true_pose.x, f.true_pose.y]], static).min()
        assert d >= 0.25 - 1e-9
    assert off_static > 0  # some beams hit the person or the box


@pytest.mark.parametrize(("kind", "seed"), [("corridors", 5), ("office", 2)])
def test_follows_a_generated_loop_tour_back_to_its_start(kind: str, seed: int) -> None:
    from worldgen.generate import generate

    world = generate(kind, seed=seed)
    tour = make_tour(world, make_rng(0), kind="loop", min_length_m=30.0)
    sim = Simulator(world, seed=1, laser_noise=LaserNoise.zero())
    frames = list(sim.drive(tour, "dataset1"))
    assert not any(f.collided for f in frames)
    assert frames[-1].true_pose.distance_to(world.start) < 0.03
    xy = np.array([[f.true_pose.x, f.true_pose.y] for f in frames])
    clearance = point_segment_distance(xy, world.obstacle_segments).min()
    assert clearance >= world.robot_radius_m - 1e-9
    travelled = sum(a.true_pose.distance_to(b.true_pose) for a, b in itertools.pairwise(frames))
    assert travelled == pytest.approx(tour.length_m, rel=1e-6)


def test_person_starts_at_its_pose_on_the_path_and_faces_its_way() -> None:
    walk = np.array([[2.0, 7.0], [4.0, 7.0], [4.0, 5.0]])
    mover = dataclasses.replace(person(walk), pose=Pose(3.0, 7.2, 0.0))
    world = room_world((mover,))
    space = build_space(world)
    robot = KinematicRobot(space, pose=Pose(1.5, 1.5, 0.0))
    dyn = Dynamics(world, space, make_rng(0), PhysicsParams(person_speed_jitter=0.0))
    centre = dyn.outlines().reshape(-1, 2).mean(axis=0)
    assert centre == pytest.approx([3.0, 7.0], abs=1e-9)
    dyn.advance(1.5, robot)  # 1 m to the corner, then 0.5 m down
    centre = dyn.outlines().reshape(-1, 2).mean(axis=0)
    assert centre == pytest.approx([4.0, 6.5], abs=1e-6)
    assert robot.pose == Pose(1.5, 1.5, 0.0)


@pytest.mark.parametrize(
    ("field", "value"),
    [("step_s", 0.0), ("velocity_retained_per_s", 1.5), ("person_speed_jitter", 1.0)],
)
def test_physics_params_validated(field: str, value: float) -> None:
    with pytest.raises(InputError, match=field):
        PhysicsParams(**{field: value})


@settings(max_examples=examples(10))
@given(
    points=st.lists(st.tuples(st.floats(0.3, 11.7), st.floats(0.3, 7.7)), min_size=1, max_size=5),
    profile=st.sampled_from(["dataset3", "start_stop"]),
    seed=st.integers(0, 2**32),
)
def test_any_tour_gives_valid_frames(points: list, profile: str, seed: int) -> None:
    """Waypoints anywhere (legs may cross the pillar, points may be unreachable)."""
    world = room_world(MOVERS)
    sim = Simulator(world, seed=seed, laser_noise=LaserNoise.zero())
    frames = list(sim.drive(np.array(points), profile))
    assert [f.index for f in frames] == list(range(len(frames)))
    assert np.all(np.diff([f.timestamp for f in frames]) >= 0.0)
    xy = np.array([[f.true_pose.x, f.true_pose.y] for f in frames])
    assert point_segment_distance(xy, world.obstacle_segments).min() >= 0.25 - 1e-9
    assert all(f.odom_pose == f.true_pose for f in frames)


@pytest.mark.parametrize("lookahead", [2, 7, 10_000])
def test_lookahead_yields_the_same_frames(lookahead: int) -> None:
    """Frames simulated a batch ahead are the frames of a frame-at-a-time drive, bit for bit
    (moving obstacles and noise included), and a consumer may stop inside a batch."""
    world = room_world(MOVERS)
    sim = Simulator(world, seed=7, odometry=NOISE_PRESETS["typical"])
    want = list(sim.drive(Tour(LOOP, "loop"), "dataset1"))
    got = list(sim.drive(Tour(LOOP, "loop"), "dataset1", lookahead=lookahead))
    assert len(got) == len(want) > 10 and digest(got) == digest(want)
    head = list(itertools.islice(sim.drive(Tour(LOOP, "loop"), "dataset1", lookahead=lookahead), 5))
    assert digest(head) == digest(want[:5])


@pytest.mark.parametrize("bad", [0, -3, 2.0, True, "8"])
def test_lookahead_must_be_a_positive_integer(bad: object) -> None:
    sim = Simulator(room_world(), seed=7)
    with pytest.raises(InputError, match="lookahead must be an integer >= 1"):
        sim.drive(Tour(LOOP, "loop"), "dataset1", lookahead=bad)  # type: ignore[arg-type]
