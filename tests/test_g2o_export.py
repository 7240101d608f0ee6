"""The slam mapper's pose graph as g2o: GTSAM's own reader loads it and re-optimises it
to the mapper's trajectory; the file's lines are what g2o expects."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from albot2d.evaluation.metrics.alignment import in_world_frame
from albot2d.evaluation.run.map_exports import pose_graph_files
from albot2d.logs.g2o import g2o_text
from tests.runs import map_frames, office_loop, require_slam_extra


@pytest.fixture(scope="module")
def frames() -> list:
    require_slam_extra()
    return office_loop()[1][:260]


def slam_mapper(
    frames: list, optimizer: str, optimise_every: int, tolerance: float = 1e-6
) -> object:
    from albot2d.mapping.slam import LoopClosingSLAM, SlamParams
    from albot2d.mapping.slam.pose_graph import PoseGraphParams

    graph = PoseGraphParams(optimizer=optimizer, optimise_every=optimise_every,
                            relative_error_tol=tolerance)  # fmt: skip
    return map_frames(LoopClosingSLAM(SlamParams(graph=graph)), frames)


def reoptimise(path: Path, perturb_m: float = 0.0) -> np.ndarray:
    """Load with gtsam.readG2o, fix the first vertex by a prior, start from the file's
    vertices (optionally perturbed) and optimise by Levenberg–Marquardt."""
    import gtsam

    graph, initial = gtsam.readG2o(str(path), is3D=False)
    first = initial.atPose2(0)
    graph.add(gtsam.PriorFactorPose2(0, first, gtsam.noiseModel.Diagonal.Sigmas(
        np.array([1e-6, 1e-6, 1e-8]))))  # fmt: skip
    rng = np.random.default_rng(5)
    start = gtsam.Values()
    for k in range(initial.size()):
        p = initial.atPose2(k)
        dx, dy, dt = rng.normal(0.0, perturb_m, 3) * (k > 0) * [1.0, 1.0, 0.3]
        start.insert(k, gtsam.Pose2(p.x() + dx, p.y() + dy, p.theta() + dt))
    params = gtsam.LevenbergMarquardtParams()
    params.setRelativeErrorTol(1e-14)
    params.setAbsoluteErrorTol(0.0)
    params.setMaxIterations(100)
    result = gtsam.LevenbergMarquardtOptimizer(graph, start, params).optimize()
    return np.array([[result.atPose2(k).x(), result.atPose2(k).y(), result.atPose2(k).theta()]
                     for k in range(initial.size())])  # fmt: skip


def robust_optimum(mapper: object) -> np.ndarray:
    """The mapper's own (robust) factor graph optimised to convergence from its estimate:
    its solver stops earlier (relative decrease 1e-6 and GTSAM's default absolute 1e-5)."""
    import gtsam

    graph = mapper.graph  # type: ignore[attr-defined]
    values = gtsam.Values()
    for k, pose in enumerate(graph.estimate):
        values.insert(k, gtsam.Pose2(*pose))
    params = gtsam.LevenbergMarquardtParams()
    params.setRelativeErrorTol(1e-14)
    params.setAbsoluteErrorTol(0.0)
    params.setMaxIterations(100)
    # the mapper's GTSAM graph itself
    result = gtsam.LevenbergMarquardtOptimizer(graph.factor_graph, values, params).optimize()
    return np.array([[result.atPose2(k).x(), result.atPose2(k).y(), result.atPose2(k).theta()]
                     for k in range(len(graph.estimate))])  # fmt: skip


def check_reoptimises_to_the_mappers_trajectory(
    mapper: object, frames: list, tmp_path: Path, tol: float = 1e-6
) -> dict[str, float]:
    """Re-optimising the file ends at the mapper's own keyframe poses, to ``tol``."""
    start = frames[0].true_pose.as_array()
    files = pose_graph_files("slam", mapper, [f.timestamp for f in frames], start)
    path = tmp_path / "graph_slam.g2o"
    path.write_bytes(files["graph_slam.g2o"])
    own = in_world_frame(np.array(mapper.graph.estimate), start)  # type: ignore[attr-defined]
    errors = {}
    for perturb in (0.0, 0.05):
        out = reoptimise(path, perturb)
        assert out.shape == own.shape
        d = out - own
        d[:, 2] = np.arctan2(np.sin(d[:, 2]), np.cos(d[:, 2]))
        errors[f"xy_m_from_{perturb:g}"] = float(np.abs(d[:, :2]).max())
        errors[f"theta_rad_from_{perturb:g}"] = float(np.abs(d[:, 2]).max())
        assert np.abs(d).max() < tol, (perturb, np.abs(d).max())
    # the keyframes' times and poses beside it, in the same order
    tum = np.loadtxt(files["graph_slam.tum"].decode().splitlines(), comments="#")
    rows = np.asarray(mapper.keyframe_rows)  # type: ignore[attr-defined]
    assert np.allclose(tum[:, 0], np.array([f.timestamp for f in frames])[rows], atol=1e-6)
    assert np.allclose(tum[:, 1:3], own[:, :2], atol=1e-8)
    return errors


def test_g2o_reoptimises_to_the_slam_mappers_trajectory(frames: list, tmp_path: Path) -> None:
    """The default back end (GNC): re-optimising the file from the mapper's estimate, or
    from 5 cm / 1° away, ends at the mapper's own keyframe poses (1e-6). The mapper
    optimises after every keyframe here, so its estimate is the optimum of its graph."""
    mapper = slam_mapper(frames, "gnc", optimise_every=1)
    stats = mapper.slam_stats()  # type: ignore[attr-defined]
    assert stats["loop_closures_accepted"] + stats["local_constraints_accepted"] > 0
    errors = check_reoptimises_to_the_mappers_trajectory(mapper, frames, tmp_path)
    print(f"gnc: {stats}, re-optimisation errors {errors}")


@pytest.mark.slow
def test_g2o_folds_robust_kernel_weights_in(frames: list, tmp_path: Path) -> None:
    """Levenberg–Marquardt with robust kernels: each factor's information is weighted by
    its kernel at the estimate (iteratively reweighted least squares), so at an optimum of
    the robust graph the plain Gaussian file has that same optimum. The mapper's solver
    stops short of it (GTSAM's default absolute tolerance, 1e-5 of cost), so the file is
    written once as the mapper left it (its re-optimisation within 1e-4 of the mapper's
    estimate) and once with the estimate polished to the robust graph's optimum (1e-6)."""
    mapper = slam_mapper(frames, "lm", optimise_every=1)
    graph = mapper.graph  # type: ignore[attr-defined]
    as_left = check_reoptimises_to_the_mappers_trajectory(mapper, frames, tmp_path, tol=1e-4)
    optimum = robust_optimum(mapper)
    gap = float(np.abs(optimum[:, :2] - np.asarray(graph.estimate)[:, :2]).max())
    graph._estimate = optimum  # polished: the robust graph's own optimum (private field)
    polished = check_reoptimises_to_the_mappers_trajectory(mapper, frames, tmp_path)
    print(
        f"lm: as left {as_left}; the estimate {gap:.2g} m from its graph's optimum; "
        f"polished {polished}"
    )


def test_g2o_file_holds_every_factor_of_the_default_mapper(frames: list) -> None:
    from albot2d.mapping.slam.graph_export import pose_graph_edges

    mapper = slam_mapper(frames, "gnc", optimise_every=10)
    edges = pose_graph_edges(mapper.graph)  # type: ignore[attr-defined]
    stats = mapper.slam_stats()  # type: ignore[attr-defined]
    k = stats["keyframes"]
    loops = stats["loop_closures_accepted"] + stats["local_constraints_accepted"]
    assert edges.kinds.count("scan_matching") == edges.kinds.count("wheel") == k - 1
    assert edges.kinds.count("loop") + edges.dropped == loops
    # information matrices symmetric positive definite, as the g2o format needs
    assert np.all(np.linalg.eigvalsh(edges.information) > 0)
    assert np.array_equal(edges.information, edges.information.transpose(0, 2, 1))
    text = pose_graph_files("slam", mapper, [f.timestamp for f in frames])["graph_slam.g2o"]
    lines = text.decode().splitlines()
    assert sum(line.startswith("VERTEX_SE2 ") for line in lines) == k
    assert sum(line.startswith("EDGE_SE2 ") for line in lines) == len(edges.kinds)
    # the vertices are the mapper's own estimate, to the last bit (17 digits)
    vertices = np.array([[float(v) for v in line.split()[2:]] for line in lines[:k]])
    assert np.array_equal(vertices, np.asarray(mapper.graph.estimate))  # type: ignore[attr-defined]
    first_edge = lines[k].split()
    assert len(first_edge) == 12 and first_edge[:3] == ["EDGE_SE2", "0", "1"]


def test_g2o_text_writes_the_upper_triangle_row_by_row() -> None:
    info = np.array([[1.0, 2.0, 3.0], [2.0, 4.0, 5.0], [3.0, 5.0, 6.0]])
    text = g2o_text([[0, 0, 0], [1, 2, 0.5]], [[0, 1]], [[1, 2, 0.5]], [info])
    assert text.splitlines() == [
        "VERTEX_SE2 0 0 0 0",
        "VERTEX_SE2 1 1 2 0.5",
        "EDGE_SE2 0 1 1 2 0.5 1 2 3 4 5 6",
    ]
    with pytest.raises(ValueError, match="symmetric"):
        g2o_text([[0, 0, 0], [1, 2, 0.5]], [[0, 1]], [[1, 2, 0.5]], [np.triu(info)])
    with pytest.raises(ValueError, match="outside"):
        g2o_text([[0, 0, 0]], [[0, 1]], [[1, 2, 0.5]], [info])


def test_run_and_replay_export_the_graph(tmp_path: Path) -> None:
    """``--export g2o occupancy`` from ``run`` (world frame) and ``replay`` (the mapper's
    frame): the g2o file loads in GTSAM with a vertex per keyframe the report counts."""
    require_slam_extra()
    import json

    import gtsam

    from albot2d.cli import main

    out = tmp_path / "run"
    assert main(["run", "--out", str(out), "--max-frames", "60", "--no-figures", "--mapper",
                 "slam", "naive", "--export", "g2o", "occupancy"]) == 0  # fmt: skip
    report = json.loads((out / "report.json").read_text())
    keyframes = report["mappers"]["slam"]["counts"]["local_maps"]
    assert {"graph_slam.g2o", "graph_slam.tum", "map_slam.pgm", "world.yaml"} <= set(
        report["exports"]
    )
    graph, initial = gtsam.readG2o(str(out / "graph_slam.g2o"), is3D=False)
    assert initial.size() == keyframes and graph.size() >= 2 * (keyframes - 1)
    first = initial.atPose2(0)  # the first keyframe at the first true pose (world frame)
    truth = np.loadtxt(out / "groundtruth.tum", comments="#")[0]
    assert np.allclose([first.x(), first.y()], truth[1:3], atol=1e-9)
    sim = tmp_path / "sim"
    assert main(["simulate", "--out", str(sim), "--max-frames", "40", "--no-png"]) == 0
    assert main(["replay", str(sim / "log.clf"), "--out", str(tmp_path / "rep"), "--no-figures",
                 "--mapper", "slam", "--export", "g2o"]) == 0  # fmt: skip
    graph, initial = gtsam.readG2o(str(tmp_path / "rep" / "graph_slam.g2o"), is3D=False)
    assert initial.atPose2(0).equals(gtsam.Pose2(), 1e-12)  # a log: the first view is the origin
    assert main(["run", "--out", str(tmp_path / "no"), "--export", "g2o"]) == 2
    assert not (tmp_path / "no").exists()
