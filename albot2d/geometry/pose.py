"""SE(2) poses: the frozen ``Pose`` value type and vectorised pose-array math.

Conventions follow ROS REP-103: metres and radians, x forward, y left, angles
counter-clockwise. ``a.compose(b)`` (also ``a @ b``) is a ⊕ b: the pose ``b``,
expressed in the frame of ``a``, mapped into the frame that ``a`` is expressed in.
Arrays of poses are ``(..., 3)`` float64 arrays of ``[x, y, theta]``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "Pose",
    "add_angle",
    "between_arrays",
    "compose_arrays",
    "invert_arrays",
    "transform_points",
    "wrap_angle",
]

FloatArray = NDArray[np.float64]


@overload
def wrap_angle(angle: float) -> float: ...
@overload
def wrap_angle(angle: NDArray[Any]) -> FloatArray: ...
@overload
def wrap_angle(angle: ArrayLike) -> FloatArray | float: ...
def wrap_angle(angle: ArrayLike) -> FloatArray | float:
    """Wrap angles (radians) to [-pi, pi). Scalars in, scalar out; arrays keep their shape."""
    if isinstance(angle, float | int) and not isinstance(angle, bool):
        # Python's float % is numpy's remainder (fmod, then the divisor's sign), so this
        # equals the array path bit for bit at a tenth of its cost (called per pose).
        return float((float(angle) + math.pi) % (2.0 * math.pi) - math.pi)
    wrapped = (np.asarray(angle, dtype=np.float64) + np.pi) % (2.0 * np.pi) - np.pi
    if np.ndim(wrapped) == 0:
        return float(wrapped)
    return wrapped


def add_angle(a: float, b: float) -> float:
    """``a + b`` wrapped to [-pi, pi) for scalars; exact (no wrap rounding) when the sum is
    already in range, so small increments do not pick up rounding from the wrap."""
    total = a + b
    if -math.pi <= total < math.pi:
        return total
    return (total + math.pi) % (2.0 * math.pi) - math.pi


@dataclass(frozen=True, slots=True)
class Pose:
    """A 2D rigid pose: position in metres, heading ``theta`` in radians."""

    x: float = 0.0
    y: float = 0.0
    theta: float = 0.0

    def __repr__(self) -> str:
        # Plain floats (not ``np.float64(...)``), full precision: exact but short.
        return f"Pose(x={float(self.x)!r}, y={float(self.y)!r}, theta={float(self.theta)!r})"

    @classmethod
    def from_array(cls, values: ArrayLike) -> Pose:
        arr = np.asarray(values, dtype=np.float64)
        if arr.shape != (3,):
            raise ValueError(f"a pose needs 3 numbers [x, y, theta], got shape {arr.shape}")
        return cls(float(arr[0]), float(arr[1]), float(arr[2]))

    def as_array(self) -> FloatArray:
        return np.array([self.x, self.y, self.theta], dtype=np.float64)

    @property
    def position(self) -> FloatArray:
        return np.array([self.x, self.y], dtype=np.float64)

    def compose(self, other: Pose) -> Pose:
        """self ⊕ other."""
        c, s = math.cos(self.theta), math.sin(self.theta)
        return Pose(
            self.x + c * other.x - s * other.y,
            self.y + s * other.x + c * other.y,
            float(wrap_angle(self.theta + other.theta)),
        )

    def __matmul__(self, other: Pose) -> Pose:
        return self.compose(other)

    def inverse(self) -> Pose:
        c, s = math.cos(self.theta), math.sin(self.theta)
        x, y = -c * self.x - s * self.y, s * self.x - c * self.y
        return Pose(x, y, float(wrap_angle(-self.theta)))

    def between(self, other: Pose) -> Pose:
        """self⁻¹ ⊕ other: ``other`` expressed in the frame of ``self``."""
        return self.inverse().compose(other)

    def transform_points(self, points: ArrayLike) -> FloatArray:
        """Map ``(N, 2)`` points from this pose's frame into its parent frame."""
        return transform_points(self.as_array(), points)

    def distance_to(self, other: Pose) -> float:
        return math.hypot(other.x - self.x, other.y - self.y)


def _as_pose_array(poses: ArrayLike) -> FloatArray:
    arr = np.asarray(poses, dtype=np.float64)
    if arr.shape[-1:] != (3,):
        raise ValueError(f"pose arrays need a last axis of 3 [x, y, theta], got shape {arr.shape}")
    return arr


def compose_arrays(a: ArrayLike, b: ArrayLike) -> FloatArray:
    """Element-wise a ⊕ b over broadcastable ``(..., 3)`` pose arrays."""
    a, b = _as_pose_array(a), _as_pose_array(b)
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    out = np.empty(np.broadcast_shapes(a.shape, b.shape), dtype=np.float64)
    out[..., 0] = a[..., 0] + c * b[..., 0] - s * b[..., 1]
    out[..., 1] = a[..., 1] + s * b[..., 0] + c * b[..., 1]
    out[..., 2] = wrap_angle(a[..., 2] + b[..., 2])
    return out


def invert_arrays(a: ArrayLike) -> FloatArray:
    """Element-wise a⁻¹ over a ``(..., 3)`` pose array."""
    a = _as_pose_array(a)
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    out = np.empty_like(a)
    out[..., 0] = -c * a[..., 0] - s * a[..., 1]
    out[..., 1] = s * a[..., 0] - c * a[..., 1]
    out[..., 2] = wrap_angle(-a[..., 2])
    return out


def between_arrays(a: ArrayLike, b: ArrayLike) -> FloatArray:
    """Element-wise a⁻¹ ⊕ b: each ``b`` expressed in the frame of the matching ``a``."""
    return compose_arrays(invert_arrays(a), b)


def transform_points(pose: ArrayLike, points: ArrayLike) -> FloatArray:
    """Map ``(N, 2)`` points from the frame of ``pose`` (``[x, y, theta]``) to its parent frame."""
    p = _as_pose_array(pose)
    pts = np.asarray(points, dtype=np.float64)
    if pts.shape[-1:] != (2,):
        raise ValueError(f"points need a last axis of 2 [x, y], got shape {pts.shape}")
    c, s = math.cos(p[2]), math.sin(p[2])
    out = np.empty_like(pts)
    out[..., 0] = p[0] + c * pts[..., 0] - s * pts[..., 1]
    out[..., 1] = p[1] + s * pts[..., 0] + c * pts[..., 1]
    return out
