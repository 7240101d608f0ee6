"""The loop-closing ``slam`` mapper: closures verified, false ones rejected, the map bends.

On a ~30 m office loop (dataset3, typical noise) the ``slam`` mapper is compared with its
own front end alone (``scan_odometry``). Skips without the ``[slam]`` extra (kiss-icp and
gtsam); the clean error for a missing gtsam is tested either way.
"""

from __future__ import annotations

import sys
from dataclasses import replace

import numpy as np
import pytest

from albot2d.errors import InputError
from albot2d.frames import Frame
from albot2d.geometry import between_arrays, compose_arrays
from albot2d.mapping import Mapper
from albot2d.mapping.registry import BUILTIN_MAPPERS
from albot2d.mapping.slam import LoopClosingSLAM, ScanMatchingSLAM, SlamParams
from albot2d.mapping.slam.loop_closure import LoopClosureParams, registration_information
from albot2d.mapping.slam.pose_graph import PoseGraph, PoseGraphParams
from tests.runs import map_frames, office_loop, require_slam_extra


@pytest.fixture(scope="module")
def extra() -> None:
    require_slam_extra()


@pytest.fixture(scope="module")
def frames() -> list[Frame]:
    """A ~30 m loop through a small office, dataset3 profile, typical odometry noise."""
    return office_loop()[1]


@pytest.fixture(scope="module")
def slam(extra: None, frames: list[Frame]) -> LoopClosingSLAM:
    return map_frames(LoopClosingSLAM(), frames)


def truth_of(frames: list[Frame]) -> np.ndarray:
    truth = np.array([f.true_pose.as_array() for f in frames])  # type: ignore[union-attr]
    return between_arrays(truth[:1], truth)


def end_pose_error(frames: list[Frame], trajectory: np.ndarray) -> tuple[float, float]:
    truth = truth_of(frames)
    err = between_arrays(between_arrays(truth[0], truth[-1]),
                         between_arrays(trajectory[0], trajectory[-1]))  # fmt: skip
    return float(np.hypot(err[0], err[1])), float(np.degrees(abs(err[2])))


def test_a_true_loop_closes_and_the_end_pose_error_drops(
    slam: LoopClosingSLAM, frames: list[Frame]
) -> None:
    front_end = map_frames(ScanMatchingSLAM(), frames)
    stats = slam.slam_stats()
    assert stats["loop_closures_accepted"] >= 1 and stats["optimisations"] >= 1
    # every accepted closure agrees with the truth: a true loop, not a look-alike place
    # (a few degrees off where a keyframe's estimate disagreed with its neighbours'; with
    # odometry error generated along the motion one of the ~100 is 3.5° / 0.11 m off)
    truth, rows = truth_of(frames), np.array(slam.keyframe_rows)
    for c in (c for c in slam.checks if c.accepted):
        err = between_arrays(between_arrays(truth[rows[c.i]], truth[rows[c.j]]), c.relative)
        assert np.hypot(err[0], err[1]) < 0.25 and np.degrees(abs(err[2])) < 4.0
        # it carries its registration's information: symmetric, positive semi-definite
        assert c.information is not None and c.information.shape == (3, 3)
        np.testing.assert_allclose(c.information, c.information.T)
        assert np.linalg.eigvalsh(c.information)[0] >= -1e-9
    before = end_pose_error(frames, front_end.trajectory())
    after = end_pose_error(frames, slam.trajectory())
    assert after[0] < before[0]
    # the map follows the optimised poses: the same views, placed differently
    assert len(slam.global_map().segments) == len(front_end.global_map().segments)
    assert not np.allclose(slam.trajectory(), front_end.trajectory(), atol=1e-3)


def test_an_injected_false_candidate_is_rejected(
    slam: LoopClosingSLAM, frames: list[Frame]
) -> None:
    truth, rows = truth_of(frames), np.array(slam.keyframe_rows)
    kf_truth = truth[rows]
    i = len(rows) - 1
    far = np.flatnonzero(np.hypot(*(kf_truth[:, :2] - kf_truth[i, :2]).T) > 6.0)
    j = int(far[len(far) // 2])
    loops, optimisations = len(slam.graph.loops), slam.graph.optimisations
    before = slam.trajectory()
    # claim the two places are the same one: the robot was "here" at keyframe j
    check = slam.propose_closure(i, j, guess=np.zeros(3))
    assert not check.accepted and check.reason
    # or at j's place turned round (a 180° scanner then sees the other half of the room;
    # ICP must not snap onto a look-alike). From the current estimate itself the two local
    # maps may truly overlap (30 m laser, keyframes 6 m apart): not a false claim.
    est = slam.graph.estimate
    turned = compose_arrays(between_arrays(est[j], est[i]), np.array([0.0, 0.0, np.pi]))
    assert not slam.propose_closure(i, j, guess=turned).accepted
    assert len(slam.graph.loops) == loops and slam.graph.optimisations == optimisations
    np.testing.assert_array_equal(slam.trajectory(), before)
    stats = slam.slam_stats()
    assert stats["loop_closures_rejected"] >= 2
    assert (
        stats["loop_candidates"]
        == stats["loop_closures_accepted"] + stats["loop_closures_rejected"]
    )


def test_robust_kernel_limits_a_false_closure_that_got_through(extra: None) -> None:
    """A square of 40 keyframes with exact odometry and one true closure; a false closure
    forced in (bypassing verification) barely moves it under the Cauchy kernel."""
    motions = [np.array([1.0, 0.0, np.pi / 2 if (k + 1) % 10 == 0 else 0.0]) for k in range(40)]

    def square(kernel: str, false_closure: bool) -> np.ndarray:
        graph = PoseGraph(PoseGraphParams(optimizer="lm", loop_kernel=kernel))
        graph.add_keyframe(None, np.zeros(3))
        for m in motions[:-1]:
            graph.add_keyframe(m, compose_arrays(graph.estimate[-1], m))
        graph.add_loop(39, 0, motions[-1])  # the true closure back to the start
        if false_closure:
            graph.add_loop(20, 5, np.array([0.0, 0.0, 0.0]))  # "keyframe 5 is keyframe 20"
        assert graph.optimise()
        return graph.estimate.copy()

    clean = square("cauchy", False)
    robust = square("cauchy", True)
    plain = square("none", True)
    robust_shift = np.hypot(*(robust[:, :2] - clean[:, :2]).T).max()
    plain_shift = np.hypot(*(plain[:, :2] - clean[:, :2]).T).max()
    assert robust_shift < 0.5 < plain_shift


@pytest.mark.parametrize("loss", ["tls", "gm"])
def test_gnc_drops_false_closures_and_keeps_true_ones(extra: None, loss: str) -> None:
    """A square of 10 m sides driven twice (80 keyframes), odometry drifting 0.2° per
    keyframe (8° a lap, the size of the MIT log's big-loop corrections); ten true closures
    from the second lap to the first, three false ones (a keyframe claimed to be one
    10–35 m away). GNC, with the chain as known inliers, weighs the false closures to ~0
    and keeps the true ones, so its result is the one without the false closures; without
    a robust kernel Levenberg–Marquardt is bent by them."""
    bias = np.array([0.0, 0.0, np.radians(0.2)])
    motions = [np.array([1.0, 0.0, np.pi / 2 if (k + 1) % 10 == 0 else 0.0]) for k in range(80)]
    truth = np.zeros((80, 3))
    for k in range(1, 80):
        truth[k] = compose_arrays(truth[k - 1], motions[k - 1])
    true_loops = [(k, k - 40) for k in range(40, 80, 4)]
    false_loops = [(50, 15), (65, 42), (75, 53)]

    def two_laps(params: PoseGraphParams, loops: list[tuple[int, int]]) -> PoseGraph:
        graph = PoseGraph(params)
        graph.add_keyframe(None, np.zeros(3))
        for m in motions[:-1]:
            graph.add_keyframe(m + bias, compose_arrays(graph.estimate[-1], m + bias), m + bias)
        for i, j in true_loops:
            graph.add_loop(i, j, between_arrays(truth[i], truth[j]))
        for i, j in loops:
            graph.add_loop(i, j, np.zeros(3))  # "keyframe j is keyframe i"
        assert graph.optimise()
        return graph

    gnc_params = PoseGraphParams(optimizer="gnc", gnc_loss=loss)
    gnc = two_laps(gnc_params, false_loops)
    weights = gnc.loop_weights
    assert np.all(weights[-3:] < 0.05)
    # TLS: exactly in or out; Geman–McClure's weights are smooth, < 1 at any residual
    assert np.all(weights[:-3] > (0.99 if loss == "tls" else 0.8))
    clean = two_laps(gnc_params, []).estimate
    assert np.hypot(*(gnc.estimate[:, :2] - clean[:, :2]).T).max() < 0.01
    plain = two_laps(PoseGraphParams(optimizer="lm", loop_kernel="none"), false_loops).estimate
    assert np.hypot(*(plain[:, :2] - clean[:, :2]).T).max() > 1.0
    # and the true closures did their work: the 16° of drift at the end is mostly gone
    assert np.degrees(abs(between_arrays(truth[79], gnc.estimate[79])[2])) < 4.0


def test_the_factor_graph_and_each_closures_factor_are_readable(extra: None) -> None:
    """``factor_graph`` is the graph optimised (a prior, a factor per step, one per
    closure); ``loop_factor_indices`` names each closure's factor, in the order of
    ``loops``, and is a copy."""
    import gtsam

    graph = PoseGraph(PoseGraphParams(loop_kernel="none"))
    graph.add_keyframe(None, np.zeros(3))
    for k in range(1, 6):
        graph.add_keyframe(np.array([1.0, 0.0, 0.0]), np.array([k, 0.0, 0.0]))
    assert graph.loop_factor_indices == ()
    graph.add_loop(5, 1, np.array([-4.0, 0.0, 0.0]))
    graph.add_loop(4, 0, np.array([-4.0, 0.0, 0.0]))
    factors = graph.factor_graph
    assert int(factors.size()) == 1 + 5 + 2
    assert graph.loop_factor_indices == (6, 7)
    for (i, j), f in zip(graph.loops, graph.loop_factor_indices, strict=True):
        factor = factors.at(f)
        assert isinstance(factor, gtsam.BetweenFactorPose2)
        assert [int(k) for k in factor.keys()] == [i, j]  # noqa: SIM118 (a gtsam KeyVector)


def test_gnc_mapper_weighs_an_injected_false_closure_to_zero(
    extra: None, frames: list[Frame]
) -> None:
    """The office loop with every registration-verified candidate admitted
    (``gate="none"``) and GNC deciding: the loop closes (end error below the front end's);
    a false closure forced into the graph (keyframe ``i`` is claimed to be a keyframe 6 m
    away) gets weight ~0 and leaves the end pose where it was."""
    params = SlamParams(loops=LoopClosureParams(gate="none"),
                        graph=PoseGraphParams(optimizer="gnc"))  # fmt: skip
    slam = map_frames(LoopClosingSLAM(params), frames)
    stats = slam.slam_stats()
    assert stats["loop_closures_accepted"] >= 1
    assert stats["loop_closures_down_weighted"] == int(np.sum(slam.graph.loop_weights < 0.5))
    front = end_pose_error(frames, map_frames(ScanMatchingSLAM(), frames).trajectory())
    closed = end_pose_error(frames, slam.trajectory())
    assert closed[0] < front[0]
    truth, rows = truth_of(frames), np.array(slam.keyframe_rows)
    kf_truth = truth[rows]
    i = len(rows) - 1
    far = np.flatnonzero(np.hypot(*(kf_truth[:, :2] - kf_truth[i, :2]).T) > 6.0)
    j = int(far[len(far) // 2])
    slam.graph.add_loop(i, j, np.zeros(3))
    assert slam.graph.optimise()
    assert slam.graph.loop_weights[-1] < 0.05
    after = end_pose_error(frames, slam.trajectory())
    assert abs(after[0] - closed[0]) < 0.05 and abs(after[1] - closed[1]) < 0.5


def test_relative_covariance_is_the_chain_propagated(extra: None) -> None:
    """On a chain of turning moves (no closures) the graph's marginal covariance of one
    keyframe seen from another is the first-order propagation of the moves' sigmas."""
    import gtsam

    params = PoseGraphParams(odom_kernel="none")
    graph = PoseGraph(params)
    graph.add_keyframe(None, np.zeros(3))
    move = np.array([1.0, 0.0, 0.1])
    for _ in range(9):
        graph.add_keyframe(move, compose_arrays(graph.estimate[-1], move))
    sigma_m = params.odom_sigma_m + params.odom_sigma_m_per_m
    sigma = np.array([sigma_m, sigma_m,
                      np.radians(params.odom_sigma_deg + params.odom_sigma_deg_per_m)])  # fmt: skip
    # keyframe 8 from keyframe 2: moves 3..8, each perturbed on its right, carried to the end
    expected, rest = np.zeros((3, 3)), gtsam.Pose2()
    for _ in range(6):
        adj = rest.inverse().AdjointMap()
        expected += adj @ np.diag(sigma**2) @ adj.T
        rest = gtsam.Pose2(*move).compose(rest)
    np.testing.assert_allclose(graph.relative_covariance(2, 8), expected, rtol=1e-6, atol=1e-12)


def test_chi2_gate_rejects_a_closure_the_uncertainty_cannot_explain(
    slam: LoopClosingSLAM,
) -> None:
    """Every accepted closure passed the χ² gate; the same closure 1 m and 10° away from
    what the graph allows for (a look-alike place, or ICP that slid) is rejected."""
    accepted = [c for c in slam.checks if c.accepted]
    limit = slam.params.loops.gate_chi2
    assert accepted and all(c.chi2 is not None and c.chi2 <= limit for c in accepted)
    check = accepted[-1]
    # judged again against the graph it is now part of: still compatible
    again = slam.chi2_gate(replace(check, chi2=None))
    assert again.accepted and again.chi2 is not None and again.chi2 <= limit
    off = compose_arrays(check.relative, np.array([1.0, 0.0, np.radians(10.0)]))
    wrong = slam.chi2_gate(replace(check, relative=off))
    assert not wrong.accepted and wrong.reason.startswith("χ² gate")
    assert wrong.chi2 is not None and wrong.chi2 > limit


def _sigmas(noise: object) -> np.ndarray:
    r = noise.R()  # type: ignore[attr-defined]
    return np.sqrt(np.diag(np.linalg.inv(r.T @ r)))


def test_closure_information_follows_what_the_registration_fixed(extra: None) -> None:
    """A scan seen in a straight corridor (two parallel walls) fixes the cross-corridor
    position and the heading, not the position along it: the closure's noise model is
    loose along the corridor only. A corner fixes everything: the configured sigmas."""
    x = np.linspace(-3.0, 3.0, 61)
    walls = np.vstack([np.column_stack([x, np.full_like(x, 1.0)]),
                       np.column_stack([x, np.full_like(x, -1.0)])])  # fmt: skip
    up, down = np.tile([0.0, 1.0], (61, 1)), np.tile([0.0, -1.0], (61, 1))
    corridor = registration_information(walls, np.vstack([up, down]))
    assert corridor[0, 0] == pytest.approx(0.0) and corridor[1, 1] > 100
    # rotating the corridor rotates the unconstrained direction with it
    c, s = np.cos(0.5), np.sin(0.5)
    rot = np.array([[c, -s], [s, c]])
    turned = registration_information(walls @ rot.T, np.vstack([up, down]) @ rot.T)
    assert np.linalg.eigvalsh(turned[:2, :2])[0] == pytest.approx(0.0, abs=1e-9)
    params = PoseGraphParams()
    graph = PoseGraph(params)
    along, across, heading = _sigmas(graph.loop_noise(corridor))
    assert along == pytest.approx(params.loop_sigma_m * params.loop_max_sigma_ratio)
    assert across == pytest.approx(params.loop_sigma_m)
    assert heading < np.radians(3 * params.loop_sigma_deg)
    wall = np.column_stack([np.full_like(x, 3.0), x])  # a second wall across the end
    corner = registration_information(
        np.vstack([walls, wall]), np.vstack([up, down, np.tile([-1.0, 0.0], (61, 1))])
    )
    assert max(_sigmas(graph.loop_noise(corner))[:2]) < 3 * params.loop_sigma_m
    plain = PoseGraph(PoseGraphParams(loop_information=False))
    np.testing.assert_allclose(_sigmas(plain.loop_noise(corridor)),
                               [params.loop_sigma_m, params.loop_sigma_m,
                                np.radians(params.loop_sigma_deg)])  # fmt: skip


def test_slam_is_a_deterministic_protocol_mapper(
    slam: LoopClosingSLAM, frames: list[Frame]
) -> None:
    first = BUILTIN_MAPPERS["slam"]()
    assert isinstance(first, Mapper) and first.name == "slam"
    for f in frames:
        first.observe(f)
    traj = first.trajectory()
    assert traj.shape == (len(frames), 3) and np.all(np.isfinite(traj))
    np.testing.assert_allclose(traj[0], 0.0, atol=1e-9)  # the first pose is the origin
    np.testing.assert_array_equal(first.pose().as_array(), traj[-1])
    snap = first.global_map()
    assert snap.segments.shape[1] == 4 and len(snap.segments) == len(snap.map_ids)
    assert first.slam_stats()["loop_closures_accepted"] >= 1  # type: ignore[attr-defined]
    # the `slam` fixture ran the same frames: identical poses and map (a rejected
    # injected candidate, if that test ran first, changes neither)
    np.testing.assert_array_equal(traj, slam.trajectory())
    np.testing.assert_array_equal(snap.segments, slam.global_map().segments)
    np.testing.assert_array_equal(snap.map_ids, slam.global_map().map_ids)
    counts = first.counts()
    assert counts.views == len(frames) and counts.local_maps == len(slam.keyframe_rows)
    assert counts.triangulations + counts.path_integrations == len(frames) - 1
    assert {"extraction", "scan_matching", "loop_closure", "optimisation", "global_map"} <= set(
        first.timings_ms()
    )


def test_bad_loop_params_name_the_field() -> None:
    with pytest.raises(InputError, match="min_inlier_ratio"):
        LoopClosureParams(min_inlier_ratio=1.5)
    with pytest.raises(InputError, match="keyframe_distance_m"):
        LoopClosureParams(keyframe_distance_m=0.0)
    with pytest.raises(InputError, match="loop_kernel"):
        PoseGraphParams(loop_kernel="tukey-ish")
    with pytest.raises(InputError, match="overlap_distance_m"):
        LoopClosureParams(overlap_distance_m=0.0)
    with pytest.raises(InputError, match="max_correction_deg_per_m"):
        LoopClosureParams(max_correction_deg_per_m=-0.1)
    with pytest.raises(InputError, match="wheel_kernel"):
        PoseGraphParams(wheel_kernel="tukey-ish")
    with pytest.raises(InputError, match="loop_max_sigma_ratio"):
        PoseGraphParams(loop_max_sigma_ratio=0.0)
    with pytest.raises(InputError, match="gate"):
        LoopClosureParams(gate="wide")
    with pytest.raises(InputError, match="gate_chi2"):
        LoopClosureParams(gate_chi2=0.0)
    with pytest.raises(InputError, match="closure_spacing_m"):
        LoopClosureParams(closure_spacing_m=-1.0)
    with pytest.raises(InputError, match="optimizer"):
        PoseGraphParams(optimizer="dogleg-ish")
    with pytest.raises(InputError, match="gnc_loss"):
        PoseGraphParams(gnc_loss="cauchy")
    with pytest.raises(InputError, match="gnc_inlier_probability"):
        PoseGraphParams(gnc_inlier_probability=1.0)


def test_missing_gtsam_is_one_clean_error(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "gtsam", None)
    with pytest.raises(InputError, match=r"pip install 'albot2d\[slam\]'"):
        LoopClosingSLAM()


def test_closure_spacing_keeps_closures_a_query_local_map_apart(
    slam: LoopClosingSLAM, frames: list[Frame]
) -> None:
    """With ``closure_spacing_m`` no two accepted closures come from keyframes closer than
    that along the path (consecutive keyframes onto one target share its registration
    error), fewer candidates are verified, and the loop still closes."""
    spaced = map_frames(
        LoopClosingSLAM(replace(slam.params, loops=replace(slam.params.loops,
                                                           closure_spacing_m=5.0))),
        frames,
    )  # fmt: skip
    accepted = [c.i for c in spaced.checks if c.accepted]
    assert len(accepted) >= 1
    path = np.array(spaced._kf_path_m)[accepted]
    assert np.all(np.diff(path) >= 5.0)
    assert len(spaced.checks) < len(slam.checks)
    dense = [c.i for c in slam.checks if c.accepted]
    assert np.any(np.diff(np.array(slam._kf_path_m)[dense]) < 5.0)  # the rule did something
    assert (
        end_pose_error(frames, spaced.trajectory())[0]
        < end_pose_error(frames, map_frames(ScanMatchingSLAM(), frames).trajectory())[0]
    )
