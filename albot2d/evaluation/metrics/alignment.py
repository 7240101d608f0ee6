"""Frames of a mapper's results, and the absolute pose error after SE(2) alignment.

Every mapper reports its trajectory and its map in *its own* frame: the first view it
observed is the origin (x forward, y left, REP-103). The simulator's truth is in the
*world* frame. ``in_world_frame`` / ``map_in_world_frame`` put a mapper's poses or map
where they would be if it had started at ``start_pose`` (in simulation the first true
pose: ``trace.true_poses[0]``), so drift shows against the true walls.

``absolute_pose_error`` is the APE of the field's tools (evo's ``evo_ape --align``):
the estimate is rigidly aligned to the reference by Umeyama's least-squares method
without scale (a rotation and a translation in the plane), then the position error
(m) and heading error (deg) of every pose are summarised. ``evo_ape`` computes the same
numbers from the TUM files of a run folder (``albot2d.evaluation.run.export``).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from albot2d.errors import InputError
from albot2d.geometry import Pose, compose_arrays, transform_segments, wrap_angle

__all__ = [
    "AbsolutePoseError",
    "absolute_pose_error",
    "align_se2",
    "ape_result",
    "evo_absolute_pose_error",
    "evo_pose_errors",
    "in_world_frame",
    "map_in_world_frame",
]

FloatArray = NDArray[np.float64]


def _pose_array(pose: Pose | ArrayLike) -> FloatArray:
    return pose.as_array() if isinstance(pose, Pose) else np.asarray(pose, dtype=np.float64)


def in_world_frame(poses: ArrayLike, start_pose: Pose | ArrayLike) -> FloatArray:
    """A mapper's ``(F, 3)`` poses (first view = origin) expressed in the world frame,
    given the world pose of its first view: ``start_pose ⊕ pose`` for each pose."""
    poses = np.asarray(poses, dtype=np.float64).reshape(-1, 3)
    return compose_arrays(_pose_array(start_pose), poses)


def map_in_world_frame(segments: ArrayLike, start_pose: Pose | ArrayLike) -> FloatArray:
    """A mapper's ``(M, 4)`` map segments expressed in the world frame (see above)."""
    return transform_segments(_pose_array(start_pose), np.asarray(segments, dtype=np.float64))


def align_se2(estimate_xy: ArrayLike, reference_xy: ArrayLike) -> tuple[float, FloatArray]:
    """Umeyama (1991) without scale in the plane: the rotation angle θ and translation t
    minimising Σ‖R(θ)·e + t − r‖² over corresponding ``(N, 2)`` positions."""
    e = np.asarray(estimate_xy, dtype=np.float64)
    r = np.asarray(reference_xy, dtype=np.float64)
    if e.shape != r.shape or e.ndim != 2 or e.shape[1] != 2 or len(e) < 2:
        raise InputError(f"alignment needs two (N, 2) arrays with N ≥ 2, got {e.shape}, {r.shape}")
    mu_e, mu_r = e.mean(axis=0), r.mean(axis=0)
    cov = (r - mu_r).T @ (e - mu_e) / len(e)
    u, _, vt = np.linalg.svd(cov)
    s = np.eye(2)
    if np.linalg.det(u) * np.linalg.det(vt) < 0:  # a reflection is not a rigid motion
        s[1, 1] = -1.0
    rot = u @ s @ vt
    theta = math.atan2(rot[1, 0], rot[0, 0])
    return theta, mu_r - rot @ mu_e


@dataclass(frozen=True, slots=True)
class AbsolutePoseError:
    """APE after SE(2) alignment: position error (m) and heading error (deg) statistics."""

    trans_m_rmse: float
    trans_m_mean: float
    trans_m_median: float
    trans_m_max: float
    rot_deg_rmse: float
    rot_deg_max: float
    poses: int
    align_rot_deg: float
    implementation: str = "albot2d"

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def absolute_pose_error(estimate: ArrayLike, reference: ArrayLike) -> AbsolutePoseError:
    """APE of ``(N, 3)`` poses against the reference poses of the same instants."""
    est = np.asarray(estimate, dtype=np.float64).reshape(-1, 3)
    ref = np.asarray(reference, dtype=np.float64).reshape(-1, 3)
    if est.shape != ref.shape:
        raise InputError(f"APE needs poses of the same instants, got {est.shape} and {ref.shape}")
    theta, t = align_se2(est[:, :2], ref[:, :2])
    aligned = compose_arrays(np.array([t[0], t[1], theta]), est)
    trans = np.hypot(*(aligned[:, :2] - ref[:, :2]).T)
    rot = np.abs(np.degrees(np.asarray(wrap_angle(aligned[:, 2] - ref[:, 2]))))
    return AbsolutePoseError(
        trans_m_rmse=float(np.sqrt(np.mean(trans**2))),
        trans_m_mean=float(trans.mean()),
        trans_m_median=float(np.median(trans)),
        trans_m_max=float(trans.max()),
        rot_deg_rmse=float(np.sqrt(np.mean(rot**2))),
        rot_deg_max=float(rot.max()),
        poses=len(est),
        align_rot_deg=math.degrees(theta),
    )


def _evo_trajectory(timestamps: FloatArray, poses: FloatArray) -> Any:
    from evo.core.trajectory import PoseTrajectory3D

    half = poses[:, 2] / 2.0
    xyz = np.column_stack([poses[:, 0], poses[:, 1], np.zeros(len(poses))])
    wxyz = np.column_stack([np.cos(half), np.zeros(len(poses)), np.zeros(len(poses)), np.sin(half)])
    return PoseTrajectory3D(positions_xyz=xyz, orientations_quat_wxyz=wxyz, timestamps=timestamps)


def evo_absolute_pose_error(
    timestamps: ArrayLike, estimate: ArrayLike, reference: ArrayLike
) -> AbsolutePoseError:
    """The same APE computed by evo (``pip install 'albot2d[eval]'``): SE(3) Umeyama
    alignment without scale of the planar poses (evo's ``align``), then evo's APE
    statistics of the translation and rotation-angle errors.

    The per-pose errors are evo's ``metrics.APE`` formulas evaluated on all poses at once
    (``evo_pose_errors``), bit for bit the numbers of its per-pose loop, which calls scipy
    once per pose and was most of a run's scoring time."""
    import evo
    from evo.core import metrics

    t = np.asarray(timestamps, dtype=np.float64)
    est = _evo_trajectory(t, np.asarray(estimate, dtype=np.float64).reshape(-1, 3))
    ref = _evo_trajectory(t, np.asarray(reference, dtype=np.float64).reshape(-1, 3))
    rot, _, _ = est.align(ref, correct_scale=False)
    trans, angle = evo_pose_errors(est, ref)
    stats = {}
    for relation, error in (
        (metrics.PoseRelation.translation_part, trans),
        (metrics.PoseRelation.rotation_angle_deg, angle),
    ):
        ape = metrics.APE(relation)
        ape.error = error  # evo's statistics (rmse, mean, median, max) of these errors
        stats[relation] = ape
    trans_ape = stats[metrics.PoseRelation.translation_part]
    angle_ape = stats[metrics.PoseRelation.rotation_angle_deg]
    return AbsolutePoseError(
        trans_m_rmse=float(trans_ape.get_statistic(metrics.StatisticsType.rmse)),
        trans_m_mean=float(trans_ape.get_statistic(metrics.StatisticsType.mean)),
        trans_m_median=float(trans_ape.get_statistic(metrics.StatisticsType.median)),
        trans_m_max=float(trans_ape.get_statistic(metrics.StatisticsType.max)),
        rot_deg_rmse=float(angle_ape.get_statistic(metrics.StatisticsType.rmse)),
        rot_deg_max=float(angle_ape.get_statistic(metrics.StatisticsType.max)),
        poses=len(t),
        align_rot_deg=math.degrees(math.atan2(rot[1, 0], rot[0, 0])),
        implementation=f"evo {evo.__version__.lstrip('v')}",
    )


def evo_pose_errors(est: Any, ref: Any) -> tuple[FloatArray, FloatArray]:
    """Per pose, evo's APE translation error (m) and rotation angle (deg) of the evo
    trajectories ``est`` (aligned) and ``ref``: the formulas of evo's ``metrics.APE``
    on all poses at once, with the same floating-point operations, so the same bits.

    - translation: ``‖p_est − p_ref‖`` (evo: ``np.linalg.norm``, i.e. ``sqrt(x·x)`` with
      BLAS's dot, which batched ``matmul`` of 1×3 by 3×1 also calls; an ``einsum`` sum
      would differ in the last bit);
    - rotation: the angle of the rotation part of ``E = P_est⁻¹ · P_ref`` (4×4 matrices,
      multiplied by ``matmul`` as evo's ``np.dot`` does), scipy's rotation vector of it
      (one batched call instead of one per pose), its norm in degrees. evo first checks
      each matrix is in SO(3) (``lie.is_so3``); so do we, all at once.
    """
    # evo's own helper: scipy's Rotation.from_matrix, which takes 1..n matrices
    from evo.core.lie_algebra import LieAlgebraException, sst_rotation_from_matrix

    diff = np.ascontiguousarray(est.positions_xyz - ref.positions_xyz)
    trans = np.sqrt(np.matmul(diff[:, None, :], diff[:, :, None])[:, 0, 0])
    p_est = np.asarray(est.poses_se3, dtype=np.float64).reshape(-1, 4, 4)
    p_ref = np.asarray(ref.poses_se3, dtype=np.float64).reshape(-1, 4, 4)
    inverse = np.zeros_like(p_est)  # evo's se3_inverse: [Rᵀ, −Rᵀt; 0 1]
    r_inv = p_est[:, :3, :3].transpose(0, 2, 1)
    inverse[:, :3, :3] = r_inv
    inverse[:, :3, 3] = -np.matmul(r_inv, p_est[:, :3, 3, None])[:, :, 0]
    inverse[:, 3, 3] = 1.0
    rotations = np.matmul(inverse, p_ref)[:, :3, :3]
    det_ok = np.isclose(np.linalg.det(rotations), 1.0, rtol=1e-5, atol=1e-6)
    gram = np.matmul(rotations.transpose(0, 2, 1), rotations)
    inv_ok = np.isclose(gram, np.eye(3), rtol=1e-5, atol=1e-6).all(axis=(1, 2))
    if not (det_ok.all() and inv_ok.all()):
        raise LieAlgebraException("matrix is not a valid SO(3) group element")
    if len(rotations) == 0:
        return trans, np.zeros(0)
    rotvec = sst_rotation_from_matrix(rotations).as_rotvec().reshape(-1, 3)
    norms = np.sqrt(np.matmul(rotvec[:, None, :], rotvec[:, :, None])[:, 0, 0])
    return trans, np.abs(np.rad2deg(norms))


def ape_result(
    timestamps: ArrayLike, estimate: ArrayLike, reference: ArrayLike | None
) -> AbsolutePoseError | None:
    """report.json's ``ape``: computed by evo when it is installed, else by
    ``absolute_pose_error`` (the same numbers to ~1e-9); ``None`` without a reference."""
    if reference is None or len(np.asarray(reference)) < 2:
        return None
    try:
        from evo.core.geometry import GeometryException
    except ImportError:
        return absolute_pose_error(estimate, reference)
    try:
        return evo_absolute_pose_error(timestamps, estimate, reference)
    except GeometryException:  # evo's 3D Umeyama needs a path that is not a straight line
        return absolute_pose_error(estimate, reference)
