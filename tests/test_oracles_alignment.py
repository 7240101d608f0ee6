"""APE and SE(2) alignment against answers worked out by hand, not against each other.

- A rigid copy of a trajectory aligns back exactly: the rotation and translation are the
  inverse of the motion that made it, and every error is zero.
- Radial position errors of equal length on a square leave the best alignment where it
  was (no torque, no net shift), so every position error is exactly that length; heading
  errors pass through alignment untouched, so their RMSE and maximum are known.
- In the plane the least-squares rotation has a closed form: ``θ = atan2(Σ e×r, Σ e·r)``
  over centred points; ``align_se2`` (an SVD) must agree on random and mirrored clouds.
- evo's APE (``evo_absolute_pose_error``) gives the same hand-worked numbers, and
  ``ape_result`` falls back to albot2d's APE where evo's 3D alignment cannot run.

These run in milliseconds (no simulation), so mutation testing runs them per mutant.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from albot2d.errors import InputError
from albot2d.evaluation.metrics.alignment import (
    absolute_pose_error,
    align_se2,
    ape_result,
    evo_absolute_pose_error,
    in_world_frame,
    map_in_world_frame,
)
from albot2d.geometry import compose_arrays

SQUARE = np.array([[1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]]) * 2.0 + [3.0, -1.0]
HEADINGS = np.radians([10.0, 100.0, -170.0, 175.0])  # across ±π on purpose


def _apes(t: np.ndarray, est: np.ndarray, ref: np.ndarray) -> list:
    out = [absolute_pose_error(est, ref)]
    pytest.importorskip("evo", reason="evo is the [eval] extra (also in the test extra)")
    out.append(evo_absolute_pose_error(t, est, ref))
    return out


def _closed_form_theta(e: np.ndarray, r: np.ndarray) -> float:
    ec, rc = e - e.mean(axis=0), r - r.mean(axis=0)
    cross = np.sum(ec[:, 0] * rc[:, 1] - ec[:, 1] * rc[:, 0])
    dot = np.sum(ec[:, 0] * rc[:, 0] + ec[:, 1] * rc[:, 1])
    return math.atan2(cross, dot)


def test_a_rigid_copy_aligns_back_exactly() -> None:
    """Estimate = motion⁻¹ applied to the reference (motion: 40° and (2, −3)); the
    alignment found is the motion itself and every error is zero, with evo too."""
    ref = np.column_stack([SQUARE, HEADINGS])
    motion = np.array([2.0, -3.0, math.radians(40.0)])
    c, s = math.cos(-motion[2]), math.sin(-motion[2])
    inv = np.array([-(c * motion[0] - s * motion[1]), -(s * motion[0] + c * motion[1]), -motion[2]])
    est = compose_arrays(inv, ref)
    theta, t = align_se2(est[:, :2], ref[:, :2])
    assert theta == pytest.approx(math.radians(40.0), abs=1e-12)
    np.testing.assert_allclose(t, [2.0, -3.0], atol=1e-12)
    for ape in _apes(np.arange(4.0), est, ref):
        assert ape.poses == 4
        assert ape.align_rot_deg == pytest.approx(40.0, abs=1e-9)
        for field in ("trans_m_rmse", "trans_m_mean", "trans_m_median", "trans_m_max"):
            assert getattr(ape, field) == pytest.approx(0.0, abs=1e-9), field
        assert ape.rot_deg_rmse == pytest.approx(0.0, abs=1e-6)
        assert ape.rot_deg_max == pytest.approx(0.0, abs=1e-6)


def test_radial_errors_of_one_length_are_that_length_after_alignment() -> None:
    """Corners of a square pushed 0.3 m outwards (and the whole estimate turned by −25°
    and shifted): every position error is 0.3 m exactly. Headings off by 1, 2, 3 and 4°
    (one of them across ±π): RMSE √7.5°, maximum 4°."""
    ref = np.column_stack([SQUARE, HEADINGS])
    centre = SQUARE.mean(axis=0)
    out = (SQUARE - centre) / np.linalg.norm(SQUARE - centre, axis=1)[:, None]
    pushed = np.column_stack([SQUARE + 0.3 * out, HEADINGS + np.radians([1.0, -2.0, -3.0, 4.0])])
    est = compose_arrays([-1.0, 4.0, math.radians(-25.0)], pushed)
    for ape in _apes(np.arange(4.0), est, ref):
        assert ape.align_rot_deg == pytest.approx(25.0, abs=1e-9)
        assert ape.trans_m_rmse == pytest.approx(0.3, abs=1e-12)
        assert ape.trans_m_mean == pytest.approx(0.3, abs=1e-12)
        assert ape.trans_m_median == pytest.approx(0.3, abs=1e-12)
        assert ape.trans_m_max == pytest.approx(0.3, abs=1e-12)
        assert ape.rot_deg_rmse == pytest.approx(math.sqrt(7.5), abs=1e-7)
        assert ape.rot_deg_max == pytest.approx(4.0, abs=1e-7)


def test_position_statistics_of_unequal_errors() -> None:
    """Errors of 0.1 m at four corners and 0.4 m at the centre, all along y, with no net
    shift and no torque about the centroid, so the best alignment is the identity:
    mean 0.16, median 0.1, max 0.4, RMSE √(0.2 / 5) = 0.2."""
    ref_xy = np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 3.0], [0.0, 3.0], [2.0, 1.5]])
    # Offsets summing to zero with no torque about the centroid (2, 1.5):
    # +0.1 at x=0 and x=4 (twice each side) balance −0.4 at the centre, x = 2.
    dy = np.array([0.1, 0.1, 0.1, 0.1, -0.4])
    est_xy = ref_xy + np.column_stack([np.zeros(5), dy])
    theta, t = align_se2(est_xy, ref_xy)
    assert theta == pytest.approx(0.0, abs=1e-12)
    np.testing.assert_allclose(t, [0.0, 0.0], atol=1e-12)
    ref = np.column_stack([ref_xy, np.zeros(5)])
    est = np.column_stack([est_xy, np.zeros(5)])
    for ape in _apes(np.arange(5.0), est, ref):
        assert ape.trans_m_mean == pytest.approx(0.16, abs=1e-12)
        assert ape.trans_m_median == pytest.approx(0.1, abs=1e-12)
        assert ape.trans_m_max == pytest.approx(0.4, abs=1e-12)
        assert ape.trans_m_rmse == pytest.approx(math.sqrt(0.04), abs=1e-12)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("mirrored", [False, True])
def test_align_se2_is_the_closed_form_least_squares_rotation(seed: int, mirrored: bool) -> None:
    """Random clouds (and mirror images, whose best rigid fit is not the reflection the
    unconstrained SVD would give): θ equals the planar closed form, t maps the estimate's
    centroid onto the reference's, and no other angle fits better."""
    rng = np.random.default_rng(seed)
    r = rng.normal(size=(7, 2)) * [3.0, 1.0] + rng.normal(size=2)
    e = r @ np.array([[math.cos(1.0), -math.sin(1.0)], [math.sin(1.0), math.cos(1.0)]]).T
    e = e + rng.normal(scale=0.2, size=e.shape) + [5.0, -2.0]
    if mirrored:
        e[:, 1] *= -1.0
    theta, t = align_se2(e, r)
    assert theta == pytest.approx(_closed_form_theta(e, r), abs=1e-9)
    rot = np.array([[math.cos(theta), -math.sin(theta)], [math.sin(theta), math.cos(theta)]])
    np.testing.assert_allclose(t, r.mean(axis=0) - rot @ e.mean(axis=0), atol=1e-9)

    def cost(angle: float) -> float:
        c, s = math.cos(angle), math.sin(angle)
        m = np.array([[c, -s], [s, c]])
        shift = r.mean(axis=0) - m @ e.mean(axis=0)
        return float(np.sum((e @ m.T + shift - r) ** 2))

    best = cost(theta)
    assert all(best <= cost(a) + 1e-9 for a in np.linspace(-math.pi, math.pi, 721))


@pytest.mark.parametrize(
    ("e", "r"),
    [
        (np.zeros((3, 2)), np.zeros((4, 2))),  # different lengths
        (np.zeros((1, 2)), np.zeros((1, 2))),  # one point fixes no rotation
        (np.zeros((3, 3)), np.zeros((3, 3))),  # not planar positions
        (np.zeros(4), np.zeros(4)),  # not (N, 2)
    ],
)
def test_align_se2_rejects_what_it_cannot_align(e: np.ndarray, r: np.ndarray) -> None:
    with pytest.raises(InputError, match="alignment needs two"):
        align_se2(e, r)


def test_ape_rejects_poses_of_different_instants() -> None:
    with pytest.raises(InputError, match="same instants"):
        absolute_pose_error(np.zeros((3, 3)), np.zeros((4, 3)))


def test_in_world_frame_composes_the_start_pose_by_hand() -> None:
    """Start at (1, 2) facing +y: a pose 1 m ahead and turned 90° is at (1, 3) facing −x;
    a map wall from (1, 0) to (1, 1) lies from (1, 3) to (0, 3)."""
    start = [1.0, 2.0, math.pi / 2]
    got = in_world_frame([[0.0, 0.0, 0.0], [1.0, 0.0, math.pi / 2]], start)
    np.testing.assert_allclose(got[:, :2], [[1.0, 2.0], [1.0, 3.0]], atol=1e-12)
    assert got[0, 2] == pytest.approx(math.pi / 2)
    assert abs(got[1, 2]) == pytest.approx(math.pi)
    np.testing.assert_allclose(
        in_world_frame([1.0, 0.0, 0.0], start), [[1.0, 3.0, math.pi / 2]], atol=1e-12
    )
    wall = map_in_world_frame([[1.0, 0.0, 1.0, 1.0]], start)
    np.testing.assert_allclose(wall, [[1.0, 3.0, 0.0, 3.0]], atol=1e-12)


def test_ape_result_needs_a_reference_of_two_poses() -> None:
    poses = np.column_stack([SQUARE, HEADINGS])
    assert ape_result(np.arange(4.0), poses, None) is None
    assert ape_result(np.arange(1.0), poses[:1], poses[:1]) is None


def test_ape_result_is_evos_on_a_square_and_albot2ds_on_a_straight_line() -> None:
    """Radial 0.3 m errors: ``ape_result`` reports 0.3 m by evo when evo imports. On a
    straight line evo's 3D Umeyama is degenerate, so albot2d's APE answers (a line
    shifted 0.2 m sideways is aligned back: error 0)."""
    pytest.importorskip("evo", reason="evo is the [eval] extra (also in the test extra)")
    ref = np.column_stack([SQUARE, HEADINGS])
    centre = SQUARE.mean(axis=0)
    out = (SQUARE - centre) / np.linalg.norm(SQUARE - centre, axis=1)[:, None]
    est = np.column_stack([SQUARE + 0.3 * out, HEADINGS])
    got = ape_result(np.arange(4.0), est, ref)
    assert got is not None
    assert got.implementation.startswith("evo ")
    assert got.trans_m_max == pytest.approx(0.3, abs=1e-12)
    assert got.poses == 4
    line = np.column_stack([np.arange(5.0), np.zeros(5), np.zeros(5)])
    shifted = line + np.array([0.0, 0.2, 0.0])
    got = ape_result(np.arange(5.0), shifted, line)
    assert got is not None
    assert got.implementation == "albot2d"
    assert got.trans_m_max == pytest.approx(0.0, abs=1e-12)
    assert got.poses == 5


def test_ape_result_without_evo_is_albot2ds_ape(monkeypatch: pytest.MonkeyPatch) -> None:
    """Where evo is not installed (``albot2d`` without the eval extra) report.json's APE
    is albot2d's own: the radial 0.3 m errors of the square, by hand."""
    import sys

    monkeypatch.setitem(sys.modules, "evo.core.geometry", None)  # import fails
    ref = np.column_stack([SQUARE, HEADINGS])
    centre = SQUARE.mean(axis=0)
    out = (SQUARE - centre) / np.linalg.norm(SQUARE - centre, axis=1)[:, None]
    est = np.column_stack([SQUARE + 0.3 * out, HEADINGS])
    got = ape_result(np.arange(4.0), est, ref)
    assert got is not None
    assert got.implementation == "albot2d"
    assert got.trans_m_max == pytest.approx(0.3, abs=1e-12)


def test_evo_pose_errors_reject_a_matrix_that_is_not_a_rotation() -> None:
    """evo's own check (``lie.is_so3``) and message, on all poses at once: a pose whose
    rotation part is scaled by 1.1 is no rotation."""
    pytest.importorskip("evo", reason="evo is the [eval] extra (also in the test extra)")
    from types import SimpleNamespace

    from evo.core.lie_algebra import LieAlgebraException

    from albot2d.evaluation.metrics.alignment import evo_pose_errors

    good = np.tile(np.eye(4), (2, 1, 1))
    bad = good.copy()
    bad[1, :3, :3] *= 1.1
    ref = SimpleNamespace(positions_xyz=np.zeros((2, 3)), poses_se3=list(good))
    est = SimpleNamespace(positions_xyz=np.zeros((2, 3)), poses_se3=list(bad))
    with pytest.raises(LieAlgebraException, match=r"^matrix is not a valid SO\(3\) group element$"):
        evo_pose_errors(est, ref)
    trans, angle = evo_pose_errors(ref, ref)
    np.testing.assert_array_equal(trans, [0.0, 0.0])
    np.testing.assert_array_equal(angle, [0.0, 0.0])
