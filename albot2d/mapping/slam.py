"""``ScanMatchingSLAM``: the paper's Albot_x as a scan-matching mapper (optional ``[slam]`` extra).

Every scan is registered against a local voxel map by KISS-ICP (PRBonn, MIT licence), with
the odometry increment as the prediction; the view's surfaces are then placed at the
registered pose and integrated into one map without deletion, like ``NaiveIntegration``
(same surface extraction, same ``GlobalMap.insert``), so the maps are comparable.

KISS-ICP is a 3D pipeline. A 2D scan is lifted to 3D by copying its points to a few fixed
heights (``layer_heights_m``): walls become vertical planes, so roll and pitch are
constrained, and z stays put because nearest neighbours stay in their own layer. Deskewing
is off (a scan is one instant here); the registered 4×4 pose is projected back to SE(2)
after every scan and written back, so the out-of-plane components cannot accumulate.
Scans with fewer than ``min_points`` hits are placed by odometry alone.

It is scan-to-map odometry: KISS-ICP has no loop closure, so drift is reduced, not
removed. One registration thread keeps runs bit-for-bit reproducible.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from albot2d.errors import InputError
from albot2d.frames import Frame
from albot2d.geometry import Pose
from albot2d.mapping.baselines import _ViewIntegrator
from albot2d.mapping.protocol import MapperCounts
from albot2d.perception import ExtractionParams
from albot2d.validation import check_non_negative, check_positive, check_positive_int

__all__ = ["ScanMatchingParams", "ScanMatchingSLAM"]

MISSING_EXTRA = "the slam mapper needs the optional extra: pip install 'albot2d[slam]'"


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

    def __post_init__(self) -> None:
        check_positive(self, "voxel_size_m", "max_range_m", "initial_threshold_m",
                       "convergence")  # fmt: skip
        check_non_negative(self, "min_range_m", "min_motion_m")
        check_positive_int(self, "max_points_per_voxel", "max_iterations", "min_points")
        if self.fixed_threshold_m is not None:
            check_positive(self, "fixed_threshold_m")
        if self.min_range_m >= self.max_range_m:
            raise InputError(
                f"ScanMatchingParams.min_range_m ({self.min_range_m}) must be below "
                f"max_range_m ({self.max_range_m})"
            )
        heights = tuple(float(h) for h in self.layer_heights_m)
        if len(heights) < 2 or len(set(heights)) != len(heights) or not all(
            np.isfinite(heights)
        ):
            raise InputError(
                "ScanMatchingParams.layer_heights_m needs at least 2 distinct finite heights "
                f"(one layer leaves roll and pitch unconstrained), got {self.layer_heights_m!r}"
            )
        object.__setattr__(self, "layer_heights_m", heights)


def _se2_matrix(pose: NDArray[np.float64]) -> NDArray[np.float64]:
    c, s = np.cos(pose[2]), np.sin(pose[2])
    out = np.eye(4)
    out[:2, :2] = [[c, -s], [s, c]]
    out[:2, 3] = pose[:2]
    return out


def _planar(matrix: NDArray[np.float64]) -> NDArray[np.float64]:
    """(x, y, yaw) of a 4×4 pose: its projection onto the plane."""
    return np.array([matrix[0, 3], matrix[1, 3], np.arctan2(matrix[1, 0], matrix[0, 0])])


class ScanMatchingSLAM(_ViewIntegrator):
    """Albot_x with scan matching: views placed at KISS-ICP poses (odometry as the prior).

    Counts: ``triangulations`` are the views localised by scan matching (the sensor
    corrected the odometry), ``path_integrations`` those placed by odometry alone.
    """

    name = "slam"

    def __init__(
        self,
        params: ScanMatchingParams | None = None,
        extraction: ExtractionParams | None = None,
    ) -> None:
        try:
            from kiss_icp.config import KISSConfig
            from kiss_icp.kiss_icp import KissICP
        except ImportError as exc:
            raise InputError(MISSING_EXTRA) from exc
        super().__init__(extraction)
        self.params = params or ScanMatchingParams()
        self._icp: Any = KissICP(self._config(KISSConfig()))
        self._heights = np.asarray(self.params.layer_heights_m, dtype=np.float64)
        self._matched = 0
        self._dead_reckoned = 0

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

    def _lift(self, points: NDArray[np.float64]) -> NDArray[np.float64]:
        n, k = len(points), len(self._heights)
        return np.column_stack([np.tile(points, (k, 1)), np.repeat(self._heights, n)])

    def _source_pose(self, frame: Frame) -> Pose:
        icp = self._icp
        # KISS-ICP predicts last_pose @ last_delta: the odometry increment is the prior.
        delta = _se2_matrix(frame.odom_increment.as_array())
        predicted = _planar(icp.last_pose @ delta)
        points = frame.scan.points()
        estimate = None
        if len(points) >= self.params.min_points:
            had_map = not icp.local_map.empty()
            with self.timer.stage("scan_matching"):
                icp.last_delta = delta
                lifted = self._lift(points)
                icp.register_frame(lifted, np.zeros(len(lifted)))
            estimate = _planar(icp.last_pose)
            if np.all(np.isfinite(estimate)):
                self._matched += had_map  # the first scan only starts the map
            else:
                estimate = None
        if estimate is None:
            estimate = predicted
            self._dead_reckoned += bool(self._poses)
        icp.last_pose = _se2_matrix(estimate)
        return Pose.from_array(estimate)

    def counts(self) -> MapperCounts:
        n = len(self._poses)
        return MapperCounts(n, n, triangulations=self._matched,
                            path_integrations=self._dead_reckoned)  # fmt: skip
