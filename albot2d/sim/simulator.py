"""The simulator: drives a robot through a World along a tour and yields ``Frame``s.

``Simulator(world, seed=...)`` owns the parameters; each ``drive(tour, profile)`` builds a
fresh pymunk space, robot, odometry and moving obstacles, so the same world, seed and
parameters give bit-identical frames on every call and in every process. Randomness comes
from one seed split (``albot2d.seeding.spawn_seeds``) into independent streams for laser
noise, odometry noise and moving obstacles, so switching one noise off leaves the others'
draws unchanged.

Each step of the profile (a turn or a move, see ``albot2d.sim.driving``) is executed
on the true robot, reported by odometry, and timed at the profile's nominal speeds; a
view records a ``Frame`` with the scan from the true pose. Moving obstacles advance during
every step and pause; the laser sees their current outlines.
"""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Iterator
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from albot2d.errors import InputError
from albot2d.frames import Frame
from albot2d.geometry import Pose
from albot2d.seeding import SeedLike, make_rng, spawn_seeds
from albot2d.sim.driving import DrivingProfile, Step, TourController, get_profile
from albot2d.sim.dynamics import Dynamics, PhysicsParams, SubstepObserver
from albot2d.sim.laser import Laser, LaserNoise, LaserParams
from albot2d.sim.odometry import Odometry, OdometryNoise
from albot2d.sim.robot import KinematicRobot, MoveResult, RobotParams
from worldgen.space import build_space
from worldgen.world import Tour, World

__all__ = ["Simulator"]

# Order of the child random streams spawned from the simulator's seed (never reorder:
# that would change every simulated run).
_STREAMS = ("laser", "odometry", "dynamic_obstacles")


class Simulator:
    """Simulates runs in ``world``. Parameters default to the paper's robot (a Pioneer with
    a SICK laser, perfect odometry); see ``RobotParams``, ``LaserParams``, ``LaserNoise``,
    ``OdometryNoise`` and ``PhysicsParams``."""

    def __init__(
        self,
        world: World,
        *,
        seed: SeedLike,
        robot: RobotParams | None = None,
        laser: LaserParams | None = None,
        laser_noise: LaserNoise | None = None,
        odometry: OdometryNoise | None = None,
        physics: PhysicsParams | None = None,
        physics_observer: SubstepObserver | None = None,
    ) -> None:
        self.world = world
        self.robot_params = robot if robot is not None else RobotParams()
        self.laser_params = laser if laser is not None else LaserParams()
        self.laser_noise = laser_noise if laser_noise is not None else LaserNoise()
        self.odometry_noise = odometry if odometry is not None else OdometryNoise()
        self.physics = physics if physics is not None else PhysicsParams()
        self.physics_observer = physics_observer  # called after every physics sub-step
        self._seeds = dict(zip(_STREAMS, spawn_seeds(seed, len(_STREAMS)), strict=True))
        self._laser = Laser(world.obstacle_segments, self.laser_params, self.laser_noise)

    def params(self) -> dict[str, Any]:
        """Every setting of this simulator as plain data (for ``run.json``)."""
        return {
            "world": {"kind": self.world.kind, "seed": self.world.seed},
            "robot": dataclasses.asdict(self.robot_params),
            "laser": dataclasses.asdict(self.laser_params),
            "laser_noise": dataclasses.asdict(self.laser_noise),
            "odometry": dataclasses.asdict(self.odometry_noise),
            "physics": dataclasses.asdict(self.physics),
        }

    def drive(
        self,
        tour: Tour | ArrayLike,
        profile: str | DrivingProfile = "dataset1",
        *,
        start: Pose | None = None,
        lookahead: int = 1,
    ) -> Iterator[Frame]:
        """Drive from ``start`` (default: the world's start pose) through the tour's
        waypoints; yields the first view, then one Frame per view of the profile.

        ``lookahead`` > 1 simulates that many frames at a time and then hands them out:
        the same frames (the drive does not depend on who consumes it), but a consumer
        that maps each frame as it comes (simulator + Albot1) runs ~10 % faster with 32,
        as the simulator's and the mapper's working sets then stay in cache for a batch
        (measured, ``benchmarks/test_simulator.py``). The cost: up to ``lookahead - 1``
        frames simulated beyond where a consumer stops, the first frame only after a
        batch, and the time of a batch spent in the ``next()`` that starts it.

        Arguments are checked here, before the first frame is asked for.
        """
        if isinstance(lookahead, bool) or not isinstance(lookahead, int) or lookahead < 1:
            raise InputError(f"lookahead must be an integer >= 1, got {lookahead!r}")
        prof = get_profile(profile)
        waypoints = tour.waypoints if isinstance(tour, Tour) else np.asarray(tour, float)
        controller = TourController(waypoints, prof)
        frames = self._run(controller, prof, start if start is not None else self.world.start)
        return frames if lookahead == 1 else _in_batches(frames, lookahead)

    def _run(
        self, controller: TourController, profile: DrivingProfile, start: Pose
    ) -> Iterator[Frame]:
        laser_rng = make_rng(self._seeds["laser"])
        odometry_rng = make_rng(self._seeds["odometry"])
        obstacle_rng = make_rng(self._seeds["dynamic_obstacles"])
        space = build_space(self.world)
        robot = KinematicRobot(space, self.robot_params, start)
        dynamics = Dynamics(
            self.world, space, obstacle_rng, self.physics, observer=self.physics_observer
        )
        noise = dataclasses.replace(
            self.odometry_noise,
            induced_step_m=self.odometry_noise.induced_step_m + profile.induced_step_m,
            induced_step_deg=self.odometry_noise.induced_step_deg + profile.induced_step_deg,
            induced_along_motion=(
                self.odometry_noise.induced_along_motion or profile.induced_along_motion
            ),
        )
        odometry = Odometry(noise, odometry_rng, start=start)

        def frame(index: int, t: float, increment: Pose, collided: bool) -> Frame:
            extra = dynamics.outlines() if dynamics.active else None
            scan = self._laser.scan(robot.pose, laser_rng, timestamp=t, extra_segments=extra)
            return Frame(
                index=index,
                timestamp=t,
                scan=scan,
                odom_pose=odometry.pose,
                odom_increment=increment,
                true_pose=robot.pose,
                collided=collided,
                obstacle_poses=dynamics.poses() if dynamics.active else None,
            )

        t = 0.0
        index = 0
        yield frame(index, t, Pose(), False)
        pending: Pose | None = None
        collided = False
        while (step := controller.next_step(robot.pose)) is not None:
            duration = profile.step_duration_s(step.kind, step.amount)
            result = self._execute(step, duration, robot, dynamics)
            controller.report(step, result.collided)
            reading = odometry.update(result.increment, step.kind)
            pending = reading.increment if pending is None else pending.compose(reading.increment)
            collided = collided or result.collided
            t += duration
            if step.view:
                index += 1
                yield frame(index, t, pending, collided)
                pending, collided = None, False
                if profile.stop_pause_s > 0.0:
                    dynamics.advance(profile.stop_pause_s, robot)
                    t += profile.stop_pause_s
        if pending is not None:
            yield frame(index + 1, t, pending, collided)

    @staticmethod
    def _execute(
        step: Step, duration: float, robot: KinematicRobot, dynamics: Dynamics
    ) -> MoveResult:
        """Run one step on the true robot while moving obstacles move for ``duration``."""
        if step.kind == "turn":
            result = robot.turn(step.amount)
            dynamics.advance(duration, robot)
            return result
        if not dynamics.active:
            return robot.move(step.amount)
        n, h = dynamics.substeps(duration)
        done = 0

        def physics(previous: Pose, new: Pose) -> None:
            nonlocal done
            done += 1
            dynamics.step(h, robot, previous, new)

        result = robot.move(step.amount, substeps=n, on_substep=physics)
        dynamics.advance((n - done) * h, robot)  # a blocked robot keeps pushing, time passes
        return result


def _in_batches(frames: Iterator[Frame], size: int) -> Iterator[Frame]:
    """``frames``, computed ``size`` at a time (``Simulator.drive(lookahead=...)``)."""
    while batch := list(itertools.islice(frames, size)):
        yield from batch
