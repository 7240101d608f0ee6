"""Simulation: kinematic robot on pymunk, 2D laser, noisy odometry, driving profiles.

``Simulator.reset`` / ``step(VelocityCommand(v, omega), dt_s)`` for a controller (an
``Observation`` per step); ``Simulator.drive(tour, profile)`` for a planned tour.
"""

from albot2d.sim.commands import Observation, Twist, VelocityCommand
from albot2d.sim.driving import (
    PROFILES,
    DrivingProfile,
    Instruction,
    Step,
    TourController,
    get_profile,
)
from albot2d.sim.dynamics import Dynamics, PhysicsParams
from albot2d.sim.laser import Laser, LaserNoise, LaserParams
from albot2d.sim.odometry import (
    NOISE_PRESETS,
    Odometry,
    OdometryNoise,
    OdometryReading,
    heading_variance_rad2,
    noise_preset,
    perturb_increment,
)
from albot2d.sim.raycast import BeamFan, RayCaster, cast_brute_force
from albot2d.sim.robot import KinematicRobot, MoveResult, RobotParams
from albot2d.sim.simulator import MAX_STEP_DT_S, Simulator

__all__: list[str] = [
    "MAX_STEP_DT_S",
    "NOISE_PRESETS",
    "PROFILES",
    "BeamFan",
    "DrivingProfile",
    "Dynamics",
    "Instruction",
    "KinematicRobot",
    "Laser",
    "LaserNoise",
    "LaserParams",
    "MoveResult",
    "Observation",
    "Odometry",
    "OdometryNoise",
    "OdometryReading",
    "PhysicsParams",
    "RayCaster",
    "RobotParams",
    "Simulator",
    "Step",
    "TourController",
    "Twist",
    "VelocityCommand",
    "cast_brute_force",
    "get_profile",
    "heading_variance_rad2",
    "noise_preset",
    "perturb_increment",
]
