"""The simulator: ``Simulator.reset`` / ``step`` for a controller, ``drive`` for a tour.

``Simulator(world, seed=...)`` owns the parameters. ``reset(seed=None, start=None)``
starts an episode (a fresh pymunk space, robot, odometry and moving obstacles) and
returns its first ``Observation``; ``step(VelocityCommand(v, omega), dt_s)`` holds the
command for ``dt_s`` simulated seconds and returns the next (``albot2d.sim.episode``
says how a step is cut into ticks, when the laser fires and where odometry error
arises). Randomness comes from the seed split (``albot2d.seeding.stream_seed``) into
independent named streams for laser noise, odometry noise and moving obstacles
(``STREAMS``), so switching one noise off leaves the others' draws unchanged, and the
same seed gives bit-identical observations in every process.

``drive(tour, profile)`` is a controller on the same core: the ``TourController`` turns
the tour into the profile's instructions (turn α, move δ; ``albot2d.sim.driving``), each
executed as a velocity command at the profile's nominal speeds, and records a ``Frame``
with a scan wherever the profile says to take a view (not at the laser's rate).
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Iterator
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from albot2d.errors import InputError
from albot2d.frames import Frame
from albot2d.geometry import Pose
from albot2d.seeding import SeedLike, stream_seed
from albot2d.sim.commands import Observation, VelocityCommand
from albot2d.sim.driving import DrivingProfile, TourController, get_profile
from albot2d.sim.dynamics import PhysicsParams, SubstepObserver
from albot2d.sim.episode import STREAMS, Episode
from albot2d.sim.laser import Laser, LaserNoise, LaserParams
from albot2d.sim.odometry import OdometryNoise
from albot2d.sim.robot import RobotParams
from worldgen.world import Tour, World

__all__ = ["MAX_STEP_DT_S", "Simulator"]

# The simulator's random streams (never reorder: that would change every simulated run).
_STREAMS = STREAMS
#: The longest ``dt_s`` one ``step`` accepts (an hour): longer is a units mistake.
MAX_STEP_DT_S = 3600.0


class Simulator:
    """Simulates runs in ``world``. Parameters default to the paper's robot (a Pioneer with
    a SICK laser, perfect odometry); see ``RobotParams``, ``LaserParams``, ``LaserNoise``,
    ``OdometryNoise`` and ``PhysicsParams``. ``laser_rate_hz``: how often the laser fires
    during ``step`` (None: never; ``drive`` takes views where its profile says instead).
    """

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
        laser_rate_hz: float | None = 10.0,
    ) -> None:
        self.world = world
        self.robot_params = robot if robot is not None else RobotParams()
        self.laser_params = laser if laser is not None else LaserParams()
        self.laser_noise = laser_noise if laser_noise is not None else LaserNoise()
        self.odometry_noise = odometry if odometry is not None else OdometryNoise()
        self.physics = physics if physics is not None else PhysicsParams()
        self.physics_observer = physics_observer  # called after every physics sub-step
        if laser_rate_hz is not None and (
            isinstance(laser_rate_hz, bool)
            or not isinstance(laser_rate_hz, int | float)
            or not 0.0 < laser_rate_hz <= 1e6
        ):
            raise InputError(f"laser_rate_hz must be in (0, 1e6] or None, got {laser_rate_hz!r}")
        self.laser_rate_hz = None if laser_rate_hz is None else float(laser_rate_hz)
        self.seed = seed
        stream_seed(seed, STREAMS, STREAMS[0])  # a bad seed fails here, not at reset
        self.laser = Laser(world.obstacle_segments, self.laser_params, self.laser_noise)
        self._episode: Episode | None = None

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

    # -- the time-stepped interface ---------------------------------------------------------

    def reset(self, seed: SeedLike | None = None, *, start: Pose | None = None) -> Observation:
        """Start an episode at ``start`` (default: the world's start pose) and return its
        first observation (time 0, with a scan when the laser fires).

        ``seed`` None: the simulator's own seed, so every ``reset()`` replays the same
        noise; an int (or SeedSequence) gives that seed's episode, the same every time.
        """
        if start is not None and not isinstance(start, Pose):
            raise InputError(f"reset start must be a Pose, got {start!r}")
        if start is not None and not all(math.isfinite(v) for v in (start.x, start.y, start.theta)):
            raise InputError(f"reset start must be finite, got {start!r}")
        episode = self._episode_at(
            self.seed if seed is None else seed,
            start if start is not None else self.world.start,
            self.odometry_noise,
            self.laser_rate_hz,
        )
        self._episode = episode
        return episode.observe(Pose(), False, VelocityCommand(), 0.0)

    def step(self, command: VelocityCommand, dt_s: float) -> Observation:
        """Hold ``command`` for ``dt_s`` simulated seconds and return the observation.

        The command is clamped to ``RobotParams.max_speed_m_s`` and
        ``max_turn_rate_deg_s`` (``Observation.command`` is what was executed). A NaN or
        infinite command, or ``dt_s`` not in (0, ``MAX_STEP_DT_S``], is an ``InputError``.
        """
        episode = self._episode
        if episode is None:
            raise RuntimeError("Simulator.step called before reset(): call reset() first")
        if not isinstance(command, VelocityCommand):
            if isinstance(command, tuple | list | np.ndarray) and len(command) == 2:
                command = VelocityCommand(*(float(c) for c in command))
            else:
                raise InputError(
                    f"step command must be a VelocityCommand(v_mps, omega_radps), got {command!r}"
                )
        dt = _check_dt(dt_s)
        executed = episode.limit(command)
        increment, collided = episode.advance(executed, dt)
        return episode.observe(increment, collided, executed, dt)

    @property
    def time_s(self) -> float:
        """Simulated time of the current episode (0 before ``reset``)."""
        return 0.0 if self._episode is None else self._episode.time_s

    # -- a tour, driven by the profile's controller -----------------------------------------

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

        Each call runs its own episode (the simulator's seed), so the same arguments give
        the same frames, and a ``reset``/``step`` episode in progress is not disturbed.

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
        self._check_profile_speeds(prof)
        waypoints = tour.waypoints if isinstance(tour, Tour) else np.asarray(tour, float)
        controller = TourController(waypoints, prof)
        frames = self._run(controller, prof, start if start is not None else self.world.start)
        return frames if lookahead == 1 else _in_batches(frames, lookahead)

    def _episode_at(
        self, seed: SeedLike, start: Pose, noise: OdometryNoise, laser_rate_hz: float | None
    ) -> Episode:
        return Episode(
            self.world,
            seed,
            start,
            robot=self.robot_params,
            laser=self.laser,
            odometry_noise=noise,
            physics=self.physics,
            physics_observer=self.physics_observer,
            laser_rate_hz=laser_rate_hz,
        )

    def _check_profile_speeds(self, profile: DrivingProfile) -> None:
        r = self.robot_params
        if profile.speed_m_s > r.max_speed_m_s:
            raise InputError(
                f"driving profile {profile.name!r}: speed_m_s {profile.speed_m_s!r} exceeds "
                f"the robot's max_speed_m_s {r.max_speed_m_s!r}"
            )
        if profile.turn_rate_deg_s > r.max_turn_rate_deg_s:
            raise InputError(
                f"driving profile {profile.name!r}: turn_rate_deg_s {profile.turn_rate_deg_s!r} "
                f"exceeds the robot's max_turn_rate_deg_s {r.max_turn_rate_deg_s!r}"
            )

    def _run(
        self, controller: TourController, profile: DrivingProfile, start: Pose
    ) -> Iterator[Frame]:
        noise = dataclasses.replace(
            self.odometry_noise,
            induced_step_m=self.odometry_noise.induced_step_m + profile.induced_step_m,
            induced_step_deg=self.odometry_noise.induced_step_deg + profile.induced_step_deg,
            induced_along_motion=(
                self.odometry_noise.induced_along_motion or profile.induced_along_motion
            ),
        )
        episode = self._episode_at(self.seed, start, noise, None)
        robot, odometry, dynamics = episode.robot, episode.odometry, episode.dynamics
        induced = bool(noise.induced_step_m or noise.induced_step_deg)
        pause = VelocityCommand()

        def frame(index: int, increment: Pose, collided: bool) -> Frame:
            return Frame(
                index=index,
                timestamp=episode.time_s,
                scan=episode.scan(),
                odom_pose=odometry.pose,
                odom_increment=increment,
                true_pose=robot.pose,
                collided=collided,
                obstacle_poses=dynamics.poses() if dynamics.active else None,
            )

        index = 0
        yield frame(index, Pose(), False)
        pending: Pose | None = None  # the odometry increments since the last view
        collided = False
        while (instruction := controller.next_instruction(robot.pose)) is not None:
            step = instruction.step
            increment, blocked = episode.advance(instruction.command, instruction.dt_s)
            controller.report(step, blocked)
            if induced and (added := odometry.induce(step.kind, step.amount)) is not None:
                increment = increment.compose(added)
            pending = increment if pending is None else pending.compose(increment)
            collided = collided or blocked
            if step.view:
                index += 1
                yield frame(index, pending, collided)
                pending, collided = None, False
                if profile.stop_pause_s > 0.0:
                    episode.advance(pause, profile.stop_pause_s)
        if pending is not None:
            yield frame(index + 1, pending, collided)


def _check_dt(dt_s: object) -> float:
    if isinstance(dt_s, bool) or not isinstance(dt_s, int | float | np.floating | np.integer):
        raise InputError(f"step dt_s must be a number of seconds, got {dt_s!r}")
    dt = float(dt_s)
    if not math.isfinite(dt) or not 0.0 < dt <= MAX_STEP_DT_S:
        raise InputError(f"step dt_s must be in (0, {MAX_STEP_DT_S:g}] seconds, got {dt_s!r}")
    return dt


def _in_batches(frames: Iterator[Frame], size: int) -> Iterator[Frame]:
    """``frames``, computed ``size`` at a time (``Simulator.drive(lookahead=...)``)."""
    while batch := list(itertools.islice(frames, size)):
        yield from batch
