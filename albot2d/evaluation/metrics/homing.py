"""Homing, the paper's "orientation to the start" (Table 1).

At a stop, the bearing to the start is the angle the robot must turn from its current
heading to face the start (degrees, + = turn left / counter-clockwise, as in the paper),
and the distance is straight-line metres. Both are computed in a map's frame from the
robot's pose and the start position in that frame, so a mapper's estimate and the truth
are compared the same way.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
from numpy.typing import ArrayLike

from albot2d.geometry import Pose, wrap_angle

__all__ = ["HomingResult", "homing", "homing_to_start"]


@dataclass(frozen=True, slots=True)
class HomingResult:
    """Estimated and true bearing (deg) and distance (m) to the start at one stop; the
    true values (and so the errors) are None when the truth is unknown (a real log)."""

    view: int
    bearing_est_deg: float
    bearing_true_deg: float | None
    distance_est_m: float
    distance_true_m: float | None

    @property
    def bearing_error_deg(self) -> float | None:
        if self.bearing_true_deg is None:
            return None
        diff = math.radians(self.bearing_est_deg - self.bearing_true_deg)
        return math.degrees(float(wrap_angle(diff)))

    @property
    def distance_error_m(self) -> float | None:
        if self.distance_true_m is None:
            return None
        return self.distance_est_m - self.distance_true_m

    def to_dict(self) -> dict[str, float | int | None]:
        return asdict(self)


def homing(robot: Pose, start_xy: ArrayLike) -> tuple[float, float]:
    """(bearing_deg, distance_m) from ``robot`` to the point ``start_xy``, same frame."""
    sx, sy = (float(v) for v in np.asarray(start_xy, dtype=np.float64).reshape(2))
    dx, dy = sx - robot.x, sy - robot.y
    bearing = wrap_angle(math.atan2(dy, dx) - robot.theta)
    return math.degrees(float(bearing)), math.hypot(dx, dy)


def homing_to_start(
    view: int,
    est_pose: ArrayLike,
    est_start: ArrayLike,
    true_pose: ArrayLike | None = None,
    true_start: ArrayLike | None = None,
) -> HomingResult:
    """Homing at frame ``view``: the estimated pose and start (``(x, y[, theta])``) in the
    mapper's frame, and the true ones in the world frame when known. Each pair is
    compared in its own frame, so a mapper's frame need not be the world's."""
    be, de = homing(Pose.from_array(est_pose), np.asarray(est_start, np.float64)[:2])
    if true_pose is None or true_start is None:
        return HomingResult(int(view), be, None, de, None)
    bt, dt = homing(Pose.from_array(true_pose), np.asarray(true_start, np.float64)[:2])
    return HomingResult(int(view), be, bt, de, dt)
