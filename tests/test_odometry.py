"""Odometry: exact zero-noise integration, induced errors, noise statistics, bias."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import example, given
from hypothesis import strategies as st

from albot2d.errors import InputError
from albot2d.geometry import Pose
from albot2d.sim.odometry import (
    NOISE_PRESETS,
    Odometry,
    OdometryNoise,
    noise_preset,
    perturb_increment,
)

steps = st.one_of(
    st.floats(-math.pi, math.pi, exclude_max=True).map(lambda a: Pose(0.0, 0.0, a)),
    st.floats(-3.0, 3.0).map(lambda d: Pose(d, 0.0, 0.0)),
    st.tuples(st.floats(-2, 2), st.floats(-2, 2), st.floats(-3, 3)).map(lambda t: Pose(*t)),
)


@given(
    start=st.tuples(st.floats(-50, 50), st.floats(-50, 50), st.floats(-3, 3)),
    increments=st.lists(steps, max_size=60),
)
def test_zero_noise_equals_truth_bit_for_bit(start: tuple, increments: list[Pose]) -> None:
    truth = Pose(*start)
    odom = Odometry(OdometryNoise(), start=truth)
    for inc in increments:
        reading = odom.update(inc)
        truth = truth.compose(inc)
        assert reading.increment == inc
        assert reading.pose == truth


@given(increments=st.lists(steps, min_size=1, max_size=30))
@example(increments=[Pose(0.0, 0.0, math.pi - 1e-3)])
def test_induced_error_is_exact_per_step(increments: list[Pose]) -> None:
    noise = OdometryNoise(induced_step_m=0.10, induced_step_deg=1.0)
    for inc in increments:
        reported = perturb_increment(inc, noise, None)
        if inc.x == 0.0 and inc.y == 0.0 and inc.theta != 0.0:  # a turn step
            assert (reported.x, reported.y) == (0.0, 0.0)
            expected = inc.theta + math.radians(1.0)
            if expected < math.pi:
                assert reported.theta == expected
            else:
                assert reported.theta == pytest.approx(expected - 2 * math.pi, abs=1e-12)
        elif inc.y == 0.0 and inc.theta == 0.0 and inc.x != 0.0:  # a move step
            assert reported == Pose(inc.x + 0.10, 0.0, 0.0)
        else:
            assert reported == inc


def test_induced_error_with_explicit_kind_and_along_motion() -> None:
    noise = OdometryNoise(induced_step_m=0.1, induced_step_deg=1.0, induced_along_motion=True)
    assert perturb_increment(Pose(0.0, 0.0, 0.0), noise, None, "move") == Pose(0.1, 0.0, 0.0)
    assert perturb_increment(Pose(-0.5, 0.0, 0.0), noise, None) == Pose(-0.6, 0.0, 0.0)
    right = perturb_increment(Pose(0.0, 0.0, -0.2), noise, None)
    assert right.theta == -0.2 - math.radians(1.0)
    # A composite step gets no induced error unless its kind is given.
    diag = Pose(0.3, 0.4, 0.1)
    assert perturb_increment(diag, noise, None) == diag
    longer = perturb_increment(diag, noise, None, "move")
    assert math.hypot(longer.x, longer.y) == pytest.approx(0.6)


def _draws(inc: Pose, noise: OdometryNoise, n: int = 4000) -> np.ndarray:
    rng = np.random.default_rng(12345)
    return np.array([_as_tuple(perturb_increment(inc, noise, rng)) for _ in range(n)])


def _as_tuple(p: Pose) -> tuple[float, float, float]:
    return p.x, p.y, p.theta


@pytest.mark.parametrize("distance", [0.1, 1.0, -2.0])
def test_move_noise_std_matches_model(distance: float) -> None:
    noise = OdometryNoise(alpha1=0.05, alpha2=0.02, alpha3=0.04, alpha4=0.01)
    samples = _draws(Pose(distance, 0.0, 0.0), noise)
    trans = np.copysign(np.hypot(samples[:, 0], samples[:, 1]), samples[:, 0])
    d = abs(distance)
    assert trans.mean() == pytest.approx(distance, abs=4 * noise.alpha3 * d / math.sqrt(4000))
    assert trans.std(ddof=1) == pytest.approx(noise.alpha3 * d, rel=0.06)
    # The heading is rot1 + rot2: two independent draws of std alpha2·d.
    assert samples[:, 2].std(ddof=1) == pytest.approx(math.sqrt(2) * noise.alpha2 * d, rel=0.06)


@pytest.mark.parametrize("angle", [math.radians(1.0), -1.2])
def test_turn_noise_std_matches_model(angle: float) -> None:
    noise = OdometryNoise(alpha1=0.05, alpha2=0.02, alpha3=0.04, alpha4=0.01)
    samples = _draws(Pose(0.0, 0.0, angle), noise)
    assert samples[:, 2].mean() == pytest.approx(angle, abs=4 * 0.05 * abs(angle) / 60)
    assert samples[:, 2].std(ddof=1) == pytest.approx(noise.alpha1 * abs(angle), rel=0.06)
    assert samples[:, 0].std(ddof=1) == pytest.approx(noise.alpha4 * abs(angle), rel=0.06)


def test_systematic_bias() -> None:
    noise = OdometryNoise(distance_scale_error=0.02, heading_drift_deg_per_m=1.5)
    reported = perturb_increment(Pose(2.0, 0.0, 0.0), noise, None)
    assert reported.x == pytest.approx(2.04)
    assert reported.y == pytest.approx(0.0, abs=1e-15)
    assert reported.theta == pytest.approx(math.radians(3.0))
    turn = perturb_increment(Pose(0.0, 0.0, 0.5), noise, None)
    assert _as_tuple(turn) == pytest.approx((0.0, 0.0, 0.5))


def test_random_noise_needs_rng_and_draws_per_cell_of_path() -> None:
    noise = OdometryNoise(alpha3=0.1, resolution_m=0.5)
    with pytest.raises(ValueError, match="rng"):
        Odometry(noise)
    # Two normals per 0.5 m cell, drawn in blocks: 5 m is 10 cells, 20 normals, whatever
    # the reads; one 5 m read and fifty 10 cm reads report the same pose.
    once, often = (
        Odometry(noise, np.random.default_rng(7)),
        Odometry(noise, np.random.default_rng(7)),
    )
    once.update(Pose(5.0, 0.0, 0.0))
    for _ in range(50):
        often.update(Pose(0.1, 0.0, 0.0))
    assert once.pose.x == pytest.approx(often.pose.x, abs=1e-12)
    z = np.random.default_rng(7).standard_normal(20)[1::2]
    assert once.pose.x == pytest.approx(5.0 + 0.1 * math.sqrt(0.5) * z.sum(), abs=1e-12)


def test_reading_properties() -> None:
    odom = Odometry(start=Pose(1.0, 2.0, 0.0))
    reading = odom.update(Pose(3.0, 4.0, 0.25))
    assert reading.distance_m == 5.0 and reading.turn_rad == 0.25
    assert odom.pose == Pose(1.0, 2.0, 0.0).compose(Pose(3.0, 4.0, 0.25))


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("alpha1", -0.1),
        ("alpha3", math.nan),
        ("distance_scale_error", -1.0),
        ("heading_drift_deg_per_m", math.inf),
        ("induced_step_m", "x"),
        ("induced_along_motion", 1),
    ],
)
def test_noise_params_validated(field: str, value: object) -> None:
    with pytest.raises(InputError, match=field):
        OdometryNoise(**{field: value})


def test_presets() -> None:
    assert noise_preset("none").is_zero
    assert noise_preset("typical").is_random and noise_preset("typical").is_biased
    with pytest.raises(InputError, match="valid: " + ", ".join(NOISE_PRESETS)):
        noise_preset("bogus")


def test_turn_scale_error_scales_every_turn() -> None:
    noise = OdometryNoise(turn_scale_error=0.02)
    turn = perturb_increment(Pose(0.0, 0.0, math.radians(90.0)), noise, None)
    assert math.degrees(turn.theta) == pytest.approx(91.8)
    right = perturb_increment(Pose(0.0, 0.0, math.radians(-45.0)), noise, None)
    assert math.degrees(right.theta) == pytest.approx(-45.9)
    straight = perturb_increment(Pose(1.0, 0.0, 0.0), noise, None)
    assert (straight.x, straight.y, straight.theta) == (1.0, 0.0, 0.0)
    with pytest.raises(InputError, match="turn_scale_error"):
        OdometryNoise(turn_scale_error=-1.5)


def test_pioneer3dx_preset_is_documented_and_between_low_and_typical():
    import albot2d.sim.odometry as odometry

    p3 = noise_preset("pioneer3dx")
    low, typical = noise_preset("low"), noise_preset("typical")
    assert p3.is_random and p3.is_biased
    assert low.alpha1 <= p3.alpha1 <= typical.alpha1
    assert 0.0 < p3.turn_scale_error < typical.turn_scale_error
    # the sources are named beside the numbers
    with open(odometry.__file__, encoding="utf-8") as f:
        source = f.read()
    assert "Borenstein & Feng" in source and "Pioneer 3 Operations Manual" in source


def test_pioneer3dx_quarter_turn_error_is_about_one_percent():
    # 1000 simulated 90° turns: mean error 1 % (turn scale), spread 1 % (alpha1)
    rng = np.random.default_rng(0)
    p3 = noise_preset("pioneer3dx")
    quarter = math.pi / 2
    reported = np.array(
        [perturb_increment(Pose(0.0, 0.0, quarter), p3, rng).theta for _ in range(1000)]
    )
    err = np.degrees(reported - quarter)
    assert np.mean(err) == pytest.approx(0.9, abs=0.15)
    assert np.std(err) == pytest.approx(0.9, abs=0.15)
