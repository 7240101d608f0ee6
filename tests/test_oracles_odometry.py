"""Odometry against poses worked out by hand from the error model's definition.

- systematic errors of ``Odometry`` (not only of the per-read ``perturb_increment``):
  turns scaled both ways, the rot1–trans–rot2 split of a diagonal step, heading drift
  accumulated per cell (a chord of known length per cell);
- the random walk is linear inside a cell: reads that split one cell report distances
  in proportion, with one normal per cell (the normals are the rng's own, drawn here);
- dataset 2's induced error by instruction (``Odometry.induce``) and per read
  (``perturb_increment``) together with systematic errors, along the motion or not.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from albot2d.geometry import Pose
from albot2d.sim.odometry import Odometry, OdometryNoise, perturb_increment

QUARTER = math.pi / 4


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_odometry_scales_left_and_right_turns_alike(sign: float) -> None:
    """A 10 % turn-scale error turns a 45° turn into 49.5°, either way round."""
    odom = Odometry(OdometryNoise(turn_scale_error=0.1))
    reading = odom.update(Pose(0.0, 0.0, sign * QUARTER))
    assert odom.pose.theta == pytest.approx(sign * 1.1 * QUARTER, abs=1e-12)
    assert (odom.pose.x, odom.pose.y) == (0.0, 0.0)
    assert reading.turn_rad == pytest.approx(sign * 1.1 * QUARTER, abs=1e-12)


def test_a_diagonal_step_is_turn_straight_turn_with_both_turns_scaled() -> None:
    """(1, 1, 0): turn 45° (reported 49.5°), drive √2, turn −45° (reported −49.5°): the
    robot ends √2 away along 49.5°, facing 0."""
    odom = Odometry(OdometryNoise(turn_scale_error=0.1))
    odom.update(Pose(1.0, 1.0, 0.0))
    angle = 1.1 * QUARTER
    assert odom.pose.x == pytest.approx(math.sqrt(2) * math.cos(angle), abs=1e-12)
    assert odom.pose.y == pytest.approx(math.sqrt(2) * math.sin(angle), abs=1e-12)
    assert odom.pose.theta == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("direction", [1.0, -1.0])
def test_heading_drift_bends_the_path_cell_by_cell(direction: float) -> None:
    """Drift 2°/m on 0.5 m cells, 1 m driven (forwards or backwards) and 2 % long: the
    first cell is a 0.51 m chord at heading 0, the second at 1°; heading 2° at the end
    (drift goes with distance, not direction)."""
    noise = OdometryNoise(heading_drift_deg_per_m=2.0, distance_scale_error=0.02, resolution_m=0.5)
    odom = Odometry(noise)
    odom.update(Pose(direction * 1.0, 0.0, 0.0))
    one = math.radians(1.0)
    assert odom.pose.x == pytest.approx(direction * 0.51 * (1.0 + math.cos(one)), abs=1e-12)
    assert odom.pose.y == pytest.approx(direction * 0.51 * math.sin(one), abs=1e-12)
    assert odom.pose.theta == pytest.approx(2.0 * one, abs=1e-12)


def test_reads_inside_one_cell_share_its_normal() -> None:
    """alpha3 = 0.1 on 1 cm cells: a cell's distance error is 0.1·√0.01·z = 0.01·z, so a
    read of d inside it reports d·(1 + z). A read stopping 50 nm short of the cell's end
    and one of the next 10 nm both report (1 + z₁)·d with the rng's first distance normal
    z₁; the following read, in a new cell, uses the next pair's (z₃)."""
    noise = OdometryNoise(alpha3=0.1, resolution_m=0.01)
    odom = Odometry(noise, np.random.default_rng(3))
    z = np.random.default_rng(3).standard_normal(4)
    first = odom.update(Pose(0.01 - 5e-8, 0.0, 0.0)).increment.x
    second = odom.update(Pose(1e-8, 0.0, 0.0)).increment.x
    assert first == pytest.approx((0.01 - 5e-8) * (1.0 + z[1]), rel=1e-9)
    assert second == pytest.approx(1e-8 * (1.0 + z[1]), rel=1e-6)
    # 40 nm left in the first cell, then 0.005 m of the second (normal z[3]).
    third = odom.update(Pose(0.005 + 4e-8, 0.0, 0.0)).increment.x
    assert third == pytest.approx(4e-8 * (1.0 + z[1]) + 0.005 * (1.0 + z[3]), rel=1e-9)


@pytest.mark.parametrize("along", [False, True])
def test_induce_adds_one_step_per_instruction(along: bool) -> None:
    """Induced 0.1 m and 2°: a right turn gets −2° along the motion (+2° otherwise), then a
    backward move −0.1 m along the motion (+0.1 m otherwise) in the turned frame."""
    noise = OdometryNoise(induced_step_m=0.1, induced_step_deg=2.0, induced_along_motion=along)
    odom = Odometry(noise)
    turn = -2.0 if along else 2.0
    assert odom.induce("turn", -0.5) == Pose(0.0, 0.0, math.radians(turn))
    assert odom.pose.theta == pytest.approx(math.radians(turn), abs=1e-15)
    move = -0.1 if along else 0.1
    assert odom.induce("move", -1.0) == Pose(move, 0.0, 0.0)
    assert odom.pose.x == pytest.approx(move * math.cos(math.radians(turn)), abs=1e-15)
    assert odom.pose.y == pytest.approx(move * math.sin(math.radians(turn)), abs=1e-15)
    assert odom.induce("other", 1.0) is None
    assert Odometry(OdometryNoise(induced_step_deg=2.0)).induce("move", 1.0) is None
    assert Odometry(OdometryNoise(induced_step_m=0.1)).induce("turn", 1.0) is None


@pytest.mark.parametrize("along", [False, True])
def test_per_read_induced_error_after_the_systematic_errors(along: bool) -> None:
    """With 10 % distance and turn scale errors: a backward 1 m read is −1.1 m, then the
    induced 0.05 m (−0.05 along the motion); a right turn of 0.5 rad is −0.55 rad, then
    the induced 2° (−2° along the motion)."""
    noise = OdometryNoise(
        distance_scale_error=0.1,
        turn_scale_error=0.1,
        induced_step_m=0.05,
        induced_step_deg=2.0,
        induced_along_motion=along,
    )
    back = perturb_increment(Pose(-1.0, 0.0, 0.0), noise, None)
    assert back.x == pytest.approx(-1.15 if along else -1.05, abs=1e-12)
    assert back.y == pytest.approx(0.0, abs=1e-12)
    assert back.theta == pytest.approx(0.0, abs=1e-12)
    right = perturb_increment(Pose(0.0, 0.0, -0.5), noise, None)
    extra = -math.radians(2.0) if along else math.radians(2.0)
    assert (right.x, right.y) == (0.0, 0.0)
    assert right.theta == pytest.approx(-0.55 + extra, abs=1e-12)
    left = perturb_increment(Pose(0.0, 0.0, 0.5), noise, None)
    assert left.theta == pytest.approx(0.55 + math.radians(2.0), abs=1e-12)


@pytest.mark.parametrize(
    ("increment", "along", "want"),
    [
        (Pose(0.0, 1.0, 0.0), False, (0.0, 1.5, 0.0)),  # sideways: lengthened along y
        (Pose(-3.0, -4.0, 0.25), True, (-3.3, -4.4, 0.25)),  # backwards, along the motion
        (Pose(-3.0, -4.0, 0.25), False, (-2.7, -3.6, 0.25)),  # backwards, +0.5 m forward
        (Pose(0.3, 0.0, 0.0), False, (0.8, 0.0, 0.0)),
    ],
)
def test_exact_induced_move_of_any_direction(
    increment: Pose, along: bool, want: tuple[float, float, float]
) -> None:
    """A read declared a move gets 0.5 m more along its own direction (signed by x)."""
    noise = OdometryNoise(induced_step_m=0.5, induced_along_motion=along)
    got = perturb_increment(increment, noise, None, "move")
    assert (got.x, got.y, got.theta) == pytest.approx(want, abs=1e-12)


def test_one_cells_heading_error_is_alpha_times_root_cell_times_its_normal() -> None:
    """alpha2 = 0.1 rad/√m on 1 cm cells: one cell driven turns the heading by
    0.1·√0.01·z = 0.01·z, z the rng's first normal (the cell's heading normal)."""
    odom = Odometry(OdometryNoise(alpha2=0.1, resolution_m=0.01), np.random.default_rng(5))
    z = np.random.default_rng(5).standard_normal(2)
    odom.update(Pose(0.01, 0.0, 0.0))
    assert odom.pose.theta == pytest.approx(0.01 * z[0], rel=1e-9)
    assert odom.pose.x == pytest.approx(0.01, abs=1e-15)


def test_heading_variance_of_a_path_by_hand() -> None:
    """alpha1 = 0.1, alpha2 = 0.2: 2 rad turned and 3 m driven (signs ignored):
    0.01·2 + 0.04·3 = 0.14 rad²."""
    from albot2d.sim.odometry import heading_variance_rad2

    noise = OdometryNoise(alpha1=0.1, alpha2=0.2)
    got = heading_variance_rad2(noise, [3.0, -3.0, 0.0], [2.0, -2.0, 0.0])
    np.testing.assert_allclose(got, [0.14, 0.14, 0.0], atol=1e-15)


def test_random_noise_without_an_rng_is_refused_by_name() -> None:
    with pytest.raises(
        ValueError, match=r"^perturb_increment: random odometry noise needs an rng$"
    ):
        perturb_increment(Pose(1.0, 0.0, 0.0), OdometryNoise(alpha1=0.1), None)


def test_turning_slips_forward_by_alpha4_along_the_heading() -> None:
    """alpha4 = 0.1 m/√rad on 1° cells: turning one cell slips 0.1·√(π/180)·z metres
    along the heading it had (60°), z the cell's distance normal."""
    res = math.radians(1.0)
    noise = OdometryNoise(alpha4=0.1, resolution_deg=1.0)
    start = Pose(0.0, 0.0, math.pi / 3)
    odom = Odometry(noise, np.random.default_rng(9), start=start)
    z = np.random.default_rng(9).standard_normal(2)
    odom.update(Pose(0.0, 0.0, -res))
    slip = 0.1 * math.sqrt(res) * z[1]
    assert odom.pose.x == pytest.approx(0.5 * slip, rel=1e-9)
    assert odom.pose.y == pytest.approx(math.sqrt(3) / 2 * slip, rel=1e-9)
    assert odom.pose.theta == pytest.approx(math.pi / 3 - res, abs=1e-12)
