"""Simulation: kinematic robot on pymunk, 2D laser, noisy odometry, driving profiles."""

from albot2d.sim.laser import Laser, LaserNoise, LaserParams
from albot2d.sim.raycast import BeamFan, RayCaster, cast_brute_force

__all__: list[str] = [
    "BeamFan",
    "Laser",
    "LaserNoise",
    "LaserParams",
    "RayCaster",
    "cast_brute_force",
]
