"""Simulation: kinematic robot on pymunk, 2D laser, noisy odometry, driving profiles."""

from albot2d.sim.driving import PROFILES, DrivingProfile, Step, TourController, get_profile
from albot2d.sim.dynamics import Dynamics, PhysicsParams
from albot2d.sim.laser import Laser, LaserNoise, LaserParams
from albot2d.sim.odometry import (
    NOISE_PRESETS,
    Odometry,
    OdometryNoise,
    OdometryReading,
    noise_preset,
    perturb_increment,
)
from albot2d.sim.raycast import BeamFan, RayCaster, cast_brute_force
from albot2d.sim.robot import KinematicRobot, MoveResult, RobotParams
from albot2d.sim.simulator import Simulator

__all__: list[str] = [
    "NOISE_PRESETS",
    "PROFILES",
    "BeamFan",
    "DrivingProfile",
    "Dynamics",
    "KinematicRobot",
    "Laser",
    "LaserNoise",
    "LaserParams",
    "MoveResult",
    "Odometry",
    "OdometryNoise",
    "OdometryReading",
    "PhysicsParams",
    "RayCaster",
    "RobotParams",
    "Simulator",
    "Step",
    "TourController",
    "cast_brute_force",
    "get_profile",
    "noise_preset",
    "perturb_increment",
]
