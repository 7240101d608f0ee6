"""Exact synthetic scans for the perception tests: vectorised ray casting against segments.

Independent of ``albot2d.sim`` on purpose, so extraction and tracking are tested against
geometry computed here in closed form.
"""

from __future__ import annotations

import math

import numpy as np

from albot2d.frames import Scan, beam_angles
from albot2d.geometry import Pose, transform_segments

ORIGIN = Pose()

__all__ = ["ORIGIN", "box", "cast_ranges", "scan_of"]


def cast_ranges(segments: np.ndarray, angles: np.ndarray, max_range: float) -> np.ndarray:
    """Range of each ray from the origin to the nearest segment (``inf`` if none)."""
    s = np.asarray(segments, float).reshape(-1, 4)
    dx, dy = np.cos(angles)[:, None], np.sin(angles)[:, None]
    px, py = s[None, :, 0], s[None, :, 1]
    ex, ey = s[None, :, 2] - px, s[None, :, 3] - py
    denom = dx * ey - dy * ex
    with np.errstate(divide="ignore", invalid="ignore"):
        r = (px * ey - py * ex) / denom
        t = (px * dy - py * dx) / denom
    hit = (np.abs(denom) > 1e-12) & (r > 0.0) & (t >= 0.0) & (t <= 1.0)
    r = np.where(hit, r, np.inf).min(axis=1)
    return np.where(r < max_range, r, np.inf)


def scan_of(
    world: np.ndarray,
    pose: Pose = ORIGIN,
    *,
    n_beams: int = 361,
    fov_rad: float = math.pi,
    max_range: float = 30.0,
    noise_sigma: float = 0.0,
    rng: np.random.Generator | None = None,
    laser_pose: Pose = ORIGIN,
) -> Scan:
    """The scan a laser mounted at ``laser_pose`` on a robot at ``pose`` sees of ``world``."""
    angles = beam_angles(n_beams, fov_rad)
    sensor = pose.compose(laser_pose)
    local = transform_segments(sensor.inverse().as_array(), np.asarray(world, float))
    ranges = cast_ranges(local, angles, max_range)
    valid = np.isfinite(ranges)
    if noise_sigma > 0.0:
        gen = rng if rng is not None else np.random.default_rng(0)
        ranges = ranges + gen.normal(0.0, noise_sigma, n_beams)
    ranges = np.where(valid, ranges, max_range)
    return Scan(ranges, angles, valid, max_range, laser_pose=laser_pose)


def box(cx: float, cy: float, half_x: float, half_y: float) -> np.ndarray:
    """The four walls of an axis-aligned box, counter-clockwise."""
    x0, x1, y0, y1 = cx - half_x, cx + half_x, cy - half_y, cy + half_y
    return np.array([[x0, y0, x1, y0], [x1, y0, x1, y1], [x1, y1, x0, y1], [x0, y1, x0, y0]])
