"""Invariants of the simulator itself: the robot keeps clear of obstacles, laser hits lie on them.

- ``robot_clear_of_obstacles``: the robot disc at every true pose keeps clear of every
  static wall and clutter segment (moving obstacles are not static segments);
- ``laser_hits_on_obstacles``: every valid hit, placed by the true pose, lies on a static
  obstacle within a tolerance derived from the laser noise (``FrameChecker``); hits that
  may be mixed pixels (by design between two surfaces) are exempt.

Violations raise ``albot2d.evaluation.invariants.InvariantError`` like the mapper checks.
"""

from __future__ import annotations

import math

import numpy as np
import shapely
from numpy.typing import NDArray

from albot2d.evaluation.invariants import InvariantParams, fail
from albot2d.frames import Frame
from albot2d.geometry import transform_points
from albot2d.sim.laser import LaserNoise

__all__ = ["MIXED_PIXEL_REACH_BEAMS", "FrameChecker", "check_robot_clear"]

FloatArray = NDArray[np.float64]

# Beams this close to an observed depth jump may be mixed pixels (see FrameChecker).
MIXED_PIXEL_REACH_BEAMS = 2


def _nearest_distance(tree: shapely.STRtree, points: FloatArray) -> FloatArray:
    if len(points) == 0:
        return np.zeros(0)
    (idx, _), dist = tree.query_nearest(shapely.points(points), return_distance=True,
                                        all_matches=False)
    out = np.full(len(points), np.inf)
    out[idx] = dist
    return out


def _segment_tree(segments: FloatArray) -> shapely.STRtree:
    return shapely.STRtree(shapely.linestrings(np.asarray(segments).reshape(-1, 2, 2)))


def check_robot_clear(
    obstacle_segments: FloatArray, true_poses: FloatArray, radius_m: float,
    tolerance_m: float = 1e-9,
) -> None:
    """The robot disc at every true pose keeps clear of every static obstacle segment."""
    if len(obstacle_segments) == 0 or len(true_poses) == 0:
        return
    dist = _nearest_distance(_segment_tree(obstacle_segments), np.asarray(true_poses)[:, :2])
    overlap = radius_m - dist
    if overlap.max() > tolerance_m:
        k = int(np.argmax(overlap))
        fail("robot_clear_of_obstacles",
              f"frame row {k}: the robot (radius {radius_m} m) reaches {overlap[k]:.3g} m into "
              f"an obstacle at ({true_poses[k, 0]:.3f}, {true_poses[k, 1]:.3f})")


class FrameChecker:
    """Checks each simulated frame's laser hits against the true obstacles (an ``on_frame``
    hook). Hits are buffered and checked in batches; ``finish()`` checks the rest and
    raises the first violation (or, without ``raise_at_once``, returns the messages)."""

    def __init__(
        self, obstacle_segments: FloatArray, laser_noise: LaserNoise,
        params: InvariantParams | None = None, *, batch_frames: int = 64,
        raise_at_once: bool = True,
    ) -> None:
        self.params = params or InvariantParams()
        self.noise = laser_noise
        self.raise_at_once = raise_at_once
        self.batch_frames = batch_frames
        self._tree = _segment_tree(obstacle_segments) if len(obstacle_segments) else None
        self._points: list[FloatArray] = []
        self._tolerance: list[FloatArray] = []
        self._frames: list[FloatArray] = []
        self.frames = 0
        self.hits = 0
        self.violations: list[str] = []

    def tolerance_m(self, ranges: FloatArray) -> FloatArray:
        """How far a hit at ``ranges`` may lie from the wall it hit."""
        p, nz = self.params, self.noise
        sigma = nz.range_sigma_m + nz.range_sigma_per_m * ranges
        lateral = ranges * math.sin(min(p.hit_sigmas * math.radians(nz.angle_jitter_deg),
                                        0.5 * math.pi))
        return p.hit_tolerance_m + p.hit_sigmas * sigma + 0.5 * nz.range_resolution_m + lateral

    def mixed_pixel_candidates(self, ranges: FloatArray) -> NDArray[np.bool_]:
        """Beams that may be mixed pixels (a range blended between the two sides of a depth
        jump, by design off every obstacle): where the laser mixes pixels, every beam within
        ``MIXED_PIXEL_REACH_BEAMS`` of an observed jump, and the two end beams (one side
        unseen). Two jumps next to each other can blend two neighbouring beams, hiding the
        jump between them, hence a reach of two beams rather than one."""
        n = len(ranges)
        nz = self.noise
        if nz.mixed_pixel_prob == 0.0 or n < 2:
            return np.zeros(n, dtype=bool)
        pair_far = np.maximum(ranges[:-1], ranges[1:])
        jump = np.abs(np.diff(ranges)) > nz.mixed_pixel_min_jump_m - 2.0 * self.tolerance_m(
            pair_far)
        out = np.zeros(n, dtype=bool)
        reach = MIXED_PIXEL_REACH_BEAMS
        for shift in range(-reach + 1, reach + 1):  # pair a covers beams a-reach+1 … a+reach
            lo, hi = max(shift, 0), min(n - 1 + shift, n)
            out[lo:hi] |= jump[lo - shift : hi - shift]
        out[[0, -1]] = True
        return out

    def __call__(self, frame: Frame, travelled_m: float = 0.0) -> None:
        if frame.true_pose is None:
            raise ValueError("FrameChecker needs simulated frames (with a true pose)")
        scan = frame.scan
        checked = scan.valid & ~self.mixed_pixel_candidates(scan.ranges)
        pts = transform_points(frame.true_pose.as_array(), scan.points(valid_only=False)[checked])
        self._points.append(pts)
        self._tolerance.append(self.tolerance_m(scan.ranges[checked]))
        self._frames.append(np.full(len(pts), frame.index, dtype=np.float64))
        self.frames += 1
        if len(self._points) >= self.batch_frames:
            self._check_batch()

    def _check_batch(self) -> None:
        if not self._points:
            return
        pts = np.vstack(self._points)
        tol = np.concatenate(self._tolerance)
        frames = np.concatenate(self._frames)
        self._points, self._tolerance, self._frames = [], [], []
        self.hits += len(pts)
        if len(pts) == 0:
            return
        off = np.ones(len(pts), dtype=bool)
        if self._tree is not None:
            # A within-distance query is ~10× cheaper than nearest-distance for every hit.
            near, _ = self._tree.query(shapely.points(pts), predicate="dwithin", distance=tol)
            off[near] = False
        if off.any():
            k = int(np.flatnonzero(off)[0])
            dist = np.full(len(pts), np.inf)
            if self._tree is not None:
                dist[k] = _nearest_distance(self._tree, pts[k : k + 1])[0]
            msg = (f"frame {int(frames[k])}: {int(off.sum())} valid hit(s) off every obstacle, "
                   f"e.g. ({pts[k, 0]:.3f}, {pts[k, 1]:.3f}) {dist[k]:.3g} m away "
                   f"(tolerance {tol[k]:.3g} m)")
            if self.raise_at_once:
                fail("laser_hits_on_obstacles", msg)
            self.violations.append(msg)

    def finish(self) -> list[str]:
        self._check_batch()
        return self.violations
