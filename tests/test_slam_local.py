"""The ``slam`` mapper's short-range constraints and registration-shaped chain information.

``LoopClosureParams(local_separation_m=…)`` registers every new keyframe against the one a
few metres back with the closure verifier and gate; ``PoseGraphParams(odom_information=
"hessian")`` shapes the scan-matching chain factor by the two keyframes' point-to-line
Hessian. Both off by default (docs/albot-x.md, "Short-range constraints and registration
information"). Skips without the ``[slam]`` extra (kiss-icp and gtsam).
"""

from __future__ import annotations

import numpy as np
import pytest

from albot2d.errors import InputError
from albot2d.frames import Frame
from albot2d.geometry import between_arrays
from albot2d.mapping.slam import LoopClosingSLAM, SlamParams
from albot2d.mapping.slam.loop_closure import LoopClosureParams, LoopVerifier
from albot2d.mapping.slam.pose_graph import PoseGraph, PoseGraphParams
from tests.runs import map_frames, office_loop, require_slam_extra


@pytest.fixture(scope="module")
def extra() -> None:
    require_slam_extra()


@pytest.fixture(scope="module")
def opening() -> list[Frame]:
    """The first part of the SLAM tests' office loop (its first closures included)."""
    return office_loop()[1][:260]


def test_bad_values_name_the_field() -> None:
    with pytest.raises(InputError, match=r"LoopClosureParams\.local_separation_m"):
        LoopClosureParams(local_separation_m=0.0)
    with pytest.raises(InputError, match=r"LoopClosureParams\.local_separation_m"):
        LoopClosureParams(local_separation_m=float("nan"))
    with pytest.raises(InputError, match=r"LoopClosureParams\.local_query"):
        LoopClosureParams(local_query="map")
    with pytest.raises(InputError, match=r"PoseGraphParams\.odom_information"):
        PoseGraphParams(odom_information="icp")
    with pytest.raises(InputError, match=r"PoseGraphParams\.odom_max_sigma_ratio"):
        PoseGraphParams(odom_max_sigma_ratio=0.0)


@pytest.mark.parametrize("query", ["submap", "scan"])
def test_short_range_constraints_join_the_graph(
    extra: None, opening: list[Frame], query: str
) -> None:
    """With short-range constraints each keyframe is checked against the one ≥ 3 m back,
    the accepted ones join the graph beside the loop closures (and move the estimate),
    and the loop-closure counts stay apart from theirs."""
    off = LoopClosureParams(local_separation_m=None)  # the rule off (3 m is the default)
    plain = map_frames(LoopClosingSLAM(SlamParams(loops=off)), opening)
    loops = LoopClosureParams(local_separation_m=3.0, local_query=query)
    local = map_frames(LoopClosingSLAM(SlamParams(loops=loops)), opening)
    assert "local_candidates" not in plain.slam_stats() and not plain.local_checks
    stats = local.slam_stats()
    assert stats["local_candidates"] > 10
    accepted = [c for c in local.local_checks if c.accepted]
    closures = [(c.i, c.j) for c in local.checks if c.accepted]
    assert 0 < len(accepted) == stats["local_constraints_accepted"]
    assert len(closures) == stats["loop_closures_accepted"]
    assert sorted(local.graph.loops) == sorted(closures + [(c.i, c.j) for c in accepted])
    assert len(local.graph.loops) > len(plain.graph.loops)
    path = np.array(local._kf_path_m)
    for c in local.local_checks:  # the newest keyframe at least 3 m back
        assert path[c.i] - path[c.j] >= 3.0 and path[c.i] - path[c.j + 1] < 3.0
    assert not np.allclose(local.trajectory(), plain.trajectory())


def _corridor_scan(pose: np.ndarray) -> np.ndarray:
    """Points of a straight corridor (walls y = ±1 m, world frame) in ``pose``'s frame."""
    x = np.arange(-5.0, 15.0, 0.05)
    world = np.vstack([np.column_stack([x, np.ones_like(x)]),
                       np.column_stack([x, -np.ones_like(x)])])  # fmt: skip
    c, s = np.cos(pose[2]), np.sin(pose[2])
    d = world - pose[:2]
    return np.column_stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]])


def test_chain_information_is_in_the_factors_own_coordinates(extra: None) -> None:
    """The chain factor perturbs the newer keyframe's pose in its own frame: in a corridor
    the direction the scans do not fix is along the corridor as the *newer* keyframe sees
    it (turned 30° here), and nothing else is unconstrained."""
    verifier = LoopVerifier(LoopClosureParams(), np.array([-0.5, 0.0, 0.5]))
    motion = np.array([0.5, 0.0, np.radians(30.0)])
    info = verifier.chain_information(motion, _corridor_scan(np.zeros(3)),
                                      _corridor_scan(motion))  # fmt: skip
    along = np.array([np.cos(-motion[2]), np.sin(-motion[2]), 0.0])
    scale = np.linalg.norm(info)
    assert np.linalg.norm(info @ along) < 1e-6 * scale
    block = info[:2, :2]  # the older keyframe's corridor direction is constrained
    assert np.linalg.norm(block @ np.array([1.0, 0.0])) > 0.3 * np.linalg.norm(block)
    values = np.linalg.eigvalsh(info)
    assert values[0] < 1e-6 * scale and values[1] > 1e-3 * scale


def test_hessian_chain_factor_is_loose_only_where_scan_matching_is(extra: None) -> None:
    """``odom_information="hessian"``: a corridor's chain factor lets the keyframe slide
    along the corridor (up to ``odom_max_sigma_ratio`` × the sigma) but not across it;
    ``"fixed"`` ignores the Hessian."""
    verifier = LoopVerifier(LoopClosureParams(), np.array([-0.5, 0.0, 0.5]))
    motion = np.array([0.5, 0.0, 0.0])
    info = verifier.chain_information(motion, _corridor_scan(np.zeros(3)),
                                      _corridor_scan(motion))  # fmt: skip
    sigmas = {}
    for mode in ("fixed", "hessian"):
        params = PoseGraphParams(odom_kernel="none", odom_information=mode)
        graph = PoseGraph(params)
        graph.add_keyframe(None, np.zeros(3))
        graph.add_keyframe(motion, motion, information=info)
        cov = graph.relative_covariance(0, 1)
        assert cov is not None
        sigmas[mode] = np.sqrt(np.diag(cov))
    sigma_m = params.odom_sigma_m + params.odom_sigma_m_per_m * 0.5
    np.testing.assert_allclose(sigmas["fixed"][:2], sigma_m, rtol=1e-3)
    assert sigmas["hessian"][0] == pytest.approx(sigma_m * params.odom_max_sigma_ratio, rel=1e-3)
    assert sigmas["hessian"][1] < 2 * sigma_m  # across: barely looser (via the heading)


def test_hessian_chain_information_changes_the_mapper_graph(
    extra: None, opening: list[Frame]
) -> None:
    """On the office run the shaped chain factors give a different optimised path than
    the fixed ones, from the same front end."""
    fixed = SlamParams(graph=PoseGraphParams(odom_information="fixed"))
    plain = map_frames(LoopClosingSLAM(fixed), opening[:120])
    shaped = map_frames(
        LoopClosingSLAM(SlamParams(graph=PoseGraphParams(odom_information="hessian"))),
        opening[:120],
    )
    np.testing.assert_array_equal(np.array(plain._kf_fe), np.array(shaped._kf_fe))
    a, b = plain.graph.estimate, shaped.graph.estimate
    assert len(a) == len(b) > 5
    gap = between_arrays(a, b)
    assert np.max(np.hypot(gap[:, 0], gap[:, 1])) > 1e-4


def test_hessian_xy_shapes_the_position_only(extra: None) -> None:
    """``odom_information="hessian_xy"``: along the corridor as loose as ``"hessian"``, but
    the heading keeps its configured sigma and is not coupled to the position."""
    verifier = LoopVerifier(LoopClosureParams(), np.array([-0.5, 0.0, 0.5]))
    motion = np.array([0.5, 0.0, 0.0])
    info = verifier.chain_information(motion, _corridor_scan(np.zeros(3)),
                                      _corridor_scan(motion))  # fmt: skip
    sigmas = np.array([0.03, 0.03, np.radians(0.2)])
    graph = PoseGraph(PoseGraphParams(odom_information="hessian_xy"))
    shaped = graph.odom_information_matrix(info, sigmas)
    assert shaped[2, 2] == pytest.approx(sigmas[2] ** -2)
    np.testing.assert_array_equal(shaped[:2, 2], 0.0)
    cov = np.linalg.inv(shaped)
    assert np.sqrt(cov[0, 0]) == pytest.approx(0.03 * graph.params.odom_max_sigma_ratio)
    assert np.sqrt(cov[1, 1]) == pytest.approx(0.03)
    full = PoseGraph(PoseGraphParams(odom_information="hessian")).odom_information_matrix(
        info, sigmas
    )
    assert np.sqrt(np.linalg.inv(full)[2, 2]) > 1.5 * sigmas[2]  # "hessian" loosens the heading
