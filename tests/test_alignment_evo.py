"""report.json's APE: evo's per-pose errors computed on all poses at once, bit for bit evo's.

``alignment.evo_pose_errors`` replaces evo's ``metrics.APE.process_data`` loop (one scipy
rotation per pose, most of a run's scoring time); these tests run evo's own loop beside it
on real trajectories (a simulated run: odometry, Albot1, the naive and truth mappers).
"""

from __future__ import annotations

import numpy as np
import pytest

from albot2d.evaluation import RunSpec, run_experiment
from albot2d.evaluation.metrics.alignment import (
    _evo_trajectory,
    absolute_pose_error,
    evo_absolute_pose_error,
    evo_pose_errors,
)

pytest.importorskip("evo", reason="evo is the [eval] extra (also in the test extra)")

SPEC = RunSpec(
    kind="office",
    seed=0,
    world_params={"width_m": 30.0, "height_m": 24.0},
    profile="dataset3",
    tour_length_m=30.0,
    max_frames=400,
)


@pytest.fixture(scope="module")
def trajectories() -> dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """name → (timestamps, estimate, reference) of one real simulated run."""
    result = run_experiment(SPEC, score=False)
    trace = result.trace
    assert trace.true_poses is not None
    out = {"odometry": (trace.timestamps, trace.odom_poses, trace.true_poses)}
    for name, mapper in trace.mappers.items():
        poses = np.asarray(mapper.trajectory(), dtype=np.float64)
        out[name] = (trace.timestamps, poses, trace.true_poses)
    return out


def _evo_loop(t: np.ndarray, est_poses: np.ndarray, ref_poses: np.ndarray) -> dict:
    """evo's own path: align, then ``metrics.APE.process_data`` per relation."""
    from evo.core import metrics

    est, ref = _evo_trajectory(t, est_poses), _evo_trajectory(t, ref_poses)
    est.align(ref, correct_scale=False)
    out = {}
    for relation in (
        metrics.PoseRelation.translation_part,
        metrics.PoseRelation.rotation_angle_deg,
    ):
        ape = metrics.APE(relation)
        ape.process_data((ref, est))
        out[relation] = ape
    return out


def test_pose_errors_equal_evos_loop_bit_for_bit(trajectories: dict) -> None:
    from evo.core import metrics

    assert set(trajectories) == {"odometry", "albot1", "naive", "truth"}
    for name, (t, est_poses, ref_poses) in trajectories.items():
        evo = _evo_loop(t, est_poses, ref_poses)
        est, ref = _evo_trajectory(t, est_poses), _evo_trajectory(t, ref_poses)
        est.align(ref, correct_scale=False)
        trans, angle = evo_pose_errors(est, ref)
        want_trans = evo[metrics.PoseRelation.translation_part].error
        want_angle = evo[metrics.PoseRelation.rotation_angle_deg].error
        assert trans.shape == angle.shape == (len(t),), name
        # Equal bits, not only 1e-9: report.json's digests hold 12 significant digits and
        # the truth mapper's angles are ~1e-12 deg, where any other formula differs.
        assert np.array_equal(trans, want_trans), name
        assert np.array_equal(angle, want_angle), name
        assert np.abs(angle - want_angle).max() <= 1e-9


def test_apes_statistics_equal_evos(trajectories: dict) -> None:
    from evo.core import metrics

    for name, (t, est_poses, ref_poses) in trajectories.items():
        evo = _evo_loop(t, est_poses, ref_poses)
        ours = evo_absolute_pose_error(t, est_poses, ref_poses)
        trans = evo[metrics.PoseRelation.translation_part]
        angle = evo[metrics.PoseRelation.rotation_angle_deg]
        assert ours.implementation.startswith("evo ")
        assert ours.poses == len(t)
        assert ours.trans_m_rmse == trans.get_statistic(metrics.StatisticsType.rmse), name
        assert ours.trans_m_mean == trans.get_statistic(metrics.StatisticsType.mean), name
        assert ours.trans_m_median == trans.get_statistic(metrics.StatisticsType.median), name
        assert ours.trans_m_max == trans.get_statistic(metrics.StatisticsType.max), name
        assert ours.rot_deg_rmse == angle.get_statistic(metrics.StatisticsType.rmse), name
        assert ours.rot_deg_max == angle.get_statistic(metrics.StatisticsType.max), name
        # and albot2d's own SE(2) APE (no evo) agrees with it
        plain = absolute_pose_error(est_poses, ref_poses)
        assert plain.trans_m_rmse == pytest.approx(ours.trans_m_rmse, rel=1e-9, abs=1e-12)
        assert plain.rot_deg_max == pytest.approx(ours.rot_deg_max, rel=1e-6, abs=1e-9)


def test_a_drifting_estimate_has_errors_and_the_truth_has_none(trajectories: dict) -> None:
    odo_trans, odo_angle = evo_pose_errors(*_aligned(*trajectories["odometry"]))
    truth_trans, truth_angle = evo_pose_errors(*_aligned(*trajectories["truth"]))
    assert odo_trans.max() > 0.05 and odo_angle.max() > 0.5
    assert truth_trans.max() < 1e-6 and truth_angle.max() < 1e-6


def _aligned(t: np.ndarray, est_poses: np.ndarray, ref_poses: np.ndarray) -> tuple:
    est, ref = _evo_trajectory(t, est_poses), _evo_trajectory(t, ref_poses)
    est.align(ref, correct_scale=False)
    return est, ref
