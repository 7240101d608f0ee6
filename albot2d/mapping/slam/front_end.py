"""The ``slam`` and ``scan_odometry`` mappers' front end: KISS-ICP scan-to-map odometry.

Every scan is registered against a local voxel map by KISS-ICP (PRBonn, MIT licence), with
the odometry increment as the prediction (``KissIcpOdometry``, settings in
``ScanMatchingParams``).

KISS-ICP is a 3D pipeline. A 2D scan is lifted to 3D by copying its points to a few fixed
heights (``layer_heights_m``): walls become vertical planes, so roll and pitch are
constrained, and z stays put because nearest neighbours stay in their own layer. Deskewing
is off (a scan is one instant here); the registered 4×4 pose is projected back to SE(2)
after every scan and written back, so the out-of-plane components cannot accumulate.
Scans with fewer than ``min_points`` hits are placed by odometry alone. One registration
thread keeps runs bit-for-bit reproducible.

The prior (``ScanMatchingParams.prior``): KISS-ICP starts from the odometry increment
(``"odometry"``), or first registers the scan against the previous scan alone, from the
odometry increment, and starts the scan-to-map registration from that (``"scan_to_scan"``,
the LOAM split of scan-to-scan odometry and scan-to-map refinement; ``"scan_to_scan_heading"``
keeps the odometry's translation and takes only the heading from it; ``"gated"`` does that
only where the two headings disagree by more than ``prior_gate_deg``). Why (docs/albot-x.md, MIT
log): the log's odometry overstates fast turns (30° between two scans where the relations
say 17°), and scan-to-map ICP against a local map already smeared by earlier turns stays
near such a prior (from 30° it stops at 26°), while the previous scan alone pulls it to
16.9° from any start between 12° and 30°. Each registration has its own KISS-ICP adaptive
threshold, fed by the deviation from its own prediction.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from albot2d.errors import InputError
from albot2d.frames import Frame
from albot2d.geometry import between_arrays, wrap_angle
from albot2d.mapping.protocol import StageTimer
from albot2d.validation import check_non_negative, check_positive, check_positive_int

__all__ = [
    "MISSING_EXTRA",
    "PRIORS",
    "KissIcpOdometry",
    "ScanMatchingParams",
    "lift_points",
]

MISSING_EXTRA = "the slam mapper needs the optional extra: pip install 'albot2d[slam]'"
PRIORS = ("odometry", "scan_to_scan", "scan_to_scan_heading", "gated")


@dataclass(frozen=True, slots=True)
class ScanMatchingParams:
    """KISS-ICP settings for indoor 2D scans.

    - ``voxel_size_m``: map voxel size; scans are downsampled to 0.5× and 1.5× of it.
    - ``max_range_m`` / ``min_range_m``: hits used, and how far map points are kept.
    - ``max_points_per_voxel``: map points kept per voxel.
    - ``initial_threshold_m``: correspondence sigma before any motion is seen (the adaptive
      threshold then follows the deviation of ICP from the odometry prediction).
    - ``fixed_threshold_m``: use this sigma throughout instead (None: adaptive).
    - ``min_motion_m``: motion below which a scan does not update the adaptive threshold.
    - ``layer_heights_m``: heights at which each 2D point is copied (see the module doc).
    - ``max_iterations`` / ``convergence``: ICP stopping rules.
    - ``min_points``: fewer hits than this and the scan is placed by odometry alone.
    - ``map_update_m`` / ``map_update_deg``: every scan is registered, but it joins the
      local map only once the registered pose moved this far (or turned this much) since
      the last scan that joined it (keyframe-based map insertion, as in LiDAR odometry
      such as LIO-SAM's 1 m / 0.2 rad). 0 (the default): every scan joins the map,
      KISS-ICP's own behaviour. Measured (docs/albot-x.md): 0.5 m / 10° cures the front end's drift
      on the paper's fig6 route with dense views (2–4 m → ≤ 0.1 m at the end with loop
      closing) but loses track on the MIT log (RPE 0.38 → 1.56 m), so it is not the default.
    - ``prior``: where scan-to-map registration starts (see the module doc): ``"odometry"``
      (KISS-ICP with the odometry increment as its motion model), ``"scan_to_scan"`` (the
      scan registered against the previous scan first) or ``"scan_to_scan_heading"`` (the
      odometry's translation with that registration's heading) or ``"gated"`` (the
      odometry, unless the scan-to-scan heading differs from it by more than
      ``prior_gate_deg``; then ``"scan_to_scan_heading"``: a registration's per-scan
      heading noise adds up with dense views, so it is used only where the odometry is
      plainly wrong).
    - ``prior_gate_deg``: that disagreement (per scan) for ``"gated"``.
    """

    voxel_size_m: float = 0.20
    max_range_m: float = 30.0
    min_range_m: float = 0.05
    max_points_per_voxel: int = 20
    initial_threshold_m: float = 0.5
    fixed_threshold_m: float | None = None
    min_motion_m: float = 0.1
    layer_heights_m: tuple[float, ...] = (-0.5, 0.0, 0.5)
    max_iterations: int = 500
    convergence: float = 1e-4
    min_points: int = 20
    map_update_m: float = 0.0
    map_update_deg: float = 0.0
    prior: str = "odometry"
    prior_gate_deg: float = 2.0

    def __post_init__(self) -> None:
        if self.prior not in PRIORS:
            raise InputError(
                f"ScanMatchingParams.prior must be one of {', '.join(PRIORS)}, got {self.prior!r}"
            )
        check_positive(self, "voxel_size_m", "max_range_m", "initial_threshold_m",
                       "convergence", "prior_gate_deg")  # fmt: skip
        check_non_negative(self, "min_range_m", "min_motion_m", "map_update_m",
                           "map_update_deg")  # fmt: skip
        check_positive_int(self, "max_points_per_voxel", "max_iterations", "min_points")
        if self.fixed_threshold_m is not None:
            check_positive(self, "fixed_threshold_m")
        if self.min_range_m >= self.max_range_m:
            raise InputError(
                f"ScanMatchingParams.min_range_m ({self.min_range_m}) must be below "
                f"max_range_m ({self.max_range_m})"
            )
        heights = tuple(float(h) for h in self.layer_heights_m)
        if len(heights) < 2 or len(set(heights)) != len(heights) or not all(np.isfinite(heights)):
            raise InputError(
                "ScanMatchingParams.layer_heights_m needs at least 2 distinct finite heights "
                f"(one layer leaves roll and pitch unconstrained), got {self.layer_heights_m!r}"
            )
        object.__setattr__(self, "layer_heights_m", heights)


def se2_matrix_4x4(pose: NDArray[np.float64]) -> NDArray[np.float64]:
    """``[x, y, theta]`` as the 4×4 homogeneous transform KISS-ICP works in (z = 0)."""
    c, s = np.cos(pose[2]), np.sin(pose[2])
    out = np.eye(4)
    out[:2, :2] = [[c, -s], [s, c]]
    out[:2, 3] = pose[:2]
    return out


def _planar(matrix: NDArray[np.float64]) -> NDArray[np.float64]:
    """(x, y, yaw) of a 4×4 pose: its projection onto the plane."""
    return np.array([matrix[0, 3], matrix[1, 3], np.arctan2(matrix[1, 0], matrix[0, 0])])


class KissIcpOdometry:
    """The scan-matching front end: each frame's pose by KISS-ICP, odometry as the prior.

    Poses are in the front end's own frame (the first frame's pose is the identity). The
    ``slam`` mapper builds its pose graph on these poses; ``scan_odometry`` uses them as is.
    """

    def __init__(self, params: ScanMatchingParams, timer: StageTimer) -> None:
        try:
            from kiss_icp.config import KISSConfig
            from kiss_icp.kiss_icp import KissICP
        except ImportError as exc:
            raise InputError(MISSING_EXTRA) from exc
        self.params = params
        self.timer = timer
        self._icp: Any = KissICP(self._config(KISSConfig()))
        self._heights = np.asarray(params.layer_heights_m, dtype=np.float64)
        self.frames = 0
        self.matched = 0
        self.dead_reckoned = 0
        self._inserted: NDArray[np.float64] | None = None  # pose of the last scan mapped
        # scan-to-scan prior: the previous scan as a one-scan map, and a second adaptive
        # threshold for scan-to-map (its prediction is then the scan-to-scan result)
        self._previous: Any = None
        self.prior_switches = 0  # scans where "gated" took the scan-to-scan heading
        self._map_threshold: Any = None
        if params.prior != "odometry":
            from kiss_icp.threshold import get_threshold_estimator

            self._map_threshold = get_threshold_estimator(self._icp.config)

    def _config(self, config: Any) -> Any:
        p = self.params
        config.data.deskew = False
        config.data.max_range = p.max_range_m
        config.data.min_range = p.min_range_m
        config.mapping.voxel_size = p.voxel_size_m
        config.mapping.max_points_per_voxel = p.max_points_per_voxel
        config.registration.max_num_iterations = p.max_iterations
        config.registration.convergence_criterion = p.convergence
        config.registration.max_num_threads = 1  # a fixed reduction order: reproducible runs
        config.adaptive_threshold.initial_threshold = p.initial_threshold_m
        config.adaptive_threshold.fixed_threshold = p.fixed_threshold_m
        config.adaptive_threshold.min_motion_th = p.min_motion_m
        return config

    def lift(self, points: NDArray[np.float64]) -> NDArray[np.float64]:
        """``(N, 2)`` points copied to every layer height: ``(N·layers, 3)``."""
        return lift_points(points, self._heights)

    def _register_frame(self, lifted: NDArray[np.float64]) -> None:
        """KISS-ICP's ``register_frame`` step by step, but the scan joins the local map only
        once the pose moved ``map_update_m`` / ``map_update_deg`` since the last scan that
        joined it."""
        icp, p = self._icp, self.params
        frame = icp.preprocessor.preprocess(lifted, np.zeros(len(lifted)), icp.last_delta)
        source, downsampled = icp.voxelize(frame)
        sigma = icp.adaptive_threshold.get_threshold()
        guess = icp.last_pose @ icp.last_delta
        prior = self._scan_to_scan(source, sigma, guess)
        map_threshold = self._map_threshold or icp.adaptive_threshold
        map_sigma = map_threshold.get_threshold()
        new_pose = icp.registration.align_points_to_map(
            points=source, voxel_map=icp.local_map, initial_guess=prior,
            max_correspondance_distance=3 * map_sigma, kernel=map_sigma,
        )  # fmt: skip
        icp.adaptive_threshold.update_model_deviation(np.linalg.inv(guess) @ new_pose)
        if self._map_threshold is not None:
            self._map_threshold.update_model_deviation(np.linalg.inv(prior) @ new_pose)
        planar = _planar(new_pose)
        if self._inserted is None:
            moved = True
        else:
            step = between_arrays(self._inserted, planar)
            moved = bool(np.hypot(step[0], step[1]) >= p.map_update_m
                         or np.degrees(abs(step[2])) >= p.map_update_deg)  # fmt: skip
        if moved and np.all(np.isfinite(planar)):
            icp.local_map.update(downsampled, new_pose)
            self._inserted = planar
        if self._map_threshold is not None:
            from kiss_icp.mapping import VoxelHashMap

            self._previous = VoxelHashMap(voxel_size=p.voxel_size_m, max_distance=1e6,
                                          max_points_per_voxel=p.max_points_per_voxel)  # fmt: skip
            self._previous.add_points(downsampled)
        icp.last_delta = np.linalg.inv(icp.last_pose) @ new_pose
        icp.last_pose = new_pose

    def _scan_to_scan(
        self, source: NDArray[np.float64], sigma: float, guess: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        """The scan-to-map prior: ``guess`` (odometry), or the scan registered against the
        previous scan from there (``prior`` option; its translation replaced by the
        odometry's with ``"scan_to_scan_heading"`` and ``"gated"``, which keeps ``guess``
        unless the headings disagree by more than ``prior_gate_deg``)."""
        icp = self._icp
        if self._previous is None:
            return guess
        delta = icp.registration.align_points_to_map(
            points=source, voxel_map=self._previous, initial_guess=icp.last_delta,
            max_correspondance_distance=3 * sigma, kernel=sigma,
        )  # fmt: skip
        if not np.all(np.isfinite(delta)):
            return guess
        prior = self.params.prior
        if prior != "scan_to_scan":
            odom, scan = _planar(icp.last_delta), _planar(delta)
            gap = np.degrees(abs(float(wrap_angle(scan[2] - odom[2]))))
            if prior == "gated" and gap <= self.params.prior_gate_deg:
                return guess
            delta = se2_matrix_4x4(np.array([odom[0], odom[1], scan[2]]))
            self.prior_switches += prior == "gated"
        return np.asarray(icp.last_pose @ delta)

    def register(self, frame: Frame) -> NDArray[np.float64]:
        """The frame's ``(x, y, yaw)`` in the front end's frame."""
        icp = self._icp
        # KISS-ICP predicts last_pose @ last_delta: the odometry increment is the prior.
        delta = se2_matrix_4x4(frame.odom_increment.as_array())
        predicted = _planar(icp.last_pose @ delta)
        points = frame.scan.points()
        estimate = None
        if len(points) >= self.params.min_points:
            had_map = not icp.local_map.empty()
            with self.timer.stage("scan_matching"):
                icp.last_delta = delta
                self._register_frame(self.lift(points))
            estimate = _planar(icp.last_pose)
            if np.all(np.isfinite(estimate)):
                self.matched += had_map  # the first scan only starts the map
            else:
                estimate = None
        if estimate is None:
            estimate = predicted
            self.dead_reckoned += self.frames > 0
        icp.last_pose = se2_matrix_4x4(estimate)
        self.frames += 1
        return estimate


def lift_points(points: NDArray[np.float64], heights: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(N, 2)`` points copied to every height in ``heights``: ``(N·len(heights), 3)``."""
    n, k = len(points), len(heights)
    return np.column_stack([np.tile(points, (k, 1)), np.repeat(heights, n)])
