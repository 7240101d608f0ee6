"""Invariants of the simulator itself: the robot keeps clear of obstacles, laser hits lie on them.

- ``robot_clear_of_obstacles``: the robot disc at every true pose keeps clear of every
  static wall and clutter segment (``check_robot_clear``) and, where the frames carry the
  moving obstacles' true poses, of every moving obstacle (``ClearanceChecker``): their
  outlines are placed at those poses and measured here with plain geometry, not with the
  simulator's own collision queries;
- ``laser_hits_on_obstacles``: every valid hit, placed by the true pose, lies on a static
  obstacle within a tolerance derived from the laser noise (``FrameChecker``), unless it is
  a mixed pixel: on its beam, between the exact ranges of a true depth jump.

Violations raise ``albot2d.evaluation.invariants.InvariantError`` like the mapper checks.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TypedDict, Unpack

import numpy as np
import shapely
from numpy.typing import NDArray

from albot2d.evaluation.checks.hit_geometry import SegmentGrid, ray_ranges
from albot2d.evaluation.checks.invariants import InvariantParams, fail
from albot2d.frames import Frame
from albot2d.geometry import Pose, point_segment_distance, polygon_ring_segments
from albot2d.sim.laser import LaserNoise
from worldgen.world import World

__all__ = ["ClearanceChecker", "FrameChecker", "SegmentGrid", "check_robot_clear"]

# A moving obstacle may touch the robot up to this deep (contacts solved by pymunk keep a
# sub-millimetre overlap); the bound for "never passes through the robot".
MOVING_OVERLAP_TOLERANCE_M = 0.01

FloatArray = NDArray[np.float64]


def _nearest_distance(tree: shapely.STRtree, points: FloatArray) -> FloatArray:
    if len(points) == 0:
        return np.zeros(0)
    (idx, _), dist = tree.query_nearest(
        shapely.points(points), return_distance=True, all_matches=False
    )
    out = np.full(len(points), np.inf)
    out[idx] = dist
    return out


def _segment_tree(segments: FloatArray) -> shapely.STRtree:
    return shapely.STRtree(shapely.linestrings(np.asarray(segments).reshape(-1, 2, 2)))


def check_robot_clear(
    obstacle_segments: FloatArray,
    true_poses: FloatArray,
    radius_m: float,
    tolerance_m: float = 1e-9,
) -> None:
    """The robot disc at every true pose keeps clear of every static obstacle segment."""
    if len(obstacle_segments) == 0 or len(true_poses) == 0:
        return
    dist = _nearest_distance(_segment_tree(obstacle_segments), np.asarray(true_poses)[:, :2])
    overlap = radius_m - dist
    if overlap.max() > tolerance_m:
        k = int(np.argmax(overlap))
        fail(
            "robot_clear_of_obstacles",
            f"frame row {k}: the robot (radius {radius_m} m) reaches {overlap[k]:.3g} m into "
            f"an obstacle at ({true_poses[k, 0]:.3f}, {true_poses[k, 1]:.3f})",
        )


def _overlap_with_ring(centres: FloatArray, ring: FloatArray, radius_m: float) -> FloatArray:
    """How deep a disc of ``radius_m`` at each of ``centres (B, 2)`` reaches into the polygon
    with edge segments ``ring (K, 4)``: radius minus the distance to the outline, plus that
    distance again when the centre lies inside (even-odd rule)."""
    dist = point_segment_distance(centres, ring).min(axis=1)
    x, y = centres[:, :1], centres[:, 1:]
    x1, y1, x2, y2 = ring[:, 0], ring[:, 1], ring[:, 2], ring[:, 3]
    with np.errstate(divide="ignore", invalid="ignore"):
        crosses = ((y1 > y) != (y2 > y)) & (x < x1 + (y - y1) * (x2 - x1) / (y2 - y1))
    inside = crosses.sum(axis=1) % 2 == 1
    return radius_m + np.where(inside, dist, -dist)


class CheckerOptions(TypedDict, total=False):
    """The optional keywords of ``ClearanceChecker`` that ``for_world`` passes on."""

    tolerance_m: float
    moving_tolerance_m: float
    batch: int
    raise_at_once: bool


class ClearanceChecker:
    """``robot_clear_of_obstacles`` pose by pose, static and moving obstacles alike.

    Feed it ``add(robot_xy, obstacle_poses)`` (or use it as an ``on_frame`` hook: frames
    carry their ``obstacle_poses``); poses are checked in batches. Each moving obstacle's
    outline (``moving_shapes[m]``, its own frame) is placed at its recorded true pose and
    the disc's overlap with it computed here with plain geometry (distance to the outline,
    even-odd inside test), independently of the simulator's collision queries. Overlaps
    deeper than ``tolerance_m`` (static) or ``moving_tolerance_m`` (moving) are violations;
    ``finish()`` returns their messages (or the first one raises at once). The deepest
    overlaps and the number of poses checked are kept as statistics.
    """

    def __init__(
        self,
        obstacle_segments: FloatArray,
        moving_shapes: Sequence[FloatArray],
        radius_m: float,
        *,
        tolerance_m: float = 1e-9,
        moving_tolerance_m: float = MOVING_OVERLAP_TOLERANCE_M,
        batch: int = 4096,
        raise_at_once: bool = True,
        names: Sequence[str] | None = None,
    ) -> None:
        self.segments = np.asarray(obstacle_segments, dtype=np.float64).reshape(-1, 4)
        self._tree = _segment_tree(self.segments) if len(self.segments) else None
        self.rings = [polygon_ring_segments(np.asarray(s, dtype=np.float64)) for s in moving_shapes]
        self.names = (
            list(names)
            if names is not None
            else [f"moving obstacle {m}" for m in range(len(self.rings))]
        )
        self.radius_m = float(radius_m)
        self.tolerance_m = tolerance_m
        self.moving_tolerance_m = moving_tolerance_m
        self.batch = batch
        self.raise_at_once = raise_at_once
        self._xy: list[tuple[float, float]] = []
        self._poses: list[FloatArray] = []
        self._rows: list[int] = []
        self.poses_checked = 0
        self.max_static_overlap_m = -math.inf
        self.max_moving_overlap_m = -math.inf
        self.static_overlaps = 0
        self.moving_overlaps = 0
        self.violations: list[str] = []

    @classmethod
    def for_world(
        cls, world: World, radius_m: float | None = None, **kwargs: Unpack[CheckerOptions]
    ) -> ClearanceChecker:
        """A checker for ``world``'s walls, clutter and moving obstacles."""
        obstacles = world.dynamic_obstacles
        return cls(
            world.obstacle_segments,
            [o.shape for o in obstacles],
            world.robot_radius_m if radius_m is None else radius_m,
            names=[f"dynamic_obstacles[{m}] ({o.kind})" for m, o in enumerate(obstacles)],
            **kwargs,
        )

    def add(
        self, robot_pose: Pose, obstacle_poses: FloatArray | None = None, row: int | None = None
    ) -> None:
        """One true robot pose and the moving obstacles' true poses ``(M, 3)`` then."""
        self._xy.append((robot_pose.x, robot_pose.y))
        if self.rings:
            poses = (
                np.full((len(self.rings), 3), np.nan)
                if obstacle_poses is None
                else np.asarray(obstacle_poses, dtype=np.float64).reshape(-1, 3)
            )
            if len(poses) != len(self.rings):
                raise ValueError(
                    f"{len(poses)} obstacle poses for {len(self.rings)} moving obstacles"
                )
            self._poses.append(poses)
        self._rows.append(self.poses_checked + len(self._rows) if row is None else row)
        if len(self._xy) >= self.batch:
            self._check_batch()

    def __call__(self, frame: Frame, travelled_m: float = 0.0) -> None:
        if frame.true_pose is None:
            raise ValueError("ClearanceChecker needs simulated frames (with a true pose)")
        self.add(frame.true_pose, frame.obstacle_poses, row=frame.index)

    def _check_batch(self) -> None:
        if not self._xy:
            return
        xy = np.array(self._xy, dtype=np.float64)
        rows = self._rows
        poses = np.stack(self._poses) if self._poses else None  # (B, M, 3)
        self._xy, self._poses, self._rows = [], [], []
        self.poses_checked += len(xy)
        if self._tree is not None:
            overlap = self.radius_m - _nearest_distance(self._tree, xy)
            k = int(np.argmax(overlap))
            self.max_static_overlap_m = max(self.max_static_overlap_m, float(overlap[k]))
            bad = overlap > self.tolerance_m
            self.static_overlaps += int(bad.sum())
            if bad.any():
                self._violation(
                    f"row {rows[k]}: the robot (radius {self.radius_m} m) reaches "
                    f"{overlap[k]:.3g} m into a wall or clutter at "
                    f"({xy[k, 0]:.3f}, {xy[k, 1]:.3f})"
                )
        if poses is None:
            return
        for m, ring in enumerate(self.rings):
            p = poses[:, m]
            known = np.flatnonzero(np.isfinite(p).all(axis=1))
            if len(known) == 0 or len(ring) == 0:
                continue
            p = p[known]
            c, s = np.cos(p[:, 2]), np.sin(p[:, 2])
            dx, dy = xy[known, 0] - p[:, 0], xy[known, 1] - p[:, 1]
            local = np.column_stack([c * dx + s * dy, -s * dx + c * dy])
            overlap = _overlap_with_ring(local, ring, self.radius_m)
            k = int(np.argmax(overlap))
            self.max_moving_overlap_m = max(self.max_moving_overlap_m, float(overlap[k]))
            bad = overlap > self.moving_tolerance_m
            self.moving_overlaps += int(bad.sum())
            if bad.any():
                j = int(known[k])
                self._violation(
                    f"row {rows[j]}: the robot (radius {self.radius_m} m) reaches "
                    f"{overlap[k]:.3g} m into {self.names[m]} at "
                    f"({xy[j, 0]:.3f}, {xy[j, 1]:.3f})"
                )

    def _violation(self, message: str) -> None:
        if self.raise_at_once:
            fail("robot_clear_of_obstacles", message)
        self.violations.append(message)

    def finish(self) -> list[str]:
        """Check what is buffered; the violations' messages (empty: the robot kept clear)."""
        self._check_batch()
        return self.violations


#: How far an exact hit, recomputed from its range, may lie from the segment it hit.
_ON_SEGMENT_M = 1e-6


class FrameChecker:
    """Checks each simulated frame's laser hits against the true obstacles (an ``on_frame``
    hook). Frames are buffered and their hits checked in batches; ``finish()`` checks the
    rest and raises the first violation (or, without ``raise_at_once``, returns the messages).

    A hit is on an obstacle when some obstacle segment lies within its tolerance; the
    candidates are found on a grid of the segments built here (``SegmentGrid``), and the
    distances measured with plain geometry, independently of the simulator's ray caster.

    A hit off every obstacle is still right when it is a mixed pixel, which the laser makes
    by design (``albot2d.sim.laser``): where the laser mixes pixels, a beam whose exact range
    and a neighbour's differ by more than ``mixed_pixel_min_jump_m`` may return a range
    between the two, and (``mixed_pixel_edges="occluding"``, the default) only where the two
    exact hits lie on different, unconnected segments: an occluding edge, never along one
    smooth wall (with angular jitter, at any such jump). Those beams' exact ranges are
    computed here, independently of the simulator's ray caster, by intersecting the rays
    with the obstacle segments.
    """

    def __init__(
        self,
        obstacle_segments: FloatArray,
        laser_noise: LaserNoise,
        params: InvariantParams | None = None,
        *,
        batch_frames: int = 64,
        raise_at_once: bool = True,
    ) -> None:
        self.params = params or InvariantParams()
        self.noise = laser_noise
        self.raise_at_once = raise_at_once
        self.batch_frames = batch_frames
        self.segments = np.asarray(obstacle_segments, dtype=np.float64).reshape(-1, 4)
        self._grid: SegmentGrid | None = None
        self._corner: NDArray[np.intp] | None = None
        self._frames: list[Frame] = []
        self.frames = 0
        self.hits = 0
        self.mixed_pixels = 0
        self.violations: list[str] = []

    def tolerance_m(self, ranges: FloatArray) -> FloatArray:
        """How far a hit at ``ranges`` may lie from the wall it hit."""
        p, nz = self.params, self.noise
        sigma = nz.range_sigma_m + nz.range_sigma_per_m * ranges
        lateral = ranges * math.sin(
            min(p.hit_sigmas * math.radians(nz.angle_jitter_deg), 0.5 * math.pi)
        )
        return p.hit_tolerance_m + p.hit_sigmas * sigma + 0.5 * nz.range_resolution_m + lateral

    def __call__(self, frame: Frame, travelled_m: float = 0.0) -> None:
        if frame.true_pose is None:
            raise ValueError("FrameChecker needs simulated frames (with a true pose)")
        self._frames.append(frame)
        self.frames += 1
        if len(self._frames) >= self.batch_frames:
            self._check_batch()

    def _hits(self, frames: list[Frame]) -> tuple[FloatArray, FloatArray, NDArray[np.intp]]:
        """Every valid hit of ``frames``: its world point (``Frame.world_hits``: the true
        pose applied to the robot-frame point, as ``transform_points`` does it), its range,
        and its beam's row in the batch's concatenated scans."""
        pts = np.vstack([f.world_hits() for f in frames])
        ranges = np.concatenate([f.scan.ranges for f in frames]).astype(np.float64, copy=False)
        beams = np.flatnonzero(np.concatenate([f.scan.valid for f in frames]))
        return pts, ranges[beams], beams

    @staticmethod
    def _beam_details(frames: list[Frame], beams: NDArray[np.intp]) -> dict[str, FloatArray]:
        """For the batch's beams ``beams`` (rows of the concatenated scans; only the few
        hits off every obstacle): frame index, laser origin, the world angles of the beam
        and its two neighbours (NaN past the scan's ends) and the scan's maximum range."""
        n = np.array([len(f.scan.ranges) for f in frames])
        ends = np.cumsum(n)
        fid = np.searchsorted(ends, beams, side="right")
        angles = np.concatenate([f.scan.angles for f in frames]).astype(np.float64, copy=False)
        frame, max_range = np.empty(len(beams)), np.empty(len(beams))
        origin, world = np.empty((len(beams), 2)), np.empty((len(beams), 3))
        for row, (i, b) in enumerate(zip(fid.tolist(), beams.tolist(), strict=True)):
            f = frames[i]
            assert f.true_pose is not None  # checked in __call__
            laser = f.true_pose @ f.scan.laser_pose
            first, last = int(ends[i] - n[i]), int(ends[i] - 1)
            frame[row], max_range[row] = f.index, f.scan.max_range_m
            origin[row] = (laser.x, laser.y)
            world[row] = (
                laser.theta + angles[b],
                laser.theta + angles[b - 1] if b > first else np.nan,
                laser.theta + angles[b + 1] if b < last else np.nan,
            )
        return {"frame": frame, "origin": origin, "angles": world, "max_range": max_range}

    def _mixed_pixels(
        self, details: dict[str, FloatArray], r: FloatArray, tol: FloatArray
    ) -> NDArray[np.bool_]:
        """Which off-obstacle hits (their ``_beam_details``, ranges ``r`` and tolerances
        ``tol``) are mixed pixels of a true depth jump (see the class)."""
        nz = self.noise
        if nz.mixed_pixel_prob == 0.0 or len(r) == 0:
            return np.zeros(len(r), dtype=bool)
        exact = ray_ranges(details["origin"], details["angles"], self.segments)
        exact[exact > details["max_range"][:, None]] = np.inf  # beyond the maximum range
        own = exact[:, 0]
        mixed = np.zeros(len(r), dtype=bool)
        for j in (1, 2):
            other = exact[:, j]
            with np.errstate(invalid="ignore"):
                jump = (
                    np.isfinite(own)
                    & np.isfinite(other)
                    & (np.abs(own - other) > nz.mixed_pixel_min_jump_m)
                )
                between = (np.minimum(own, other) - tol <= r) & (r <= np.maximum(own, other) + tol)
            jump &= between
            # A jittered beam is cast off its nominal angle, so which surfaces it straddled
            # is not known here: then any jump may mix.
            if nz.mixed_pixel_edges == "occluding" and nz.angle_jitter_deg == 0.0 and jump.any():
                k = np.flatnonzero(jump)
                o, a = details["origin"][k], details["angles"][k]
                p = o + own[k, None] * np.column_stack([np.cos(a[:, 0]), np.sin(a[:, 0])])
                q = o + other[k, None] * np.column_stack([np.cos(a[:, j]), np.sin(a[:, j])])
                jump[k[self._one_surface(p, q)]] = False
            mixed |= jump
        return mixed

    def _one_surface(self, p: FloatArray, q: FloatArray) -> NDArray[np.bool_]:
        """Whether the exact hits ``p[k]`` and ``q[k]`` lie on one smooth run of wall: some
        segment through each is the same or shares an endpoint with the other (plain
        distances to every segment, independent of the simulator's ``same_surface``)."""
        if self._corner is None:  # (N, 2): the ids of each segment's two ends
            ends = np.concatenate([self.segments[:, :2], self.segments[:, 2:]])
            _, ids = np.unique(ends, axis=0, return_inverse=True)
            self._corner = ids.reshape(2, -1).T
        corner = self._corner
        through_p = point_segment_distance(p, self.segments) <= _ON_SEGMENT_M
        through_q = point_segment_distance(q, self.segments) <= _ON_SEGMENT_M
        return np.array(
            [
                bool(np.intersect1d(corner[a].ravel(), corner[b].ravel()).size)
                for a, b in zip(through_p, through_q, strict=True)
            ],
            dtype=bool,
        )

    def _check_batch(self) -> None:
        if not self._frames:
            return
        frames, self._frames = self._frames, []
        pts, r, beams = self._hits(frames)
        tol = self.tolerance_m(r)
        self.hits += len(pts)
        if len(pts) == 0:
            return
        off = np.ones(len(pts), dtype=bool)
        if len(self.segments):
            reach = float(tol.max())
            if self._grid is None or self._grid.reach_m < reach:
                # Reach for the longest range the laser returns, so the grid is made once.
                longest_m = max(f.scan.max_range_m for f in frames)
                longest = float(self.tolerance_m(np.array([longest_m]))[0])
                self._grid = SegmentGrid(self.segments, max(reach, longest))
            off = ~self._grid.within(pts, tol)
        suspects = np.flatnonzero(off)
        if not len(suspects):
            return
        details = self._beam_details(frames, beams[suspects])
        mixed = self._mixed_pixels(details, r[suspects], tol[suspects])
        self.mixed_pixels += int(mixed.sum())
        off[suspects[mixed]] = False
        if off.any():
            k = int(np.flatnonzero(off)[0])
            frame = int(details["frame"][int(np.searchsorted(suspects, k))])
            dist = (
                _nearest_distance(_segment_tree(self.segments), pts[k : k + 1])[0]
                if len(self.segments)
                else math.inf
            )
            msg = (
                f"frame {frame}: {int(off.sum())} valid hit(s) off every "
                f"obstacle (and not mixed pixels), e.g. ({pts[k, 0]:.3f}, {pts[k, 1]:.3f}) "
                f"{dist:.3g} m away (tolerance {tol[k]:.3g} m)"
            )
            if self.raise_at_once:
                fail("laser_hits_on_obstacles", msg)
            self.violations.append(msg)

    def finish(self) -> list[str]:
        self._check_batch()
        return self.violations
