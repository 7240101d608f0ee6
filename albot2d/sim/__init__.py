"""Simulation: kinematic robot on pymunk, 2D laser, noisy odometry, driving profiles."""

__all__: list[str] = []
