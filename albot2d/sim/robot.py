"""The robot's body and motion: ``RobotParams``, ``MoveResult``, ``KinematicRobot``.

A Pioneer-3DX-like robot: a disc with unicycle kinematics, moved as a KINEMATIC pymunk
body among a space's shapes. Static shapes (walls, clutter) and other kinematic bodies
(walking people) block it; DYNAMIC bodies (movable boxes) do not block — the simulator
lets pymunk push them, and undoes a sub-step (``refuse_substep``) that would push a box
into something that does not give way. A blocked move stops just short of contact
(``contact_skin_m``) and is reported as a collision; turning in place never collides (the
robot is a disc).

The true pose is always ``previous pose ⊕ increment`` (``Pose.compose``), the same
composition odometry uses, so zero-noise odometry equals the truth bit for bit.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import pymunk

from albot2d.errors import InputError
from albot2d.geometry import Pose
from albot2d.validation import check_non_negative, check_positive

__all__ = ["KinematicRobot", "MoveResult", "RobotParams"]

# The robot's shape group: queries with this group never report the robot itself.
_ROBOT_GROUP = 0x5EED
# Distances this close to the radius count as touching, not overlapping (float noise).
_OVERLAP_TOLERANCE_M = 1e-12
# Shapes this much beyond the contact distance count as touching (see _allowed_distance).
_NEAR_CONTACT_M = 1e-7
# Bisection steps when the swept stop point fails the exact clearance check (rare: float).
_BISECTION_STEPS = 60
# Below this angular speed an arc is integrated as a straight line (avoids v/ω blow-up).
_STRAIGHT_ARC_OMEGA_RAD_S = 1e-12


@dataclass(frozen=True)
class RobotParams:
    """Robot geometry and motion integration.

    - ``radius_m``: the disc's radius (a Pioneer 3-DX fits in ~0.25 m).
    - ``contact_skin_m``: a blocked move stops with this clearance between the disc and the
      obstacle (the disc is swept with radius ``radius_m + contact_skin_m``).
    - ``max_substep_s``: velocity commands are integrated in arc sub-steps at most this long,
      each collision-checked.
    - ``max_speed_m_s`` / ``max_turn_rate_deg_s``: ``Simulator.step`` clamps a velocity
      command's forward speed (either direction) and turn rate to these (a Pioneer 3-DX:
      1.2 m/s and 300°/s, its operations manual's maxima). Velocity changes are immediate:
      no acceleration limit is modelled.
    """

    radius_m: float = 0.25
    contact_skin_m: float = 1e-6
    max_substep_s: float = 0.05
    max_speed_m_s: float = 1.2
    max_turn_rate_deg_s: float = 300.0

    def __post_init__(self) -> None:
        check_positive(self, "radius_m", "max_substep_s", "max_speed_m_s", "max_turn_rate_deg_s")
        check_non_negative(self, "contact_skin_m")


class MoveResult(NamedTuple):
    """The outcome of one motion command.

    ``increment`` is the true motion in the start pose's frame (``pose = start ⊕ increment``),
    ``distance_m`` the path length actually travelled and ``turned_rad`` the rotation done.
    """

    pose: Pose
    distance_m: float
    turned_rad: float
    collided: bool
    increment: Pose


def _check_finite(name: str, value: float) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise InputError(f"{name} must be a finite number, got {value!r}")
    return float(value)


def _scaled(increment: Pose, fraction: float) -> Pose:
    return Pose(increment.x * fraction, increment.y * fraction, increment.theta * fraction)


def _arc_increment(v: float, omega: float, h: float) -> Pose:
    """The exact unicycle motion over ``h`` seconds at constant ``v``, ``omega``."""
    if abs(omega) < _STRAIGHT_ARC_OMEGA_RAD_S:
        return Pose(v * h, 0.0, 0.0)
    phi = omega * h
    return Pose(v / omega * math.sin(phi), v / omega * (1.0 - math.cos(phi)), phi)


class KinematicRobot:
    """A disc robot on a pymunk space. Create one per space; it adds its own body and shape."""

    def __init__(
        self, space: pymunk.Space, params: RobotParams | None = None, pose: Pose | None = None
    ) -> None:
        self.params = params if params is not None else RobotParams()
        self.space = space
        self.body = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        self.shape = pymunk.Circle(self.body, self.params.radius_m)
        self.shape.filter = pymunk.ShapeFilter(group=_ROBOT_GROUP)
        self._query_filter = pymunk.ShapeFilter(group=_ROBOT_GROUP)
        self._pose = Pose()
        # The pose a move's current sub-step started from, while its callback runs.
        self._substep_start: Pose | None = None
        self._refused = False
        space.add(self.body, self.shape)
        self.set_pose(pose if pose is not None else Pose())

    @property
    def pose(self) -> Pose:
        return self._pose

    @property
    def radius_m(self) -> float:
        return self.params.radius_m

    def set_pose(self, pose: Pose) -> None:
        """Place the robot (no collision check: the caller promises free space)."""
        self._pose = pose
        self.sync_body()

    def sync_body(self) -> None:
        """Put the pymunk body exactly at the true pose, at rest (after a physics step)."""
        self.body.position = (self._pose.x, self._pose.y)
        self.body.angle = self._pose.theta
        self.body.velocity = (0.0, 0.0)
        self.body.angular_velocity = 0.0
        self.space.reindex_shapes_for_body(self.body)

    # -- queries -------------------------------------------------------------------------

    def _blocks(self, shape: pymunk.Shape) -> bool:
        body = shape.body
        return (
            body is not self.body
            and not shape.sensor
            and body is not None
            and body.body_type != pymunk.Body.DYNAMIC
        )

    def _overlaps(self, x: float, y: float) -> dict[pymunk.Shape, float]:
        """Blocking shapes nearer than the radius to (x, y), with their distances."""
        limit = self.params.radius_m - _OVERLAP_TOLERANCE_M
        hits = self.space.point_query((x, y), limit, self._query_filter)
        return {h.shape: h.distance for h in hits if self._blocks(h.shape) and h.distance < limit}

    def clearance_m(self, max_distance_m: float = 10.0) -> float:
        """The gap between the disc and the nearest blocking shape (``inf`` if none within
        ``max_distance_m``); negative when something overlaps the robot."""
        reach = max_distance_m + self.params.radius_m
        hits = self.space.point_query((self._pose.x, self._pose.y), reach, self._query_filter)
        dists = [h.distance for h in hits if self._blocks(h.shape)]
        return (min(dists) if dists else math.inf) - self.params.radius_m

    def _clear(self, x: float, y: float, start_overlaps: dict[pymunk.Shape, float]) -> bool:
        """No blocking shape within the radius, except ones already overlapping at the start
        that the robot does not get deeper into (a person who walked into the robot)."""
        for shape, dist in self._overlaps(x, y).items():
            before = start_overlaps.get(shape)
            if before is None or dist < before - _OVERLAP_TOLERANCE_M:
                return False
        return True

    def _allowed_distance(self, dx: float, dy: float, length: float) -> tuple[float, bool]:
        """How far (≤ ``length``) the disc can slide along unit direction (dx, dy) before
        its clearance to a blocking shape drops to ``contact_skin_m``."""
        reach = self.params.radius_m + self.params.contact_skin_m
        sx, sy = self._pose.x, self._pose.y
        # chipmunk's swept query is exact from a clear start but unreliable for shapes the
        # disc already (nearly) touches, so those are decided here: distance to a convex
        # shape is convex along the line, so a move that does not approach it at the start
        # never gets closer, and one that does is blocked at once.
        near: set[pymunk.Shape] = set()
        for hit in self.space.point_query((sx, sy), reach + _NEAR_CONTACT_M, self._query_filter):
            if not self._blocks(hit.shape):
                continue
            if dx * hit.gradient.x + dy * hit.gradient.y < 0.0:
                return 0.0, True
            near.add(hit.shape)
        end = (sx + dx * length, sy + dy * length)
        allowed, blocked = length, False
        for seg_hit in self.space.segment_query((sx, sy), end, reach, self._query_filter):
            if seg_hit.shape in near or not self._blocks(seg_hit.shape):
                continue
            stop = seg_hit.alpha * length
            if stop < allowed:
                allowed, blocked = stop, True
        return allowed, blocked

    # -- motion --------------------------------------------------------------------------

    def turn(self, angle_rad: float) -> MoveResult:
        """Rotate in place by ``angle_rad`` (CCW positive). Never collides."""
        angle = _check_finite("turn angle_rad", angle_rad)
        increment = Pose(0.0, 0.0, angle)
        self._pose = self._pose.compose(increment)
        self.sync_body()
        return MoveResult(self._pose, 0.0, angle, False, increment)

    def move(
        self,
        distance_m: float,
        *,
        substeps: int = 1,
        on_substep: Callable[[Pose, Pose], None] | None = None,
    ) -> MoveResult:
        """Drive straight by ``distance_m`` (negative: backwards), stopping at contact.

        With ``substeps`` > 1 the move is made in that many equal parts and
        ``on_substep(previous_pose, new_pose)`` runs after each (the simulator steps the
        physics there, so moving obstacles move and pushed boxes get pushed). The callback
        may call ``refuse_substep``: the robot then goes back to where that part began and
        the move ends there, blocked. The pose stays ``start ⊕ Pose(moved, 0, 0)`` exactly,
        whatever the number of parts.
        """
        distance = _check_finite("move distance_m", distance_m)
        if isinstance(substeps, bool) or not isinstance(substeps, int) or substeps < 1:
            raise InputError(f"move substeps must be a positive integer, got {substeps!r}")
        start = self._pose
        part = Pose(distance / substeps, 0.0, 0.0) if substeps > 1 else Pose(distance, 0.0, 0.0)
        before: Pose | None = None
        blocked = False
        for _ in range(substeps):
            previous, before_previous = self._pose, before
            _, fraction, before = self._slide(start, before, part)
            if on_substep is not None:
                self._substep_start = previous
                try:
                    on_substep(previous, self._pose)
                finally:
                    self._substep_start = None
                if self._refused:
                    self._refused = False
                    before, blocked = before_previous, True
                    break
            if fraction < 1.0:
                blocked = True
                break
        done = before if before is not None else Pose()
        return MoveResult(self._pose, abs(done.x), 0.0, blocked, done)

    def refuse_substep(self) -> None:
        """Undo the sub-step just made, from inside ``move``'s ``on_substep`` callback.

        The physics calls this when the part would push a box into something that does not
        give way (a wall, a person, another box): the robot is put back exactly where the
        part began (a pose the move already reached) and ``move`` ends there, blocked.
        """
        if self._substep_start is None:
            raise RuntimeError("refuse_substep is only valid inside a move's on_substep callback")
        self._pose = self._substep_start
        self._refused = True
        self.sync_body()

    def turn_then_move(self, angle_rad: float, distance_m: float) -> MoveResult:
        """The paper's linear motion: turn ``angle_rad`` then move ``distance_m``."""
        turned = self.turn(angle_rad)
        moved = self.move(distance_m)
        return MoveResult(
            moved.pose,
            moved.distance_m,
            turned.turned_rad,
            moved.collided,
            turned.increment.compose(moved.increment),
        )

    def drive(self, v_m_s: float, omega_rad_s: float, dt_s: float) -> MoveResult:
        """Follow the unicycle arc of constant (v, ω) for ``dt_s`` seconds in collision-checked
        sub-steps; a blocked sub-step ends the command where the robot touched.

        Sub-step end points lie exactly on the arc; between them the disc is swept along
        the chord (the arc's sagitta over one sub-step is micrometres at robot speeds).
        """
        v = _check_finite("drive v_m_s", v_m_s)
        omega = _check_finite("drive omega_rad_s", omega_rad_s)
        dt = _check_finite("drive dt_s", dt_s)
        if dt < 0.0:
            raise InputError(f"drive dt_s must be >= 0, got {dt_s!r}")
        start = self._pose
        n = max(1, math.ceil(dt / self.params.max_substep_s))
        h = dt / n
        sub = _arc_increment(v, omega, h)
        sub_length = abs(v) * h
        total: Pose | None = None
        distance = turned = 0.0
        collided = False
        for _ in range(n):
            moved, fraction, total = self._slide(start, total, sub)
            distance += sub_length * fraction
            turned += moved.theta
            if fraction < 1.0 or collided:
                collided = True
                break
        increment = total if total is not None else Pose()
        return MoveResult(self._pose, distance, turned, collided, increment)

    def follow(
        self,
        v_m_s: float,
        omega_rad_s: float,
        tick_s: float,
        ticks: int,
        *,
        on_tick: Callable[[Pose, Pose], None] | None = None,
    ) -> tuple[MoveResult, list[Pose]]:
        """Follow the unicycle arc of constant (v, ω) for ``ticks`` ticks of ``tick_s``.

        Each tick is swept along its chord and collision-checked, and composed onto the
        pose (``pose ← pose ⊕ piece``), so composing the returned pieces from the start
        pose (as odometry does) gives the true pose bit for bit. ``on_tick(previous,
        new)`` runs after each tick (the physics; it may call ``refuse_substep``, which
        undoes that tick). The first blocked tick ends the motion there. The simulator's
        time-stepped core; arguments are the caller's to check.
        """
        sub = _arc_increment(v_m_s, omega_rad_s, tick_s)
        sub_length = abs(v_m_s) * tick_s
        pieces: list[Pose] = []
        distance = turned = 0.0
        collided = False
        for _ in range(ticks):
            previous = self._pose
            moved, fraction, _ = self._slide(previous, None, sub)
            if on_tick is not None:
                self._substep_start = previous
                try:
                    on_tick(previous, self._pose)
                finally:
                    self._substep_start = None
                if self._refused:
                    self._refused = False
                    collided = True
                    break
            pieces.append(moved)
            distance += sub_length * fraction
            turned += moved.theta
            if fraction < 1.0:
                collided = True
                break
        increment = pieces[0] if len(pieces) == 1 else Pose()
        if len(pieces) > 1:
            for piece in pieces:
                increment = increment.compose(piece)
        return MoveResult(self._pose, distance, turned, collided, increment), pieces

    def _slide(
        self, anchor: Pose, before: Pose | None, increment: Pose
    ) -> tuple[Pose, float, Pose]:
        """Move along the straight chord from the current pose (``anchor ⊕ before``) to
        ``anchor ⊕ before ⊕ increment``, stopping short of contact.

        Returns the increment done (``increment`` itself or a scaled copy), the fraction of
        it done (< 1 means blocked) and the new pose relative to ``anchor``; the robot's
        pose becomes exactly ``anchor.compose(that)``.
        """
        start = self._pose
        fraction = 1.0
        after = self._relative(before, increment, 1.0)
        target = anchor.compose(after)
        chord = math.hypot(target.x - start.x, target.y - start.y)
        if chord > 0.0:
            dx, dy = (target.x - start.x) / chord, (target.y - start.y) / chord
            allowed, blocked = self._allowed_distance(dx, dy, chord)
            start_overlaps = self._overlaps(start.x, start.y)
            if blocked:
                fraction = allowed / chord
                after = self._relative(before, increment, fraction)
                target = anchor.compose(after)
            if not self._clear(target.x, target.y, start_overlaps):
                # The swept stop point is a hair inside (float); bisect back to a clear point.
                lo, hi = 0.0, fraction
                for _ in range(_BISECTION_STEPS):
                    mid = 0.5 * (lo + hi)
                    cand = anchor.compose(self._relative(before, increment, mid))
                    if self._clear(cand.x, cand.y, start_overlaps):
                        lo = mid
                    else:
                        hi = mid
                fraction = min(lo, np.nextafter(1.0, 0.0))
                after = self._relative(before, increment, fraction)
                target = anchor.compose(after)
        self._pose = target
        self.sync_body()
        done = increment if fraction == 1.0 else _scaled(increment, fraction)
        return done, fraction, after

    @staticmethod
    def _relative(before: Pose | None, increment: Pose, fraction: float) -> Pose:
        inc = increment if fraction == 1.0 else _scaled(increment, fraction)
        return inc if before is None else before.compose(inc)
