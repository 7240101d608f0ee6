"""Exports and APE: TUM files evo reads back, CSV maps, our SE(2) APE equal to evo's."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from albot2d.evaluation import run_experiment
from albot2d.evaluation.metrics.alignment import (
    absolute_pose_error,
    align_se2,
    in_world_frame,
    map_in_world_frame,
)
from albot2d.evaluation.run.export import export_files, segments_csv, tum_text
from albot2d.geometry import compose_arrays, transform_segments
from tests.runs import small_run

SPEC = small_run(1, max_frames=70)


@pytest.fixture(scope="module")
def run_folder(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict]:
    result = run_experiment(SPEC)
    out = tmp_path_factory.mktemp("run")
    for name, data in export_files(result).items():
        (out / name).write_bytes(data)
    return out, result.report


def test_alignment_undoes_a_rigid_motion_exactly() -> None:
    rng = np.random.default_rng(3)
    ref = np.cumsum(rng.normal(size=(50, 3)) * [0.4, 0.4, 0.2], axis=0)
    moved = compose_arrays(np.array([4.0, -1.0, 2.5]), ref)
    theta, t = align_se2(moved[:, :2], ref[:, :2])
    assert math.isclose(theta, -2.5, abs_tol=1e-12)
    assert np.allclose(compose_arrays([t[0], t[1], theta], moved), ref, atol=1e-9)
    ape = absolute_pose_error(moved, ref)
    assert ape.trans_m_rmse < 1e-9 and ape.rot_deg_max < 1e-9 and ape.poses == 50
    # Noise on the estimate shows up; its alignment is still a rigid motion.
    noisy = moved + rng.normal(size=moved.shape) * [0.1, 0.1, 0.0]
    assert 0.05 < absolute_pose_error(noisy, ref).trans_m_rmse < 0.2


def test_mapper_results_in_the_world_frame() -> None:
    start = np.array([2.0, 3.0, math.pi / 2])
    poses = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, math.pi / 2]])
    world = in_world_frame(poses, start)
    assert np.allclose(world, [[2, 3, math.pi / 2], [2, 4, math.pi / 2], [1, 4, -math.pi]])
    segment = np.array([[1.0, 0.0, 1.0, 2.0]])
    assert np.allclose(map_in_world_frame(segment, start), transform_segments(start, segment))
    assert np.allclose(map_in_world_frame(segment, start), [[2, 4, 0, 4]])


def test_tum_and_csv_text() -> None:
    text = tum_text([0.0, 0.5], [[1.0, 2.0, 0.0], [1.5, 2.0, math.pi / 2]])
    rows = np.loadtxt(text.splitlines(), comments="#")
    assert rows.shape == (2, 8)
    assert np.allclose(
        rows[1], [0.5, 1.5, 2.0, 0, 0, 0, math.sin(math.pi / 4), math.cos(math.pi / 4)]
    )
    csv = segments_csv([[0, 0, 1, 0], [1, 0, 1, 1]], [3, 4])
    assert csv.splitlines()[0] == "x1,y1,x2,y2,map_id"
    assert np.allclose(
        np.loadtxt(csv.splitlines()[1:], delimiter=","), [[0, 0, 1, 0, 3], [1, 0, 1, 1, 4]]
    )


def test_run_folder_files_overlay_the_world(run_folder: tuple[Path, dict]) -> None:
    out, report = run_folder
    names = {p.name for p in out.iterdir()}
    assert names == {
        "groundtruth.tum",
        "odometry.tum",
        "traj_albot1.tum",
        "traj_naive.tum",
        "traj_truth.tum",
        "map_albot1.csv",
        "map_naive.csv",
        "map_truth.csv",
    }
    truth = np.loadtxt(out / "groundtruth.tum")
    mine = np.loadtxt(out / "traj_truth.tum")  # the truth mapper, anchored at the true start
    assert len(truth) == report["run"]["frames"] == 70
    assert np.allclose(truth[:, 1:3], mine[:, 1:3], atol=1e-6)
    odometry = np.loadtxt(out / "odometry.tum")
    assert np.allclose(odometry[0], truth[0], atol=1e-9)
    segments = np.loadtxt(out / "map_truth.csv", delimiter=",", skiprows=1)
    assert len(segments) == report["mappers"]["truth"]["map"]["surfaces"]


def test_our_ape_equals_evo_on_the_exported_files(run_folder: tuple[Path, dict]) -> None:
    pytest.importorskip("evo", reason="evo is the [eval] extra (also in the test extra)")
    from evo.core import metrics, sync
    from evo.tools import file_interface

    out, report = run_folder
    ref = file_interface.read_tum_trajectory_file(str(out / "groundtruth.tum"))
    for name in ("albot1", "naive"):
        est = file_interface.read_tum_trajectory_file(str(out / f"traj_{name}.tum"))
        ref_s, est_s = sync.associate_trajectories(ref, est)
        est_s.align(ref_s, correct_scale=False)
        evo_ape = metrics.APE(metrics.PoseRelation.translation_part)
        evo_ape.process_data((ref_s, est_s))
        evo_rmse = evo_ape.get_statistic(metrics.StatisticsType.rmse)
        # Ours, on the same files (their 9-decimal positions and 12-decimal quaternions).
        poses = {}
        for key, path in (("ref", "groundtruth.tum"), ("est", f"traj_{name}.tum")):
            rows = np.loadtxt(out / path)
            poses[key] = np.column_stack([rows[:, 1:3], 2 * np.arctan2(rows[:, 6], rows[:, 7])])
        ours = absolute_pose_error(poses["est"], poses["ref"])
        assert ours.trans_m_rmse == pytest.approx(evo_rmse, rel=1e-9, abs=1e-12)
        evo_rot = metrics.APE(metrics.PoseRelation.rotation_angle_deg)
        evo_rot.process_data((ref_s, est_s))
        rot = evo_rot.get_statistic(metrics.StatisticsType.rmse)
        assert ours.rot_deg_rmse == pytest.approx(rot, rel=1e-6, abs=1e-9)
        # report.json lists the same APE (from the in-memory poses).
        listed = report["mappers"][name]["ape"]
        assert listed["trans_m_rmse"] == pytest.approx(evo_rmse, rel=1e-6, abs=1e-9)
        assert listed["implementation"].startswith("evo ")
    assert report["odometry"]["ape"]["trans_m_rmse"] == pytest.approx(
        report["mappers"]["naive"]["ape"]["trans_m_rmse"], rel=1e-9
    )
