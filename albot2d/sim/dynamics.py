"""Moving obstacles during a simulation: ``PhysicsParams`` and ``Dynamics``.

People walk back and forth along their ``DynamicObstacle.path`` (KINEMATIC bodies: they
push boxes, nothing stops them; the robot stops at them). Movable boxes are DYNAMIC
bodies that pymunk pushes when the robot or a person runs into them, slowed down by the
space's damping as if by floor friction. ``Dynamics`` steps the pymunk space in fixed
sub-steps and gives the laser the obstacles' current outlines.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pymunk
from numpy.typing import NDArray

from albot2d.geometry import Pose, polygon_ring_segments
from albot2d.sim.robot import KinematicRobot
from albot2d.validation import check_in_range, check_positive
from worldgen.space import obstacle_bodies
from worldgen.world import DynamicObstacle, World

__all__ = ["Dynamics", "PhysicsParams"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class PhysicsParams:
    """How moving obstacles are simulated.

    - ``step_s``: the physics sub-step while anything moves.
    - ``velocity_retained_per_s``: pymunk ``Space.damping``: the fraction of its speed a
      pushed box keeps after one second (floor friction).
    - ``person_speed_jitter``: each walk leg's speed is the person's ``speed_m_s`` times
      a uniform factor in [1 - this, 1 + this] (drawn from the obstacles' own stream).
    """

    step_s: float = 0.05
    velocity_retained_per_s: float = 0.05
    person_speed_jitter: float = 0.2

    def __post_init__(self) -> None:
        check_positive(self, "step_s")
        check_in_range(self, "velocity_retained_per_s", 0.0, 1.0)
        check_in_range(self, "person_speed_jitter", 0.0, 0.99)


class _Walker:
    """A person's position along its path: arc length ``s``, walking ``direction`` ±1."""

    def __init__(self, obstacle: DynamicObstacle, body: pymunk.Body, rng: np.random.Generator,
                 jitter: float) -> None:
        self.body = body
        self.rng = rng
        self.jitter = jitter
        self.base_speed = obstacle.speed_m_s
        path = obstacle.path
        lengths = np.hypot(*np.diff(path, axis=0).T)
        keep = np.concatenate([[True], lengths > 0.0])
        self.path = path[keep]
        self.cum = np.concatenate([[0.0], np.cumsum(lengths[lengths > 0.0])])
        self.total = float(self.cum[-1])
        self.s = self._project(obstacle.pose)
        self.direction = 1.0
        self.speed = self._leg_speed()

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

    def advance(self, h: float) -> None:
        """Walk for ``h`` seconds, turning back (at a new speed) at either end."""
        s = self.s + self.direction * self.speed * h
        while s > self.total or s < 0.0:
            s = 2.0 * self.total - s if s > self.total else -s
            self.direction = -self.direction
            self.speed = self._leg_speed()
        self.s = s

    def pose(self) -> tuple[float, float, float]:
        k = int(np.clip(np.searchsorted(self.cum, self.s, side="right") - 1, 0, len(self.cum) - 2))
        a, b = self.path[k], self.path[k + 1]
        t = (self.s - self.cum[k]) / (self.cum[k + 1] - self.cum[k])
        heading = math.atan2(b[1] - a[1], b[0] - a[0])
        if self.direction < 0.0:
            heading += math.pi
        p = a + t * (b - a)
        return float(p[0]), float(p[1]), heading


class Dynamics:
    """Moves a space's dynamic obstacles (from ``worldgen.build_space``) through time."""

    def __init__(self, world: World, space: pymunk.Space, rng: np.random.Generator,
                 params: PhysicsParams | None = None) -> None:
        self.params = params if params is not None else PhysicsParams()
        self.space = space
        space.damping = self.params.velocity_retained_per_s
        bodies = obstacle_bodies(space)
        self._shapes: list[tuple[pymunk.Body, FloatArray]] = []
        self._walkers: list[_Walker] = []
        for index, obstacle in enumerate(world.dynamic_obstacles):
            body = bodies.get(index)
            if body is None:
                continue
            self._shapes.append((body, polygon_ring_segments(obstacle.shape)))
            walks = obstacle.kind == "person" and obstacle.speed_m_s > 0.0
            if walks and len(obstacle.path) >= 2 and np.hypot(*np.ptp(obstacle.path, 0)) > 0:
                self._walkers.append(_Walker(obstacle, body, rng, self.params.person_speed_jitter))
        for walker in self._walkers:
            self._place(walker)

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
        (the robot's own pose is already ``new``; its body sweeps so it pushes boxes)."""
        for walker in self._walkers:
            x0, y0 = walker.body.position
            walker.advance(h)
            x1, y1, _ = walker.pose()
            walker.body.velocity = ((x1 - x0) / h, (y1 - y0) / h)
        robot.body.position = (previous.x, previous.y)
        robot.body.velocity = ((new.x - previous.x) / h, (new.y - previous.y) / h)
        self.space.reindex_shapes_for_body(robot.body)
        self.space.step(h)
        robot.sync_body()
        for walker in self._walkers:
            self._place(walker)

    def _place(self, walker: _Walker) -> None:
        x, y, heading = walker.pose()
        walker.body.position = (x, y)
        walker.body.angle = heading
        walker.body.velocity = (0.0, 0.0)
        self.space.reindex_shapes_for_body(walker.body)

    def outlines(self) -> FloatArray:
        """Every moving obstacle's outline now, as ``(M, 4)`` world-frame segments."""
        if not self._shapes:
            return np.zeros((0, 4))
        parts = []
        for body, ring in self._shapes:
            c, s = math.cos(body.angle), math.sin(body.angle)
            x, y = body.position
            pts = ring.reshape(-1, 2)
            world_pts = np.column_stack([x + c * pts[:, 0] - s * pts[:, 1],
                                         y + s * pts[:, 0] + c * pts[:, 1]])
            parts.append(world_pts.reshape(-1, 4))
        return np.vstack(parts)
