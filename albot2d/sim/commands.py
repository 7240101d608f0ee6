"""What a controller sends to and gets back from ``Simulator.step``: ``VelocityCommand``,
``Twist`` and ``Observation``.

Units and frames per REP-103: ``v_mps`` forward speed in the robot frame (negative:
backwards), ``omega_radps`` counter-clockwise turn rate; poses in the world frame
(``true_pose``) or the odometry frame (``odom_pose``, which starts at the start pose).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from albot2d.errors import InputError
from albot2d.frames import Scan
from albot2d.geometry import Pose

__all__ = ["Observation", "Twist", "VelocityCommand"]


def _finite(owner: str, name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise InputError(f"{owner}.{name} must be a number, got {value!r}")
    if not math.isfinite(value):
        raise InputError(f"{owner}.{name} must be finite, got {value!r}")
    return float(value)


@dataclass(frozen=True, slots=True)
class VelocityCommand:
    """A unicycle velocity command held for one ``Simulator.step``: forward speed
    ``v_mps`` (m/s) and turn rate ``omega_radps`` (rad/s, counter-clockwise positive).

    NaN, infinite or non-numeric values raise ``InputError`` naming the value. Numpy
    scalars are accepted and stored as Python floats.
    """

    v_mps: float = 0.0
    omega_radps: float = 0.0

    def __post_init__(self) -> None:
        for name in ("v_mps", "omega_radps"):
            value = getattr(self, name)
            if hasattr(value, "item") and not isinstance(value, int | float):
                value = value.item()  # a numpy scalar
            object.__setattr__(self, name, _finite("VelocityCommand", name, value))


@dataclass(frozen=True, slots=True)
class Twist:
    """A measured velocity: forward speed ``v_mps`` and turn rate ``omega_radps``."""

    v_mps: float = 0.0
    omega_radps: float = 0.0


@dataclass(frozen=True, eq=False)
class Observation:
    """What the robot knows (and, for evaluation, the truth) after ``reset`` or a ``step``.

    - ``time_s``: simulated time since ``reset``.
    - ``true_pose``: the robot's true world pose (ground truth: a controller that is meant
      to act on odometry alone must not read it).
    - ``odom_pose``: the pose integrated by odometry (starts equal to the start pose).
    - ``odom_increment``: the odometry motion reported over this step, in the odometry
      frame at the step's start (``odom_pose_before ⊕ odom_increment = odom_pose``).
    - ``odom_twist``: the odometry's speed over this step (its increment / ``dt_s``): what
      the wheel encoders say the robot did.
    - ``scan``: the laser sweep taken in this step, or ``None`` when the laser was not due
      (it fires on the simulated clock at ``Simulator.laser_rate_hz``); ``scan.timestamp``
      is the time it was taken.
    - ``collided``: the robot touched something during this step and stopped there.
    - ``command``: the command actually executed, after the robot's limits (see
      ``RobotParams``): compare it with the one sent to see clamping.
    - ``step_index``: 0 after ``reset``, then 1, 2, ...
    - ``obstacle_poses``: the moving obstacles' true poses, ``(M, 3)`` rows ``x, y,
      theta`` in the order of ``world.dynamic_obstacles`` (None: the world has none).
    """

    time_s: float
    true_pose: Pose
    odom_pose: Pose
    odom_increment: Pose
    odom_twist: Twist
    scan: Scan | None
    collided: bool
    command: VelocityCommand
    step_index: int
    obstacle_poses: NDArray[np.float64] | None = None
