"""Loop closures for the ``slam`` mapper: candidates by proximity, verified by registration.

A candidate pairs the newest keyframe ``i`` with an older keyframe ``j`` that is far back
along the path (``min_separation_m``) but near under the current estimate (within a
radius that grows with the path driven since ``j``, the drift one must allow for).

Verification registers the two *local maps*, not single scans: the scans of the last
``submap_keyframes`` keyframes up to ``i`` (placed in ``i``'s frame by the current estimate)
against those of the keyframes around ``j`` (placed in ``j``'s frame by the current
estimate). Registration is KISS-ICP's point-to-map ICP (robust kernel, points lifted to a
few height layers as in the front end) started from the current estimate of the relative
pose; keyframe ``i``'s own scan is then registered from that result with a tight gate, so
the closure is about the keyframe's own pose. The result is accepted only if

- enough of the query points and of the scan's (``min_inlier_ratio``, ``min_inliers``,
  ``min_scan_inliers``) lie within ``inlier_distance_m`` of a target point, the ratio
  taken over the points the two maps share (within ``overlap_distance_m`` of a target
  point: a 180° scanner driven back along a corridor sees the other half of it), and
- the closure agrees with the current estimate within its uncertainty (``gate="chi2"``,
  the default): the closure's innovation (its relative pose against the estimate's) has
  a Mahalanobis distance² under the estimate's relative-pose covariance (the pose
  graph's marginals) plus the closure's own covariance of at most ``gate_chi2`` (χ² with
  3 degrees of freedom). ICP that slid along a corridor or snapped onto a look-alike
  room is rejected here, and after a long open stretch, where the graph itself says the
  heading may be several degrees off, a true closure is not. ``gate="fixed"`` is the
  older reading: a fixed drift allowance (``max_correction_m`` + ``max_correction_per_m``
  × path since ``j``, ``max_correction_deg``), applied by the verifier itself;
  ``gate="none"`` admits every registration-verified candidate and leaves the outlier
  decision to the back end (GNC, ``pose_graph``).

Short-range constraints (``local_separation_m``, 3 m by default) reuse the same
verification between a new keyframe and the keyframe a few metres back along the path.

An accepted closure carries the point-to-line Hessian of the scan's registration
(``registration_information``): the pose graph shapes the closure's information matrix by
it, so a closure in a corridor does not pin the position along the corridor.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from albot2d.errors import InputError
from albot2d.geometry import between_arrays, transform_points, wrap_angle
from albot2d.mapping.slam.front_end import se2_matrix_4x4
from albot2d.validation import (
    check_in_range,
    check_non_negative,
    check_positive,
    check_positive_int,
)

__all__ = [
    "GATES",
    "LOCAL_QUERIES",
    "ClosureCheck",
    "LoopClosureParams",
    "LoopVerifier",
    "registration_information",
    "voxel_downsample_2d",
]


GATES = ("chi2", "fixed", "none")
LOCAL_QUERIES = ("submap", "scan")


@dataclass(frozen=True, slots=True)
class LoopClosureParams:
    """Keyframing, candidate search and verification thresholds.

    - ``keyframe_distance_m`` / ``keyframe_angle_deg``: a new keyframe after this much motion
      since the last one (front-end estimate).
    - ``min_separation_m``: path length (front end) between two keyframes before they may
      close a loop.
    - ``search_radius_m`` + ``search_radius_per_m`` × path since the candidate, at most
      ``max_search_radius_m``: how far apart (current estimate) a candidate may be.
    - ``max_candidates``: nearest candidates verified per keyframe.
    - ``closure_spacing_m``: after an accepted closure, no candidate is searched for
      until the robot drove this far (front-end path), as hdl_graph_slam's
      ``min_edge_interval`` (5 m there): consecutive keyframes closing onto the same
      target local map share its registration error, and the graph would count them as
      independent (docs/albot-x.md). 0 (the default): every keyframe searches.
    - ``local_separation_m``: short-range constraints (as Cartographer's and Karto's
      constraints to nearby scans): every new keyframe is also registered, by the same
      verifier and gate as a closure, against the keyframe this far back along the path
      (the newest one at least this far back), so a front-end slip between the two is
      measured against an older scan that the slip did not smear. 3 m by default (with
      the chain's ``hessian_xy`` information and the GNC back end: the combination chosen
      on the office runs, the fig6 route and the MIT log, docs/albot-x.md); None: off.
      ``min_separation_m`` still bounds the loop-closure candidates.
      ``local_query``: what is registered: ``"submap"`` (as a closure: the last
      ``submap_keyframes`` keyframes up to the new one onto those around the older one
      that are not among them) or ``"scan"`` (the new keyframe's own scan onto the
      ``submap_keyframes`` keyframes up to the older one: scan-to-submap, Cartographer's
      reading, nothing in either the slip could have smeared).
    - ``submap_keyframes``: keyframes whose scans form a local map (query: the last ones up
      to ``i``; target: as many on each side of ``j``).
    - ``voxel_size_m``: voxel size of the registration map and of the query's downsampling.
    - ``max_correspondence_m`` / ``kernel_m``: ICP correspondence gate and robust kernel.
    - ``inlier_distance_m``, ``min_inlier_ratio``, ``min_inliers``: the fitness test of the
      local maps; ``min_scan_inliers``: of keyframe ``i``'s own scan after refinement.
      ``overlap_distance_m``: the ratio counts only the points within this distance of the
      other map (the part both saw: with a 180° scanner a corridor driven the other way is
      half new surfaces, neither evidence for nor against the match); None: all points.
    - ``gate``: ``"chi2"`` (the closure's innovation against the estimate's and its own
      covariance, at most ``gate_chi2``: 16.27 is χ²₃ at 99.9 %), ``"fixed"`` (the
      allowance below) or ``"none"`` (every candidate that passes the fitness tests is
      admitted: for a back end that weighs closures jointly, ``PoseGraphParams(optimizer=
      "gnc")``).
    - ``max_correction_m`` + ``max_correction_per_m`` × path since ``j``, and
      ``max_correction_deg`` + ``max_correction_deg_per_m`` × that path: with
      ``gate="fixed"``, the largest change to the current relative estimate accepted.
    """

    keyframe_distance_m: float = 0.5
    keyframe_angle_deg: float = 10.0
    min_separation_m: float = 10.0
    search_radius_m: float = 2.0
    search_radius_per_m: float = 0.02
    max_search_radius_m: float = 6.0
    max_candidates: int = 1
    closure_spacing_m: float = 0.0
    local_separation_m: float | None = 3.0
    local_query: str = "submap"
    submap_keyframes: int = 10
    voxel_size_m: float = 0.10
    max_correspondence_m: float = 1.0
    kernel_m: float = 0.2
    max_iterations: int = 100
    inlier_distance_m: float = 0.10
    min_inlier_ratio: float = 0.60
    overlap_distance_m: float | None = 1.0
    min_inliers: int = 60
    min_scan_inliers: int = 30
    max_correction_m: float = 0.5
    max_correction_per_m: float = 0.01
    max_correction_deg: float = 5.0
    max_correction_deg_per_m: float = 0.0
    gate: str = "chi2"
    gate_chi2: float = 16.27

    def __post_init__(self) -> None:
        if self.local_query not in LOCAL_QUERIES:
            raise InputError(f"LoopClosureParams.local_query must be one of "
                             f"{', '.join(LOCAL_QUERIES)}, got {self.local_query!r}")  # fmt: skip
        if self.gate not in GATES:
            raise InputError(
                f"LoopClosureParams.gate must be one of {', '.join(GATES)}, got {self.gate!r}"
            )
        check_positive(self, "keyframe_distance_m", "keyframe_angle_deg", "search_radius_m",
                       "max_search_radius_m", "voxel_size_m", "max_correspondence_m",
                       "kernel_m", "inlier_distance_m", "max_correction_m",
                       "max_correction_deg", "gate_chi2")  # fmt: skip
        if self.overlap_distance_m is not None:
            check_positive(self, "overlap_distance_m")
        if self.local_separation_m is not None:
            check_positive(self, "local_separation_m")
        check_non_negative(self, "min_separation_m", "search_radius_per_m", "closure_spacing_m",
                           "max_correction_per_m", "max_correction_deg_per_m")  # fmt: skip
        check_positive_int(self, "max_candidates", "submap_keyframes", "max_iterations",
                           "min_inliers", "min_scan_inliers")  # fmt: skip
        check_in_range(self, "min_inlier_ratio", 0.0, 1.0)


@dataclass(frozen=True, slots=True)
class ClosureCheck:
    """The verdict on one candidate: keyframe ``j`` registered into keyframe ``i``'s frame.

    ``relative`` is ``j``'s pose in ``i``'s frame after registration; ``reason`` is empty
    when accepted, else says which test failed; ``information`` is the registration's
    point-to-line Hessian of keyframe ``i``'s scan (``registration_information``; None if
    the scan registration was not reached); ``chi2``: the innovation's Mahalanobis
    distance² when the χ² gate judged it (None otherwise).
    """

    i: int
    j: int
    relative: NDArray[np.float64]
    inlier_ratio: float
    inliers: int
    correction_m: float
    correction_deg: float
    accepted: bool
    reason: str
    information: NDArray[np.float64] | None = None
    chi2: float | None = None


def voxel_downsample_2d(points: NDArray[np.float64], voxel_m: float) -> NDArray[np.float64]:
    """One point per ``voxel_m`` grid cell (the first in input order): deterministic."""
    if len(points) == 0:
        return points.reshape(0, 2)
    cells = np.floor(points / voxel_m).astype(np.int64)
    _, first = np.unique(cells, axis=0, return_index=True)
    return points[np.sort(first)]


def _nearest(
    query: NDArray[np.float64], target: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Distance from each query point to its nearest target point, and that point's index
    (chunked brute force)."""
    out = np.empty(len(query))
    index = np.empty(len(query), dtype=np.int64)
    # |q - t|² = |q|² + |t|² - 2 q·t as one matrix product per chunk (centred first, so
    # the cancellation costs nothing at centimetre scale)
    centre = target.mean(axis=0) if len(target) else np.zeros(2)
    t = target - centre
    t2 = (t**2).sum(axis=1)
    for start in range(0, len(query), 256):
        q = query[start : start + 256] - centre
        d2 = (q**2).sum(axis=1)[:, None] + t2[None, :] - 2.0 * (q @ t.T)
        nearest = d2.argmin(axis=1)
        index[start : start + 256] = nearest
        out[start : start + 256] = np.sqrt(np.maximum(d2[np.arange(len(q)), nearest], 0.0))
    return out, index


def _normals(
    target: NDArray[np.float64], index: NDArray[np.int64], radius_m: float
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """Unit surface normals at ``target[index]`` (the least-spread direction of the target
    points within ``radius_m``), and whether the neighbourhood is line-like enough to have
    one (≥ 3 points, spread along the line ≥ 4× across it)."""
    # per neighbourhood: point count, first and second moments (chunked, vectorised)
    products = np.column_stack([np.ones(len(target)), target, target[:, 0] ** 2,
                                target[:, 0] * target[:, 1], target[:, 1] ** 2])  # fmt: skip
    sums = np.empty((len(index), 6))
    for start in range(0, len(index), 256):
        centres = target[index[start : start + 256]]
        near = ((centres[:, None, :] - target[None, :, :]) ** 2).sum(axis=2) <= radius_m**2
        sums[start : start + 256] = near.astype(np.float64) @ products
    count = sums[:, 0]
    mean = sums[:, 1:3] / np.maximum(count, 1)[:, None]
    second = sums[:, 3:] / np.maximum(count, 1)[:, None]
    cov = np.empty((len(index), 2, 2))
    cov[:, 0, 0] = second[:, 0] - mean[:, 0] ** 2
    cov[:, 0, 1] = cov[:, 1, 0] = second[:, 1] - mean[:, 0] * mean[:, 1]
    cov[:, 1, 1] = second[:, 2] - mean[:, 1] ** 2
    values, vectors = np.linalg.eigh(cov)
    normals = vectors[:, :, 0]
    ok = (count >= 3) & (values[:, 1] > 0) & (values[:, 0] <= values[:, 1] / 16)
    return normals, ok


def registration_information(
    points: NDArray[np.float64], normals: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Point-to-line Gauss–Newton Hessian ``Σ JᵀJ`` (3×3, order x, y, θ) of registered
    ``points`` (target frame) on lines with unit ``normals``, for a perturbation of the
    relative pose in GTSAM's Pose2 local coordinates. Along a corridor the ``x, y``
    direction parallel to the walls has (near) zero information: the registration does
    not constrain it."""
    moment = normals[:, 1] * points[:, 0] - normals[:, 0] * points[:, 1]
    jac = np.column_stack([normals, moment])
    return jac.T @ jac


class LoopVerifier:
    """Registers a query local map onto a target local map with KISS-ICP and judges it."""

    def __init__(self, params: LoopClosureParams, heights: NDArray[np.float64]) -> None:
        from kiss_icp.mapping import VoxelHashMap
        from kiss_icp.registration import Registration

        self.params = params
        self._heights = heights
        self._map_cls: Any = VoxelHashMap
        self._registration: Any = Registration(
            max_num_iterations=params.max_iterations, convergence_criterion=1e-4,
            max_num_threads=1,
        )  # fmt: skip

    def _lift(self, points: NDArray[np.float64]) -> NDArray[np.float64]:
        n, k = len(points), len(self._heights)
        return np.column_stack([np.tile(points, (k, 1)), np.repeat(self._heights, n)])

    def _align(
        self, points: NDArray[np.float64], target_map: Any, start: NDArray[np.float64],
        max_correspondence_m: float, kernel_m: float,
    ) -> NDArray[np.float64]:  # fmt: skip
        matrix = self._registration.align_points_to_map(
            points=self._lift(points), voxel_map=target_map, initial_guess=se2_matrix_4x4(start),
            max_correspondance_distance=max_correspondence_m, kernel=kernel_m,
        )  # fmt: skip
        return np.array([matrix[0, 3], matrix[1, 3], np.arctan2(matrix[1, 0], matrix[0, 0])])

    def _fitness(
        self, pose: NDArray[np.float64], points: NDArray[np.float64], target: NDArray[np.float64]
    ) -> tuple[int, float]:
        distances, _ = _nearest(transform_points(pose, points), target)
        inliers = int(np.count_nonzero(distances <= self.params.inlier_distance_m))
        overlap = self.params.overlap_distance_m
        seen = len(points) if overlap is None else np.count_nonzero(distances <= overlap)
        return inliers, inliers / max(int(seen), 1)

    def check(
        self,
        i: int,
        j: int,
        query: NDArray[np.float64],
        scan: NDArray[np.float64],
        target: NDArray[np.float64],
        guess: NDArray[np.float64],
        path_m: float,
        estimate: NDArray[np.float64] | None = None,
    ) -> ClosureCheck:
        """Verify a candidate. ``query``: the local map of ``i`` in ``i``'s frame; ``scan``:
        keyframe ``i``'s own scan; ``target``: the local map of ``j`` in ``j``'s frame;
        ``guess``: ``i``'s pose in ``j``'s frame to start ICP from; ``estimate``: the same
        pose under the current map estimate, against which the correction is judged
        (default ``guess``); ``path_m``: path driven from ``j`` to ``i`` (sets the drift
        allowance).

        The local maps are registered first (a wide basin, many points); keyframe ``i``'s
        own scan is then registered from there with a tight gate, so the closure constrains
        the keyframe's own pose even if its neighbours' estimates disagree with it."""
        estimate = guess if estimate is None else estimate
        p = self.params
        query = voxel_downsample_2d(query, p.voxel_size_m)
        scan = voxel_downsample_2d(scan, p.voxel_size_m)
        target = voxel_downsample_2d(target, p.voxel_size_m / 2)
        if len(query) < p.min_inliers or len(target) < p.min_inliers:
            return self._verdict(i, j, guess, estimate, 0.0, 0, path_m, "too few points")
        voxel_map = self._map_cls(voxel_size=p.voxel_size_m * 2, max_distance=1e6,
                                  max_points_per_voxel=20)  # fmt: skip
        voxel_map.add_points(self._lift(target))
        pose = self._align(query, voxel_map, guess, p.max_correspondence_m, p.kernel_m)
        if not np.all(np.isfinite(pose)):
            return self._verdict(i, j, guess, estimate, 0.0, 0, path_m, "registration failed")
        inliers, ratio = self._fitness(pose, query, target)
        if inliers < p.min_inliers or ratio < p.min_inlier_ratio:
            reason = f"fitness: inlier ratio {ratio:.2f}, {inliers} inliers"
            return self._verdict(i, j, pose, estimate, ratio, inliers, path_m, reason)
        gate = 3 * p.inlier_distance_m
        refined = self._align(scan, voxel_map, pose, gate, p.inlier_distance_m)
        if not np.all(np.isfinite(refined)):
            return self._verdict(i, j, pose, estimate, ratio, inliers, path_m,
                                 "scan registration failed")  # fmt: skip
        scan_inliers, scan_ratio = self._fitness(refined, scan, target)
        reason = ""
        if scan_inliers < p.min_scan_inliers or scan_ratio < p.min_inlier_ratio:
            reason = f"scan fitness: inlier ratio {scan_ratio:.2f}, {scan_inliers} inliers"
        return self._verdict(i, j, refined, estimate, ratio, inliers, path_m, reason,
                             self._information(refined, scan, target))  # fmt: skip

    def chain_information(
        self,
        motion: NDArray[np.float64],
        previous: NDArray[np.float64],
        scan: NDArray[np.float64],
    ) -> NDArray[np.float64]:
        """The point-to-line Hessian of a keyframe-to-keyframe motion (the scan-matching
        chain factor ``previous → scan`` measuring ``motion``, the newer keyframe's pose in
        the previous one's frame): the previous keyframe's scan placed in the newer one's
        frame at the front end's estimate, on the newer scan's lines. That is a left
        perturbation of ``motion⁻¹``, i.e. the factor's own (right) perturbation of
        ``motion``, as for a closure."""
        p = self.params
        points = voxel_downsample_2d(previous, p.voxel_size_m)
        target = voxel_downsample_2d(scan, p.voxel_size_m / 2)
        if len(points) == 0 or len(target) == 0:
            return np.zeros((3, 3))
        return self._information(between_arrays(motion, np.zeros(3)), points, target)

    def _information(
        self, pose: NDArray[np.float64], points: NDArray[np.float64], target: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        """The point-to-line Hessian of ``points`` registered at ``pose`` onto ``target``:
        inliers only, normals from the target within 3 voxels (a wall's local line)."""
        placed = transform_points(pose, points)
        distances, index = _nearest(placed, target)
        inlier = distances <= self.params.inlier_distance_m
        normals, ok = _normals(target, index[inlier], 3 * self.params.voxel_size_m)
        return registration_information(placed[inlier][ok], normals[ok])

    def _verdict(
        self,
        i: int,
        j: int,
        pose: NDArray[np.float64],
        estimate: NDArray[np.float64],
        ratio: float,
        inliers: int,
        path_m: float,
        reason: str,
        information: NDArray[np.float64] | None = None,
    ) -> ClosureCheck:
        p = self.params
        change = between_arrays(estimate, pose)
        correction_m = float(np.hypot(change[0], change[1]))
        correction_deg = float(np.degrees(abs(wrap_angle(change[2]))))
        allowed_m = p.max_correction_m + p.max_correction_per_m * path_m
        allowed_deg = p.max_correction_deg + p.max_correction_deg_per_m * path_m
        beyond = correction_m > allowed_m or correction_deg > allowed_deg
        if not reason and p.gate == "fixed" and beyond:
            reason = (
                f"correction {correction_m:.2f} m / {correction_deg:.1f}° beyond the "
                f"drift allowance {allowed_m:.2f} m / {allowed_deg:.1f}°"
            )
        # relative: keyframe j seen from keyframe i (the between factor i → j)
        relative = between_arrays(pose, np.zeros(3))
        return ClosureCheck(i, j, relative, ratio, inliers, correction_m, correction_deg,
                            not reason, reason, information)  # fmt: skip
