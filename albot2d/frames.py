"""Sensor data value types shared by the simulator, log readers and mappers: ``Scan`` and ``Frame``.

A ``Scan`` is one laser sweep in the laser's own frame; a ``Frame`` is one step of a
run: the scan plus odometry (and, in simulation, the true pose). Simulated runs and
real CARMEN logs both become streams of ``Frame``s, so every mapper runs on both.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from albot2d.arrays import readonly
from albot2d.compiled import compiled_kernel
from albot2d.geometry import Pose, transform_points

__all__ = ["Frame", "Scan", "beam_angles"]

FloatArray = NDArray[np.float64]


def beam_angles(n_beams: int, fov_rad: float = math.pi, *, inclusive: bool = True) -> FloatArray:
    """Beam angles (radians, counter-clockwise, 0 = forward) of an ``n_beams`` sweep.

    ``inclusive=True`` spreads beams from -fov/2 to +fov/2 inclusive (step fov/(n-1): the
    181- and 361-beam SICK modes). ``inclusive=False`` uses step fov/n from -fov/2, the
    reading of CARMEN FLASER lines with 180 or 360 beams (-90° … +89°).
    """
    if n_beams < 2:
        raise ValueError(f"n_beams must be >= 2, got {n_beams}")
    step = fov_rad / (n_beams - 1) if inclusive else fov_rad / n_beams
    return -0.5 * fov_rad + step * np.arange(n_beams, dtype=np.float64)


@dataclass(frozen=True, eq=False)
class Scan:
    """One laser sweep, beams ordered right to left (counter-clockwise).

    - ``ranges``: ``(n,)`` metres. Where ``valid`` is False the value is not a hit
      (no return, dropout, or at/over ``max_range_m``) and must not be used as a point.
    - ``angles``: ``(n,)`` beam angles in the laser frame, radians.
    - ``laser_pose``: the laser's mount pose in the robot frame (REP-103: x forward).
    """

    ranges: FloatArray
    angles: FloatArray
    valid: NDArray[np.bool_]
    max_range_m: float
    timestamp: float = 0.0
    laser_pose: Pose = field(default_factory=Pose)

    def __post_init__(self) -> None:
        ranges = readonly(self.ranges, np.float64)
        angles = readonly(self.angles, np.float64)
        valid = readonly(self.valid, np.bool_)
        if not (ranges.ndim == angles.ndim == valid.ndim == 1):
            raise ValueError("Scan.ranges, angles and valid must be 1-D arrays")
        if not (len(ranges) == len(angles) == len(valid)):
            raise ValueError(
                f"Scan arrays differ in length: ranges {len(ranges)}, "
                f"angles {len(angles)}, valid {len(valid)}"
            )
        object.__setattr__(self, "ranges", ranges)
        object.__setattr__(self, "angles", angles)
        object.__setattr__(self, "valid", valid)

    @classmethod
    def adopt(
        cls,
        ranges: FloatArray,
        angles: FloatArray,
        valid: NDArray[np.bool_],
        max_range_m: float,
        timestamp: float,
        laser_pose: Pose,
    ) -> Scan:
        """A scan taking ownership of arrays its producer has just made, of the right
        dtypes and one length (the simulated laser, every step): ``ranges`` and ``valid``
        are made read-only, ``angles`` must be read-only already (shared between scans);
        nothing is copied or checked again."""
        if angles.flags.writeable:
            raise ValueError("Scan.adopt shares angles between scans: pass a read-only array")
        ranges.flags.writeable = False
        valid.flags.writeable = False
        out = object.__new__(cls)
        # Frozen: the fields go straight into the instance dict (what __init__ would set).
        out.__dict__.update(
            ranges=ranges, angles=angles, valid=valid, max_range_m=max_range_m,
            timestamp=timestamp, laser_pose=laser_pose,
        )  # fmt: skip
        return out

    def __repr__(self) -> str:
        hits = self.ranges[self.valid]
        span = f", {hits.min():.3g}–{hits.max():.3g} m" if len(hits) else ""
        return (
            f"Scan({self.n_beams} beams, {int(self.valid.sum())} valid{span}, "
            f"max_range_m={self.max_range_m:g}, timestamp={self.timestamp:.6g})"
        )

    @property
    def n_beams(self) -> int:
        return len(self.ranges)

    def points_laser(self) -> FloatArray:
        """``(n, 2)`` points of every beam in the laser frame (invalid beams included)."""
        r, a = self.ranges, self.angles
        return np.column_stack([r * np.cos(a), r * np.sin(a)])

    def points(self, *, valid_only: bool = True) -> FloatArray:
        """Hit points in the robot frame (laser mount applied); ``(k, 2)``."""
        pts = self.points_laser()
        if valid_only:
            pts = pts[self.valid]
        return transform_points(self.laser_pose.as_array(), pts)


@dataclass(frozen=True, eq=False)
class Frame:
    """One step of a run.

    - ``odom_pose``: the integrated (possibly noisy) odometry pose, odometry frame.
    - ``odom_increment``: ``prev_odom_pose⁻¹ ⊕ odom_pose``, the measured motion since the
      previous frame in the previous robot frame (identity for the first frame).
    - ``true_pose``: ground truth in the world frame; ``None`` for real logs.
    - ``collided``: the motion into this frame was blocked by an obstacle.
    - ``obstacle_poses``: in simulation, the true poses ``(M, 3)`` of the world's moving
      obstacles (``World.dynamic_obstacles`` order) at this frame; ``None`` otherwise.
    """

    index: int
    timestamp: float
    scan: Scan
    odom_pose: Pose
    odom_increment: Pose
    true_pose: Pose | None = None
    collided: bool = False
    obstacle_poses: FloatArray | None = None

    def __post_init__(self) -> None:
        if self.obstacle_poses is not None:
            poses = readonly(self.obstacle_poses, np.float64).reshape(-1, 3)
            object.__setattr__(self, "obstacle_poses", poses)

    def world_hits(self) -> FloatArray:
        """``(k, 2)`` read-only: the scan's valid hits in the world frame, by the laser mount
        and then ``true_pose`` (exactly ``transform_points(true_pose, scan.points())``), kept
        with the frame: the run's trace and the laser-hit check both read them."""
        got = self.__dict__.get("_world_hits")
        if got is not None:
            return got
        true = self.true_pose
        if true is None:
            raise ValueError(f"frame {self.index} has no true pose: no world hits")
        kernel = _hits_kernel()
        scan = self.scan
        if kernel is None:
            got = transform_points(true.as_array(), scan.points())
        else:
            mount = scan.laser_pose
            got = kernel(
                scan.ranges, np.cos(scan.angles), np.sin(scan.angles), scan.valid,
                mount.x, mount.y, math.cos(mount.theta), math.sin(mount.theta),
                true.x, true.y, math.cos(true.theta), math.sin(true.theta),
            )  # fmt: skip
        got.flags.writeable = False
        object.__setattr__(self, "_world_hits", got)
        return got

    def __repr__(self) -> str:
        return (
            f"Frame(index={self.index}, timestamp={self.timestamp:.6g}, "
            f"odom_pose={self.odom_pose!r}, true_pose={self.true_pose!r}, "
            f"collided={self.collided}, scan={self.scan!r})"
        )


def _hits_kernel() -> Callable[..., Any] | None:
    """``geometry.points_numba.hits_kernel`` when numba imports, else None."""
    return compiled_kernel("albot2d.geometry.points_numba", "hits_kernel")
