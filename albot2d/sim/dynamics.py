"""Moving obstacles during a simulation: ``PhysicsParams`` and ``Dynamics``.

People walk back and forth along their ``DynamicObstacle.path`` as KINEMATIC bodies placed
by this module, never by the solver. Their pymunk shapes are rounded by
``person_clearance_m``, so the robot (``KinematicRobot``, which stops at kinematic bodies)
stops that far from a person's true outline. Each sub-step a person tries its candidate
moves in turn and takes the first that keeps a gap ≥ 0 to the robot on the rounded shape
(more when its step is longer than twice that margin, so it cannot pass through the disc
between two checks) and gets no deeper into a box, nor, off its path, into a wall or
clutter: with the robot close ahead it steps aside (away from it, then the other way, up
to ``person_max_sidestep_m``) or backs away; otherwise it walks on, drifting back onto
its path. With no move possible it stands, and after ``person_patience_s`` it turns back.

Movable boxes are DYNAMIC bodies pushed through pymunk contact when the robot runs into
them, slowed down by the space's damping as if by floor friction. Chipmunk moves a body
by the velocity of the *previous* solve, which would leave a box pushed by the robot
inside the disc for one step, so boxes are moved right after each solve instead
(``pymunk.Body.update_position``, the solver's own integration, just earlier); a move
that would take a box deeper than ``push_overlap_limit_m`` into a wall, clutter, a person
or another box is cut short (bisected) and stops the box. A robot sub-step that still
leaves a box deeper than that in the disc or anywhere (the box is pinned) is undone and
the robot stops there (``KinematicRobot.refuse_substep``).

``Dynamics`` steps all this in fixed sub-steps, gives the laser the obstacles' current
(true) outlines and, for checks, their true poses (``poses``) and an ``observer`` hook
called after every sub-step.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pymunk
from numpy.typing import NDArray

from albot2d.errors import InputError
from albot2d.geometry import Pose, polygon_ring_segments
from albot2d.sim.robot import KinematicRobot
from albot2d.validation import check_in_range, check_non_negative, check_positive
from worldgen.space import obstacle_bodies
from worldgen.world import MIN_WALK_PATH_M, DynamicObstacle, World

__all__ = [
    "MAX_MOVING_OBSTACLES",
    "MAX_STEP_S",
    "MIN_STEP_S",
    "Dynamics",
    "PhysicsParams",
    "SubstepObserver",
]

FloatArray = NDArray[np.float64]

# Limits that bound the work per simulated second (named in the errors).
MIN_STEP_S = 1e-3
MAX_STEP_S = 0.1
MAX_MOVING_OBSTACLES = 1000

# Called after every physics sub-step with the robot's true pose and ``Dynamics.poses()``.
SubstepObserver = Callable[[Pose, FloatArray], None]


@dataclass(frozen=True)
class PhysicsParams:
    """How moving obstacles are simulated.

    - ``step_s``: the physics sub-step while anything moves, in [``MIN_STEP_S``,
      ``MAX_STEP_S``] (smaller multiplies the run time; larger makes pushes coarse).
    - ``velocity_retained_per_s``: pymunk ``Space.damping``: the fraction of its speed a
      pushed box keeps after one second (floor friction).
    - ``person_speed_jitter``: each walk leg's speed is the person's ``speed_m_s`` times
      a uniform factor in [1 - this, 1 + this] (drawn from the obstacles' own stream).
    - ``person_clearance_m``: the gap people and the robot keep between them (people's
      pymunk shapes are rounded by this much; the laser sees their true outline).
    - ``person_yield_distance_m``: a person whose way the robot is in, this close, steps
      aside (away from it), up to ``person_max_sidestep_m`` off its path, and back onto its
      path once clear.
    - ``person_patience_s``: a person who could not move for this long turns back.
    - ``contact_slop_m``: pymunk ``Space.collision_slop``, the overlap contacts may keep
      (pymunk's default, 0.1, is meant for pixels).
    - ``push_overlap_limit_m``: a robot sub-step that leaves a box deeper than this in the
      disc, or in a wall, clutter, a person or another box (and deeper than before), is
      undone: the box does not give way.
    """

    step_s: float = 0.05
    velocity_retained_per_s: float = 0.05
    person_speed_jitter: float = 0.2
    person_clearance_m: float = 0.05
    person_yield_distance_m: float = 0.6
    person_max_sidestep_m: float = 1.0
    person_patience_s: float = 2.0
    contact_slop_m: float = 1e-4
    push_overlap_limit_m: float = 2e-3

    def __post_init__(self) -> None:
        check_in_range(self, "step_s", MIN_STEP_S, MAX_STEP_S)
        check_in_range(self, "velocity_retained_per_s", 0.0, 1.0)
        check_in_range(self, "person_speed_jitter", 0.0, 0.99)
        check_non_negative(
            self, "person_yield_distance_m", "person_max_sidestep_m", "person_patience_s"
        )
        check_in_range(self, "person_clearance_m", 0.0, 1.0)
        check_positive(self, "push_overlap_limit_m")
        check_in_range(self, "contact_slop_m", 0.0, 0.01)


# Bisection steps when a box's move runs into something (the stop point to ~1/256 of a step).
_BOX_BISECTION_STEPS = 8
# Contacts this much deeper than before still count as no deeper (float noise).
_DEPTH_SLACK_M = 1e-9
# Depths of ``Space.shape_query`` contacts are read as ``abs(distance)``: a query reports only
# overlapping shapes, and pymunk gives the distance positive or negative depending on the
# order in which chipmunk pairs the two shape types.


def _hold_position(body: pymunk.Body, dt: float) -> None:
    """A box's position integration inside ``Space.step``: none (done after the solve)."""


class _Walker:
    """A person's walk: arc length ``s`` along its path, walking ``direction`` ±1, leg
    ``speed``, and the ``offset`` (world-frame metres) from its path point when it has
    stepped aside (a world vector, so it carries smoothly round the path's corners)."""

    def __init__(
        self,
        index: int,
        obstacle: DynamicObstacle,
        body: pymunk.Body,
        rng: np.random.Generator,
        jitter: float,
    ) -> None:
        self.body = body
        self.rng = rng
        self.jitter = jitter
        self.base_speed = obstacle.speed_m_s
        path = obstacle.path
        with np.errstate(over="ignore", invalid="ignore"):
            lengths = np.hypot(*np.diff(path, axis=0).T)
        keep = np.concatenate([[True], lengths > 0.0])
        self.path = path[keep]
        self.cum = np.concatenate([[0.0], np.cumsum(lengths[lengths > 0.0])])
        self.total = float(self.cum[-1])
        if not MIN_WALK_PATH_M <= self.total < math.inf:
            raise InputError(
                f"dynamic_obstacles[{index}]: a walking person's path must be at least "
                f"{MIN_WALK_PATH_M} m long (MIN_WALK_PATH_M) and finite, got {self.total:.3g} m"
            )
        self.s = self._project(obstacle.pose)
        self.direction = 1.0
        self.speed = self._leg_speed()
        self.offset = (0.0, 0.0)
        self.waited_s = 0.0

    def _leg_speed(self) -> float:
        return self.base_speed * (1.0 + self.rng.uniform(-self.jitter, self.jitter))

    def _project(self, pose: Pose) -> float:
        """Arc length of the path point nearest to ``pose``."""
        a, b = self.path[:-1], self.path[1:]
        d = b - a
        len2 = np.einsum("ij,ij->i", d, d)
        t = np.clip(np.einsum("ij,ij->i", pose.position - a, d) / len2, 0.0, 1.0)
        closest = a + t[:, None] * d
        k = int(np.argmin(np.hypot(*(closest - pose.position).T)))
        return float(self.cum[k] + t[k] * math.sqrt(len2[k]))

    def peek(self, h: float) -> tuple[float, float, float]:
        """Where ``h`` seconds of walking would take it: ``(s, direction, speed)``, turning
        back (at a new speed) at either end. The speed and path limits of
        ``DynamicObstacle`` and ``PhysicsParams.step_s`` keep the turns per call few."""
        direction, speed = self.direction, self.speed
        s = self.s + direction * speed * h
        while s > self.total or s < 0.0:
            s = 2.0 * self.total - s if s > self.total else -s
            direction = -direction
            speed = self._leg_speed()
        return s, direction, speed

    def turn_back(self) -> None:
        self.direction = -self.direction
        self.speed = self._leg_speed()
        self.waited_s = 0.0

    def pose(
        self,
        s: float | None = None,
        direction: float | None = None,
        offset: tuple[float, float] | None = None,
    ) -> tuple[float, float, float]:
        s = self.s if s is None else s
        direction = self.direction if direction is None else direction
        ox, oy = self.offset if offset is None else offset
        k = int(np.clip(np.searchsorted(self.cum, s, side="right") - 1, 0, len(self.cum) - 2))
        (ax, ay), (bx, by) = self.path[k].tolist(), self.path[k + 1].tolist()
        t = (s - self.cum[k]) / (self.cum[k + 1] - self.cum[k])
        heading = math.atan2(by - ay, bx - ax) + (math.pi if direction < 0.0 else 0.0)
        return ax + t * (bx - ax) + ox, ay + t * (by - ay) + oy, heading


class Dynamics:
    """Moves a space's dynamic obstacles (from ``worldgen.build_space``) through time.

    ``observer(robot_pose, poses)`` (optional) is called after every physics sub-step.
    """

    def __init__(
        self,
        world: World,
        space: pymunk.Space,
        rng: np.random.Generator,
        params: PhysicsParams | None = None,
        *,
        observer: SubstepObserver | None = None,
    ) -> None:
        self.params = params if params is not None else PhysicsParams()
        self.space = space
        self.observer = observer
        count = len(world.dynamic_obstacles)
        if count > MAX_MOVING_OBSTACLES:
            raise InputError(
                f"the world has {count} dynamic_obstacles; at most "
                f"{MAX_MOVING_OBSTACLES} are simulated (MAX_MOVING_OBSTACLES)"
            )
        space.damping = self.params.velocity_retained_per_s
        space.collision_slop = self.params.contact_slop_m
        bodies = obstacle_bodies(space)
        self._bodies: list[pymunk.Body | None] = [bodies.get(i) for i in range(count)]
        self._shapes: list[tuple[pymunk.Body, FloatArray]] = []
        self._boxes: list[pymunk.Body] = []
        self._walkers: list[_Walker] = []
        for index, obstacle in enumerate(world.dynamic_obstacles):
            body = self._bodies[index]
            if body is None:
                continue
            self._shapes.append((body, polygon_ring_segments(obstacle.shape)))
            if body.body_type == pymunk.Body.DYNAMIC:
                body.position_func = _hold_position
                self._boxes.append(body)
            if body.body_type == pymunk.Body.KINEMATIC:
                for shape in body.shapes:  # people keep their distance (see the module)
                    shape.unsafe_set_radius(self.params.person_clearance_m)
            walks = obstacle.kind == "person" and obstacle.speed_m_s > 0.0
            if walks and len(obstacle.path) >= 2:
                self._walkers.append(
                    _Walker(index, obstacle, body, rng, self.params.person_speed_jitter)
                )
        for walker in self._walkers:
            self._place(walker.body, *walker.pose())

    @property
    def active(self) -> bool:
        """Whether there is anything to simulate (else callers may skip all stepping)."""
        return bool(self._shapes)

    def substeps(self, duration_s: float) -> tuple[int, float]:
        """How many physics sub-steps span ``duration_s``, and their length."""
        n = max(1, math.ceil(duration_s / self.params.step_s - 1e-9))
        return n, duration_s / n

    def advance(self, duration_s: float, robot: KinematicRobot) -> None:
        """Let ``duration_s`` seconds pass with the robot standing still."""
        if not self.active or duration_s <= 0.0:
            return
        n, h = self.substeps(duration_s)
        for _ in range(n):
            self.step(h, robot, robot.pose, robot.pose)

    def step(self, h: float, robot: KinematicRobot, previous: Pose, new: Pose) -> None:
        """One physics sub-step of ``h`` s while the robot goes from ``previous`` to ``new``
        (the robot's own pose is already ``new``; its body sweeps so it pushes boxes).

        A move that leaves a box deeper than ``push_overlap_limit_m`` in the disc or in
        anything else (and deeper than with the robot at ``previous``) is undone with
        ``robot.refuse_substep()`` (only valid inside ``KinematicRobot.move``'s callback)
        and the sub-step is simulated with the robot standing at ``previous``.
        """
        if self._boxes and previous != new:
            saved = [(b.position, b.angle, b.velocity, b.angular_velocity) for b in self._boxes]
            self._solve(h, robot, previous, new)
            after = self._push_depth(robot, new)
            if after > self.params.push_overlap_limit_m:
                for body, state in zip(self._boxes, saved, strict=True):
                    body.position, body.angle, body.velocity, body.angular_velocity = state
                    self.space.reindex_shapes_for_body(body)
                if after > self._push_depth(robot, previous):
                    robot.refuse_substep()
                    new = previous
                self._solve(h, robot, previous, new)
        elif self._boxes:
            self._solve(h, robot, previous, new)
        for walker in self._walkers:
            self._walk(walker, h, robot)
        if self.observer is not None:
            self.observer(robot.pose, self.poses())

    def _solve(self, h: float, robot: KinematicRobot, previous: Pose, new: Pose) -> None:
        """pymunk's step with the robot sweeping ``previous`` → ``new``, then the boxes
        moved by the velocities just solved."""
        robot.body.position = (previous.x, previous.y)
        robot.body.velocity = ((new.x - previous.x) / h, (new.y - previous.y) / h)
        self.space.reindex_shapes_for_body(robot.body)
        self.space.step(h)
        for body in self._boxes:
            self._move_box(body, h, robot)
        robot.sync_body()

    def _move_box(self, body: pymunk.Body, h: float, robot: KinematicRobot) -> None:
        """Move a box by its solved velocity, but not deeper into a wall, clutter, a person
        or another box than ``push_overlap_limit_m`` (or than it was): contacts are found
        before this move, so one it runs into is cut short (bisected) and stops it."""
        (x0, y0), a0 = body.position, body.angle
        limit = max(self.params.push_overlap_limit_m, self._box_depth(body, robot))
        pymunk.Body.update_position(body, h)
        self.space.reindex_shapes_for_body(body)
        if self._box_depth(body, robot) <= limit:
            return
        (x1, y1), a1 = body.position, body.angle
        lo, hi = 0.0, 1.0
        for _ in range(_BOX_BISECTION_STEPS):
            mid = 0.5 * (lo + hi)
            body.position = (x0 + mid * (x1 - x0), y0 + mid * (y1 - y0))
            body.angle = a0 + mid * (a1 - a0)
            self.space.reindex_shapes_for_body(body)
            if self._box_depth(body, robot) <= limit:
                lo = mid
            else:
                hi = mid
        body.position = (x0 + lo * (x1 - x0), y0 + lo * (y1 - y0))
        body.angle = a0 + lo * (a1 - a0)
        body.velocity = (0.0, 0.0)
        body.angular_velocity = 0.0
        self.space.reindex_shapes_for_body(body)

    def _box_depth(self, box: pymunk.Body, robot: KinematicRobot) -> float:
        """How deep ``box`` reaches into anything but itself and the robot (0: nothing)."""
        deepest = 0.0
        for shape in box.shapes:
            for hit in self.space.shape_query(shape):
                if hit.shape.body is robot.body or hit.shape.body is box:
                    continue
                points = hit.contact_point_set.points
                deepest = max(deepest, max((abs(p.distance) for p in points), default=0.0))
        return deepest

    def _push_depth(self, robot: KinematicRobot, at: Pose) -> float:
        """How deep the deepest box reaches into the robot's disc placed at ``at``, or into
        a wall, clutter, a person or another box (≤ 0: nowhere)."""
        radius = robot.radius_m
        deepest = -math.inf
        for hit in self.space.point_query((at.x, at.y), radius, pymunk.ShapeFilter()):
            body = hit.shape.body
            if body is not None and body.body_type == pymunk.Body.DYNAMIC:
                deepest = max(deepest, radius - hit.distance)
        for box in self._boxes:
            deepest = max(deepest, self._box_depth(box, robot))
        return deepest

    def _walk(self, walker: _Walker, h: float, robot: KinematicRobot) -> None:
        """One sub-step of a person: the first of its candidate moves that keeps clear of
        the robot, the boxes and (once off its path) the walls; else it stands."""
        if walker.waited_s >= self.params.person_patience_s:
            walker.turn_back()
        body = walker.body
        (x0, y0), angle0 = body.position, body.angle
        gap_before = self._gap(body, robot)
        depth_before = self._contact_depths(body)
        s, direction, speed = walker.peek(h)
        side_m = speed * h
        ox, oy = walker.offset
        norm = math.hypot(ox, oy)
        shrink = max(0.0, norm - side_m) / norm if norm > 0.0 else 0.0
        rx, ry = robot.pose.x - x0, robot.pose.y - y0
        hx, hy = math.cos(angle0), math.sin(angle0)
        candidates: list[tuple[float, float, tuple[float, float]]] = []
        if gap_before < self.params.person_yield_distance_m and rx * hx + ry * hy > 0.0:
            # The robot is close ahead: step aside, away from it (else the other way).
            away = -1.0 if hx * ry - hy * rx > 0.0 else 1.0
            for side in (away, -away):
                shifted = (ox - side * side_m * hy, oy + side * side_m * hx)
                if math.hypot(*shifted) <= self.params.person_max_sidestep_m:
                    candidates += [(s, direction, shifted), (walker.s, walker.direction, shifted)]
        candidates += [(s, direction, (ox * shrink, oy * shrink)), (s, direction, (ox, oy))]
        distance = math.hypot(rx, ry)
        if gap_before < self.params.person_yield_distance_m and distance > 0.0:
            # Blocked with the robot close by (it may be turning into the robot): back away.
            back_off = (ox - side_m * rx / distance, oy - side_m * ry / distance)
            if math.hypot(*back_off) <= self.params.person_max_sidestep_m:
                candidates.append((walker.s, walker.direction, back_off))
        for cs, cd, offset in candidates:
            x, y, heading = walker.pose(cs, cd, offset)
            self._place(body, x, y, heading)
            off_path = offset != (0.0, 0.0)
            if self._may_stand(
                body, robot, math.hypot(x - x0, y - y0), gap_before, depth_before, off_path
            ):
                if cd == direction and cs == s:
                    walker.s, walker.direction, walker.speed = s, direction, speed
                walker.offset = offset
                walker.waited_s = 0.0
                return
        self._place(body, x0, y0, angle0)
        walker.waited_s += h

    def _may_stand(
        self,
        body: pymunk.Body,
        robot: KinematicRobot,
        step_m: float,
        gap_before: float,
        depth_before: tuple[float, float],
        off_path: bool,
    ) -> bool:
        """Whether a person just placed ``step_m`` from where it stood may be there.

        Its pymunk shapes are rounded by ``person_clearance_m``, so a gap ≥ 0 to them
        keeps that much from its true outline; asking for half the step more than that
        margin keeps the whole step clear (distance changes no faster than the motion).
        It may not get deeper into a box, nor, off its path, into a wall or clutter."""
        gap = self._gap(body, robot)
        need = max(0.0, 0.5 * step_m - self.params.person_clearance_m)
        # Already closer than that (a world file put it on the robot): moving away is fine.
        if gap < need and gap < gap_before + 0.5 * step_m:
            return False
        box, static = self._contact_depths(body)
        if box > max(depth_before[0], 0.0) + _DEPTH_SLACK_M:
            return False
        return not (off_path and static > max(depth_before[1], 0.0) + _DEPTH_SLACK_M)

    def _contact_depths(self, body: pymunk.Body) -> tuple[float, float]:
        """How deep ``body``'s shapes reach into boxes and into walls or clutter (0: none)."""
        box = static = 0.0
        for shape in body.shapes:
            for hit in self.space.shape_query(shape):
                other = hit.shape.body
                if other is None or other.body_type == pymunk.Body.KINEMATIC:
                    continue
                points = hit.contact_point_set.points
                depth = max((abs(p.distance) for p in points), default=0.0)
                if other.body_type == pymunk.Body.DYNAMIC:
                    box = max(box, depth)
                else:
                    static = max(static, depth)
        return box, static

    def _gap(self, body: pymunk.Body, robot: KinematicRobot) -> float:
        """The gap between ``body``'s shapes and the robot's disc (negative: overlap)."""
        centre = (robot.pose.x, robot.pose.y)
        return min(shape.point_query(centre).distance for shape in body.shapes) - robot.radius_m

    def _place(self, body: pymunk.Body, x: float, y: float, heading: float) -> None:
        body.position = (x, y)
        body.angle = heading
        body.velocity = (0.0, 0.0)
        self.space.reindex_shapes_for_body(body)

    def poses(self) -> FloatArray:
        """Every moving obstacle's true pose now, ``(M, 3)`` rows ``x, y, theta`` in the
        order of ``world.dynamic_obstacles`` (NaN for one without a body in the space)."""
        out = np.full((len(self._bodies), 3), np.nan)
        for k, body in enumerate(self._bodies):
            if body is not None:
                x, y = body.position
                out[k] = (x, y, body.angle)
        return out

    def outlines(self) -> FloatArray:
        """Every moving obstacle's outline now, as ``(M, 4)`` world-frame segments."""
        if not self._shapes:
            return np.zeros((0, 4))
        parts = []
        for body, ring in self._shapes:
            c, s = math.cos(body.angle), math.sin(body.angle)
            x, y = body.position
            pts = ring.reshape(-1, 2)
            world_pts = np.column_stack(
                [x + c * pts[:, 0] - s * pts[:, 1], y + s * pts[:, 0] + c * pts[:, 1]]
            )
            parts.append(world_pts.reshape(-1, 4))
        return np.vstack(parts)
