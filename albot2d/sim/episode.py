"""One simulated episode's running state and its clock: ``Episode``.

An episode owns what changes while the robot drives: the pymunk space, the true robot,
the moving obstacles, odometry, the laser's random stream and the simulated time.
``Simulator.reset`` starts one and ``Simulator.step`` advances it; ``Simulator.drive``
runs its own. ``advance(command, dt_s)`` is the whole physics of a step:

- the command is held for ``dt_s``, cut into ticks: physics ticks of
  ``PhysicsParams.step_s`` while anything moves, else sub-steps of at most
  ``RobotParams.max_substep_s`` for an arc, or one tick for a straight move or a turn in
  place (a straight sweep is exact in one piece; a turn in place never collides);
- each tick moves the true robot along the unicycle arc on the pymunk space (it stops at
  contact and the rest of the step passes with it standing, obstacles moving on) and is
  fed to odometry, which generates its error along that motion (``albot2d.sim.odometry``);
- the laser fires on the simulated clock (``Simulator.laser_rate_hz``): a step in which a
  firing time falls gets a scan taken at the step's end (one, however many periods the
  step spans), so its rate does not depend on how the time is cut into steps.
"""

from __future__ import annotations

import math

from albot2d.frames import Scan
from albot2d.geometry import Pose
from albot2d.seeding import SeedLike, make_rng, stream_seed
from albot2d.sim.commands import Observation, Twist, VelocityCommand
from albot2d.sim.dynamics import Dynamics, PhysicsParams, SubstepObserver
from albot2d.sim.laser import Laser
from albot2d.sim.odometry import Odometry, OdometryNoise
from albot2d.sim.robot import KinematicRobot, RobotParams
from worldgen.space import build_space
from worldgen.world import World

__all__ = ["STREAMS", "Episode"]

# Order of the child random streams spawned from a simulator's seed (never reorder:
# that would change every simulated run).
STREAMS = ("laser", "odometry", "dynamic_obstacles")
# Times this close count as equal on the simulated clock (float sums of step lengths).
_CLOCK_SLACK_S = 1e-9


class Episode:
    """The state of one run in ``world`` from ``start`` with random streams from ``seed``
    (its children named in ``STREAMS``, built without advancing ``seed``'s spawn counter,
    so the same seed object gives the same episode every time). ``Simulator`` passes its
    parameters and its ``laser``."""

    def __init__(
        self,
        world: World,
        seed: SeedLike,
        start: Pose,
        *,
        robot: RobotParams,
        laser: Laser,
        odometry_noise: OdometryNoise,
        physics: PhysicsParams,
        physics_observer: SubstepObserver | None,
        laser_rate_hz: float | None,
    ) -> None:
        seeds = {name: stream_seed(seed, STREAMS, name) for name in STREAMS}
        self.laser = laser
        self.laser_rng = make_rng(seeds["laser"])
        self.space = build_space(world)
        self.robot = KinematicRobot(self.space, robot, start)
        self.dynamics = Dynamics(
            world,
            self.space,
            make_rng(seeds["dynamic_obstacles"]),
            physics,
            observer=physics_observer,
        )
        self.odometry = Odometry(odometry_noise, make_rng(seeds["odometry"]), start=start)
        self.time_s = 0.0
        self.steps = 0
        self._laser_period_s = None if laser_rate_hz is None else 1.0 / laser_rate_hz
        self._scans_due = 0  # laser firings so far: the next is at _scans_due · period
        self._max_speed = robot.max_speed_m_s
        self._max_turn = math.radians(robot.max_turn_rate_deg_s)

    def limit(self, command: VelocityCommand) -> VelocityCommand:
        """``command`` within the robot's speed and turn-rate limits."""
        v = min(max(command.v_mps, -self._max_speed), self._max_speed)
        w = min(max(command.omega_radps, -self._max_turn), self._max_turn)
        if v == command.v_mps and w == command.omega_radps:
            return command
        return VelocityCommand(v, w)

    def advance(self, command: VelocityCommand, dt_s: float) -> tuple[Pose, bool]:
        """Hold ``command`` (already within limits) for ``dt_s``: the true robot, the
        obstacles and odometry move on. Returns the odometry increment and whether the
        robot was blocked."""
        v, w = command.v_mps, command.omega_radps
        robot, dynamics, odometry = self.robot, self.dynamics, self.odometry
        increment: Pose | None = None
        collided = False
        if v == 0.0 and w == 0.0:
            dynamics.advance(dt_s, robot)
        else:
            if dynamics.active:
                ticks, h = dynamics.substeps(dt_s)
                if v != 0.0 and w != 0.0:
                    ticks = max(ticks, math.ceil(dt_s / robot.params.max_substep_s - 1e-9))
                    h = dt_s / ticks
                done = 0

                def physics(previous: Pose, new: Pose) -> None:
                    nonlocal done
                    done += 1
                    dynamics.step(h, robot, previous, new)

                result, pieces = robot.follow(v, w, h, ticks, on_tick=physics)
                dynamics.advance((ticks - done) * h, robot)  # blocked: time passes
            else:
                ticks = 1
                if v != 0.0 and w != 0.0:
                    ticks = max(1, math.ceil(dt_s / robot.params.max_substep_s - 1e-9))
                result, pieces = robot.follow(v, w, dt_s / ticks, ticks)
            collided = result.collided
            for piece in pieces:
                reported = odometry.update(piece).increment
                increment = reported if increment is None else increment.compose(reported)
        self.time_s += dt_s
        self.steps += 1
        return (increment if increment is not None else Pose()), collided

    def scan(self) -> Scan:
        """A laser sweep now, from the true pose, seeing the obstacles where they are."""
        dynamics = self.dynamics
        extra = dynamics.outlines() if dynamics.active else None
        return self.laser.scan(
            self.robot.pose, self.laser_rng, timestamp=self.time_s, extra_segments=extra
        )

    def laser_due(self) -> bool:
        """Whether a laser firing time has come (and mark it, and any skipped, as done)."""
        period = self._laser_period_s
        if period is None or self.time_s + _CLOCK_SLACK_S < self._scans_due * period:
            return False
        self._scans_due = math.floor((self.time_s + _CLOCK_SLACK_S) / period) + 1
        return True

    def observe(
        self,
        increment: Pose,
        collided: bool,
        command: VelocityCommand,
        dt_s: float,
    ) -> Observation:
        scan = self.scan() if self.laser_due() else None
        twist = Twist(increment.x / dt_s, increment.theta / dt_s) if dt_s > 0.0 else Twist()
        return Observation(
            time_s=self.time_s,
            true_pose=self.robot.pose,
            odom_pose=self.odometry.pose,
            odom_increment=increment,
            odom_twist=twist,
            scan=scan,
            collided=collided,
            command=command,
            step_index=self.steps,
            obstacle_poses=self.dynamics.poses() if self.dynamics.active else None,
        )
