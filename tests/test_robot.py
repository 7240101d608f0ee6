"""KinematicRobot: exact contact, no penetration, commands, on real pymunk spaces."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pymunk
import pytest
import shapely
from hypothesis import example, given
from hypothesis import strategies as st
from shapely import affinity

from albot2d.errors import InputError
from albot2d.geometry import Pose, point_segment_distance, polygon_ring_segments
from albot2d.sim.robot import KinematicRobot, MoveResult, RobotParams

R = 0.25


class Room:
    """A hand-made world: a rectangular room, interior walls and convex clutter."""

    def __init__(self, width: float, height: float, walls: list, clutter: list) -> None:
        corners = [(0, 0), (width, 0), (width, height), (0, height)]
        outer = polygon_ring_segments(np.array(corners, float))
        self.walls = np.vstack([outer, np.asarray(walls, float).reshape(-1, 4)])
        self.clutter = [p for p in clutter if p.area > 0]
        room = shapely.box(0, 0, width, height)
        self.free_space = room.difference(shapely.union_all(self.clutter)) if clutter else room
        rings = [polygon_ring_segments(np.asarray(p.exterior.coords)) for p in self.clutter]
        self.segments = np.vstack([self.walls, *rings])

    def space(self) -> pymunk.Space:
        space = pymunk.Space()
        for x1, y1, x2, y2 in self.walls.tolist():
            space.add(pymunk.Segment(space.static_body, (x1, y1), (x2, y2), 0.0))
        for poly in self.clutter:
            verts = list(poly.exterior.coords)[:-1]
            space.add(pymunk.Poly(space.static_body, verts, radius=0.0))
        return space

    def clearance(self, pose: Pose) -> float:
        return float(point_segment_distance([[pose.x, pose.y]], self.segments).min())

    def free_start(self, radius: float) -> Pose | None:
        margin = radius + 1e-3
        xs = np.linspace(margin, self.free_space.bounds[2] - margin, 15)
        ys = np.linspace(margin, self.free_space.bounds[3] - margin, 15)
        for x in xs:
            for y in ys:
                pose = Pose(float(x), float(y), 0.0)
                if self.clearance(pose) >= margin and self.free_space.contains(shapely.Point(x, y)):
                    return pose
        return None


@st.composite
def rooms(draw: st.DrawFn) -> Room:
    width = draw(st.floats(2.0, 8.0))
    height = draw(st.floats(2.0, 8.0))
    unit = st.floats(0.0, 1.0)
    clutter = []
    for _ in range(draw(st.integers(0, 6))):
        cx, cy = draw(unit) * width, draw(unit) * height
        w, h = draw(st.floats(0.05, 1.5)), draw(st.floats(0.05, 1.5))
        box = shapely.box(cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2)
        clutter.append(affinity.rotate(box, draw(st.floats(0, 180))))
    walls = []
    for _ in range(draw(st.integers(0, 4))):
        walls.append(
            [draw(unit) * width, draw(unit) * height, draw(unit) * width, draw(unit) * height]
        )
    return Room(width, height, walls, clutter)


commands = st.one_of(
    st.tuples(st.just("turn"), st.floats(-4.0, 4.0)),
    st.tuples(st.just("move"), st.floats(-6.0, 6.0)),
    st.tuples(st.just("drive"), st.floats(-1.0, 1.0), st.floats(-2.0, 2.0), st.floats(0.0, 3.0)),
)


def run(robot: KinematicRobot, cmd: tuple) -> MoveResult:
    if cmd[0] == "turn":
        return robot.turn(cmd[1])
    if cmd[0] == "move":
        return robot.move(cmd[1])
    return robot.drive(cmd[1], cmd[2], cmd[3])


@given(
    room=rooms(),
    cmds=st.lists(commands, min_size=1, max_size=40),
    skin=st.sampled_from([1e-6, 0.0, 1e-3]),
)
@example(  # a long move straight into a wall corner
    room=Room(3.0, 3.0, [], []),
    cmds=[("turn", math.pi / 4), ("move", 10.0), ("move", 1.0)],
    skin=1e-6,
)
@example(  # touching a wall near its end: chipmunk's swept query missed it (tunnelled)
    room=Room(2.0, 2.827086579432014, [], []),
    cmds=[("turn", -1.0), ("move", 1.0), ("turn", 2.0), ("move", -1.0)],
    skin=0.0,
)
def test_never_overlaps_obstacles_nor_leaves_free_space(
    room: Room, cmds: list, skin: float
) -> None:
    start = room.free_start(R)
    if start is None:
        return
    robot = KinematicRobot(room.space(), RobotParams(radius_m=R, contact_skin_m=skin), start)
    for cmd in cmds:
        result = run(robot, cmd)
        assert result.pose == robot.pose
        assert room.clearance(robot.pose) >= R - 1e-9, cmd
        assert room.free_space.contains(shapely.Point(robot.pose.x, robot.pose.y)), cmd


def test_blocked_move_stops_at_contact_and_reports_collision() -> None:
    room = Room(4.0, 2.0, [], [])
    params = RobotParams(radius_m=R, contact_skin_m=1e-6)
    robot = KinematicRobot(room.space(), params, Pose(1.0, 1.0, 0.0))
    assert robot.clearance_m() == pytest.approx(1.0 - R)
    assert robot.clearance_m(max_distance_m=0.5) == math.inf
    result = robot.move(10.0)
    assert result.collided
    assert result.pose.x == pytest.approx(4.0 - R - 1e-6, abs=1e-9)
    assert robot.clearance_m() == pytest.approx(1e-6, abs=1e-9)
    assert result.distance_m == pytest.approx(result.pose.x - 1.0, abs=1e-12)
    assert result.increment == Pose(result.distance_m, 0.0, 0.0)
    # Pushing on into the wall moves nothing; backing off is free.
    again = robot.move(0.5)
    assert again.collided and again.distance_m == pytest.approx(0.0, abs=1e-9)
    back = robot.move(-1.0)
    assert not back.collided and back.distance_m == 1.0


def test_touching_a_wall_end_then_backing_into_it_is_blocked() -> None:
    room = Room(2.0, 2.827086579432014, [], [])
    start = Pose(0.25000000000000006, 0.251, 0.0)
    robot = KinematicRobot(room.space(), RobotParams(contact_skin_m=0.0), start)
    result = robot.move(-1.0)
    assert result.collided and result.distance_m == 0.0
    assert robot.move(1.0).distance_m == 1.0


def test_free_move_is_exact_composition() -> None:
    room = Room(10.0, 10.0, [], [])
    start = Pose(2.0, 3.0, 0.3)
    robot = KinematicRobot(room.space(), pose=start)
    result = robot.move(2.5)
    assert not result.collided
    assert result.pose == start.compose(Pose(2.5, 0.0, 0.0))
    assert result.increment == Pose(2.5, 0.0, 0.0)


def test_turn_never_collides_even_when_touching() -> None:
    room = Room(2.0, 2.0, [], [])
    robot = KinematicRobot(room.space(), pose=Pose(1.0, 1.0, 0.0))
    robot.move(5.0)
    for angle in (0.5, 2.0, -3.0):
        result = robot.turn(angle)
        assert not result.collided and result.turned_rad == angle and result.distance_m == 0.0


def test_sliding_along_a_wall_while_touching_is_not_blocked() -> None:
    room = Room(6.0, 3.0, [], [shapely.box(2.0, 0.0, 6.0, 1.0)])
    robot = KinematicRobot(room.space(), pose=Pose(1.0, 1.0 + R + 1e-12, 0.0))
    result = robot.move(3.0)
    assert not result.collided and result.distance_m == 3.0
    up = robot.move(0.0)
    assert up.distance_m == 0.0 and not up.collided


def test_drive_follows_exact_arc_endpoint() -> None:
    room = Room(20.0, 20.0, [], [])
    start = Pose(10.0, 10.0, 0.0)
    robot = KinematicRobot(room.space(), RobotParams(max_substep_s=0.1), start)
    v, omega, dt = 0.5, 0.4, 3.0
    result = robot.drive(v, omega, dt)
    radius = v / omega
    expected = Pose(
        10.0 + radius * math.sin(omega * dt),
        10.0 + radius * (1.0 - math.cos(omega * dt)),
        omega * dt,
    )
    assert result.pose.x == pytest.approx(expected.x, abs=1e-9)
    assert result.pose.y == pytest.approx(expected.y, abs=1e-9)
    assert result.pose.theta == pytest.approx(expected.theta, abs=1e-12)
    assert result.distance_m == pytest.approx(v * dt)
    assert result.turned_rad == pytest.approx(omega * dt)
    assert start.compose(result.increment) == result.pose


def test_drive_into_wall_collides() -> None:
    room = Room(3.0, 3.0, [], [])
    robot = KinematicRobot(room.space(), pose=Pose(1.5, 1.5, 0.0))
    result = robot.drive(1.0, 0.1, 5.0)
    assert result.collided and result.distance_m < 5.0
    assert room.clearance(result.pose) >= R - 1e-9


def test_dynamic_bodies_do_not_block_but_kinematic_ones_do() -> None:
    room = Room(10.0, 4.0, [], [])
    space = room.space()
    box = pymunk.Body(10.0, 1.0)
    box.position = (4.0, 2.0)
    space.add(box, pymunk.Poly.create_box(box, (0.5, 0.5)))
    person = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
    person.position = (7.0, 2.0)
    space.add(person, pymunk.Circle(person, 0.2))
    robot = KinematicRobot(space, pose=Pose(1.0, 2.0, 0.0))
    result = robot.move(8.0)
    assert result.collided
    assert result.pose.x == pytest.approx(7.0 - 0.2 - R, abs=1e-5)


def test_person_overlapping_robot_lets_it_back_away_only() -> None:
    space = Room(10.0, 4.0, [], []).space()
    person = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
    person.position = (5.2, 2.0)
    space.add(person, pymunk.Poly.create_box(person, (0.3, 0.3)))
    robot = KinematicRobot(space, pose=Pose(5.0, 2.0, 0.0))
    assert robot.move(0.5).distance_m == pytest.approx(0.0, abs=1e-9)
    assert robot.move(-1.0).distance_m == 1.0


@pytest.mark.parametrize("bad", [math.nan, math.inf, "1"])
def test_bad_commands_raise_input_error(bad: object) -> None:
    robot = KinematicRobot(Room(3.0, 3.0, [], []).space(), pose=Pose(1.5, 1.5, 0.0))
    with pytest.raises(InputError):
        robot.move(bad)  # type: ignore[arg-type]
    with pytest.raises(InputError):
        robot.turn(bad)  # type: ignore[arg-type]
    with pytest.raises(InputError):
        robot.drive(0.1, 0.1, -1.0)


@pytest.mark.parametrize("field", ["radius_m", "max_substep_s"])
def test_params_validated(field: str) -> None:
    with pytest.raises(InputError, match=field):
        RobotParams(**{field: 0.0})
    with pytest.raises(InputError, match="contact_skin_m"):
        RobotParams(contact_skin_m=-1.0)


def test_move_in_substeps_calls_back_and_stays_an_exact_composition() -> None:
    room = Room(10.0, 4.0, [], [])
    start = Pose(1.0, 2.0, 0.1)
    robot = KinematicRobot(room.space(), pose=start)
    calls: list[tuple[Pose, Pose]] = []
    result = robot.move(3.0, substeps=7, on_substep=lambda a, b: calls.append((a, b)))
    assert len(calls) == 7 and calls[0][0] == start and calls[-1][1] == result.pose
    assert all(a[1] == b[0] for a, b in itertools.pairwise(calls))
    assert result.pose == start.compose(result.increment)
    assert result.increment.y == 0.0 and result.increment.theta == 0.0
    assert result.distance_m == pytest.approx(3.0)
    blocked = robot.move(20.0, substeps=10, on_substep=lambda a, b: calls.append((a, b)))
    assert blocked.collided and len(calls) < 7 + 10
    with pytest.raises(InputError, match="substeps"):
        robot.move(1.0, substeps=0)


def test_refused_substep_goes_back_exactly_and_ends_the_move() -> None:
    start = Pose(1.0, 2.0, 0.2)
    robot = KinematicRobot(Room(10.0, 4.0, [], []).space(), pose=start)
    seen: list[Pose] = []

    def physics(previous: Pose, new: Pose) -> None:
        seen.append(new)
        if len(seen) == 3:
            robot.refuse_substep()  # e.g. a box pinned ahead: this part is undone

    result = robot.move(2.0, substeps=10, on_substep=physics)
    assert result.collided and len(seen) == 3
    assert result.pose == seen[1] == start.compose(result.increment)
    assert result.distance_m == pytest.approx(0.4)
    with pytest.raises(RuntimeError, match="only valid inside"):
        robot.refuse_substep()
