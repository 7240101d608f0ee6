"""The simulated laser: exact zero-noise scans, mount, validity, noise statistics, seeding."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from albot2d.errors import InputError
from albot2d.frames import Scan
from albot2d.geometry import (
    Pose,
    point_segment_distance,
    polygon_ring_segments,
    transform_points,
    transform_segments,
)
from albot2d.sim.laser import Laser, LaserNoise, LaserParams
from albot2d.sim.raycast import RayCaster, cast_brute_force
from tests.raycast_helpers import (
    BACKENDS,
    EXACT_M,
    box_segments,
    grazing,
    office_segments,
    shapely_ranges,
)
from worldgen.strategies import worlds

ROOM = box_segments(-4.0, -3.0, 6.0, 5.0)
ZERO = LaserNoise.zero()


def noise(**kwargs: float) -> LaserNoise:
    return dataclasses.replace(ZERO, **kwargs)


def world_points(scan: Scan, robot: Pose) -> np.ndarray:
    return transform_points(robot.as_array(), scan.points())


def test_zero_noise_scan_is_exact_and_flags_no_returns() -> None:
    walls = np.vstack([ROOM[:3], [[-4.0, -3.0, -4.0, 0.0]]])  # a gap in the left wall
    laser = Laser(walls, LaserParams(max_range_m=20.0), ZERO)
    robot = Pose(1.0, 0.5, 2.2)
    scan = laser.scan(robot, np.random.default_rng(0), timestamp=3.5)
    want = shapely_ranges(walls, (robot.x, robot.y), laser.angles + robot.theta, 20.0)
    assert scan.n_beams == 181 and scan.timestamp == 3.5
    np.testing.assert_array_equal(scan.valid, np.isfinite(want))
    np.testing.assert_allclose(scan.ranges[scan.valid], want[scan.valid], rtol=0, atol=1e-9)
    assert 0 < (~scan.valid).sum() < 181
    assert np.all(scan.ranges[~scan.valid] == 20.0)
    assert np.all(scan.ranges <= scan.max_range_m)
    np.testing.assert_allclose(scan.angles, np.radians(np.arange(-90, 91)), atol=1e-12)
    dist = point_segment_distance(world_points(scan, robot), walls).min(axis=1)
    assert dist.max() < 1e-9


def test_mount_offset_moves_the_beams_and_is_recorded() -> None:
    params = LaserParams(mount_x_m=0.16, mount_y_m=-0.05, mount_yaw_deg=10.0)
    laser = Laser(ROOM, params, ZERO)
    robot = Pose(0.3, -0.7, -0.4)
    scan = laser.scan(robot, np.random.default_rng(1))
    assert scan.laser_pose == params.mount_pose
    lp = robot @ params.mount_pose
    want = shapely_ranges(ROOM, (lp.x, lp.y), laser.angles + lp.theta, 30.0)
    np.testing.assert_allclose(scan.ranges, want, atol=1e-9)
    assert point_segment_distance(world_points(scan, robot), ROOM).min(axis=1).max() < 1e-9


def test_beam_options_361_and_full_circle() -> None:
    half_degree = Laser(ROOM, LaserParams(n_beams=361), ZERO)
    np.testing.assert_allclose(np.diff(half_degree.angles), math.radians(0.5))
    circle = Laser(ROOM, LaserParams(fov_deg=360.0, n_beams=360), ZERO)
    assert circle.angles[0] == pytest.approx(-math.pi)
    assert circle.angles[-1] == pytest.approx(math.pi - math.radians(1.0))
    assert circle.scan(Pose(), np.random.default_rng(0)).valid.all()
    assert LaserParams.sick_lms200().max_range_m == 80.0


def test_dynamic_obstacles_are_seen() -> None:
    laser = Laser(ROOM, noise=ZERO)
    person = box_segments(1.5, -0.3, 2.1, 0.3)
    without = laser.scan(Pose(), np.random.default_rng(0))
    seen = laser.scan(Pose(), np.random.default_rng(0), extra_segments=person)
    assert seen.ranges[90] == pytest.approx(1.5) and without.ranges[90] == pytest.approx(6.0)
    assert np.all(seen.ranges <= without.ranges + 1e-12)


def test_zero_noise_draws_nothing_and_min_range_invalidates() -> None:
    rng = np.random.default_rng(5)
    before = rng.bit_generator.state
    close = Laser(box_segments(-0.03, -0.03, 0.03, 0.03), LaserParams(min_range_m=0.05), ZERO)
    scan = close.scan(Pose(), rng)
    assert rng.bit_generator.state == before
    assert not scan.valid.any() and np.all(scan.ranges == 30.0)


def test_same_seed_gives_identical_scans_and_other_seeds_differ() -> None:
    laser = Laser(office_segments(4), noise=LaserNoise.sick_lms200())
    pose = Pose(6.2, 5.1, 0.9)
    a = laser.scan(pose, np.random.default_rng(42))
    b = laser.scan(pose, np.random.default_rng(42))
    c = laser.scan(pose, np.random.default_rng(43))
    np.testing.assert_array_equal(a.ranges, b.ranges)
    np.testing.assert_array_equal(a.valid, b.valid)
    assert not np.array_equal(a.ranges, c.ranges)


def many_scans(laser: Laser, pose: Pose, n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    scans = [laser.scan(pose, rng) for _ in range(n)]
    return np.array([s.ranges for s in scans]), np.array([s.valid for s in scans])


def test_range_noise_std_matches_its_parameters() -> None:
    nz = noise(range_sigma_m=0.02, range_sigma_per_m=0.01)
    laser = Laser(ROOM, LaserParams(fov_deg=360.0, n_beams=360), nz)
    pose = Pose(0.5, 0.2, 0.3)
    exact = laser.true_ranges(pose)
    ranges, valid = many_scans(laser, pose, 300)
    assert valid.all()
    z = (ranges - exact) / (0.02 + 0.01 * exact)
    assert abs(z.mean()) < 0.02
    assert z.std() == pytest.approx(1.0, rel=0.03)
    far = exact > np.median(exact)
    near_sd = (ranges - exact)[:, ~far].std()
    far_sd = (ranges - exact)[:, far].std()
    assert far_sd > near_sd  # the proportional part shows


def test_dropout_fraction_matches_probability() -> None:
    laser = Laser(ROOM, noise=noise(dropout_prob=0.2))
    ranges, valid = many_scans(laser, Pose(), 200)
    assert (~valid).mean() == pytest.approx(0.2, abs=0.01)
    assert np.all(ranges[~valid] == laser.params.max_range_m)


def test_quantized_ranges_are_multiples_of_the_resolution() -> None:
    laser = Laser(ROOM, noise=noise(range_resolution_m=0.05, range_sigma_m=0.01))
    scan = laser.scan(Pose(0.11, 0.07, 0.2), np.random.default_rng(2))
    steps = scan.ranges[scan.valid] / 0.05
    np.testing.assert_allclose(steps, np.round(steps), atol=1e-9)


def test_angle_jitter_casts_off_nominal_but_reports_nominal_angles() -> None:
    walls = office_segments(3)
    pose = Pose(5.3, 6.1, 0.4)
    exact = Laser(walls, noise=ZERO)
    jittery = Laser(walls, noise=noise(angle_jitter_deg=0.5))
    scan = jittery.scan(pose, np.random.default_rng(9))
    np.testing.assert_array_equal(scan.angles, exact.angles)
    jitter = np.random.default_rng(9).normal(0.0, math.radians(0.5), 181)
    want = RayCaster(walls).cast((pose.x, pose.y), exact.angles + jitter + pose.theta, 30.0)
    np.testing.assert_allclose(scan.ranges[scan.valid], want[scan.valid], atol=1e-9)
    assert np.abs(scan.ranges - exact.true_ranges(pose)).max() > 1e-3
    no_jitter = Laser(walls, noise=noise(angle_jitter_deg=0.0)).scan(pose, np.random.default_rng(9))
    np.testing.assert_array_equal(
        no_jitter.ranges, exact.scan(pose, np.random.default_rng(0)).ranges
    )


def test_mixed_pixels_fall_between_foreground_and_background() -> None:
    pillar = box_segments(1.0, -0.2, 1.4, 0.2)
    walls = np.vstack([ROOM, pillar])
    pose = Pose()
    exact = Laser(walls, noise=ZERO).true_ranges(pose)
    jumps = np.flatnonzero(np.abs(np.diff(exact)) > 0.5)
    assert len(jumps) == 2
    mixed = Laser(walls, noise=noise(mixed_pixel_prob=1.0, mixed_pixel_min_jump_m=0.5))
    ranges, _ = many_scans(mixed, pose, 50)
    changed = ranges != exact
    assert np.all(changed.sum(axis=1) == len(jumps))
    beside = np.zeros(len(exact), dtype=bool)
    beside[jumps] = beside[jumps + 1] = True
    assert not changed[:, ~beside].any() and changed[:, beside].all(axis=0).sum() == 0
    near = np.minimum(exact[jumps], exact[jumps + 1])
    far = np.maximum(exact[jumps], exact[jumps + 1])
    for k, j in enumerate(jumps):
        hit = ranges[:, j : j + 2][changed[:, j : j + 2]]
        assert np.all((hit >= near[k]) & (hit <= far[k]))
    off = Laser(walls, noise=noise(mixed_pixel_prob=0.0)).scan(pose, np.random.default_rng(0))
    np.testing.assert_array_equal(off.ranges, exact)


def test_max_range_returns_are_invalid() -> None:
    laser = Laser([[5.0, -1.0, 5.0, 1.0]], LaserParams(max_range_m=8.0), LaserNoise.sick_lms200())
    scan = laser.scan(Pose(), np.random.default_rng(0))
    assert scan.valid[85:96].sum() >= 9 and not scan.valid[:60].any()
    assert np.all(scan.ranges <= 8.0)
    short = Laser([[5.0, -1.0, 5.0, 1.0]], LaserParams(max_range_m=4.0), ZERO)
    assert not short.scan(Pose(), np.random.default_rng(0)).valid.any()


@settings(max_examples=8)
@given(world=worlds(max_size_m=25.0, dynamic=True), heading=st.floats(-math.pi, math.pi))
def test_generated_worlds_scan_exactly_with_moving_obstacles(world, heading: float) -> None:
    """Zero-noise scans in generated worlds equal brute force over walls, clutter and the
    moving obstacles' outlines, and every valid hit lies on one of them."""
    laser = Laser.for_world(world, noise=ZERO)
    movers = [
        transform_segments(o.pose.as_array(), polygon_ring_segments(o.shape))
        for o in world.dynamic_obstacles
    ]
    extra = np.vstack(movers) if movers else None
    everything = np.vstack([world.obstacle_segments, *movers])
    poses = [world.start] + [Pose(x, y, heading) for x, y in world.roadmap.nodes[:4]]
    for pose in poses:
        scan = laser.scan(pose, np.random.default_rng(0), extra_segments=extra)
        world_angles = laser.angles + pose.theta
        want = cast_brute_force(everything, (pose.x, pose.y), world_angles, 30.0)
        clear = ~grazing(everything, (pose.x, pose.y), world_angles)  # float-precision ties
        np.testing.assert_array_equal(scan.valid[clear], np.isfinite(want[clear]))
        both = clear & scan.valid
        np.testing.assert_allclose(scan.ranges[both], want[both], atol=EXACT_M)
        if both.any():
            pts = transform_points(pose.as_array(), scan.points(valid_only=False)[both])
            assert point_segment_distance(pts, everything).min(axis=1).max() < EXACT_M


def test_for_world_uses_obstacle_segments() -> None:
    class FakeWorld:
        obstacle_segments = ROOM

    laser = Laser.for_world(FakeWorld(), noise=ZERO)
    assert laser.caster.n_segments == 4
    shared = Laser(laser.caster, LaserParams(n_beams=361), ZERO)
    assert shared.caster is laser.caster


@pytest.mark.parametrize(
    ("cls", "kwargs", "field"),
    [
        (LaserParams, {"n_beams": 1}, "n_beams"),
        (LaserParams, {"n_beams": 181.0}, "n_beams"),
        (LaserParams, {"fov_deg": 0.0}, "fov_deg"),
        (LaserParams, {"fov_deg": 400.0}, "fov_deg"),
        (LaserParams, {"max_range_m": -1.0}, "max_range_m"),
        (LaserParams, {"min_range_m": 31.0}, "min_range_m"),
        (LaserParams, {"mount_x_m": math.nan}, "mount_x_m"),
        (LaserNoise, {"range_sigma_m": -0.1}, "range_sigma_m"),
        (LaserNoise, {"range_sigma_per_m": -0.1}, "range_sigma_per_m"),
        (LaserNoise, {"angle_jitter_deg": -1.0}, "angle_jitter_deg"),
        (LaserNoise, {"dropout_prob": 1.5}, "dropout_prob"),
        (LaserNoise, {"range_resolution_m": -0.01}, "range_resolution_m"),
        (LaserNoise, {"mixed_pixel_prob": -0.5}, "mixed_pixel_prob"),
        (LaserNoise, {"mixed_pixel_min_jump_m": math.inf}, "mixed_pixel_min_jump_m"),
    ],
)
def test_bad_params_name_the_field_and_value(cls: type, kwargs: dict, field: str) -> None:
    with pytest.raises(InputError, match=field) as err:
        cls(**kwargs)
    assert repr(next(iter(kwargs.values()))) in str(err.value)


@pytest.mark.parametrize(
    "model",
    [LaserNoise.sick_lms200(), noise(mixed_pixel_prob=1.0, mixed_pixel_min_jump_m=0.05),
     noise(range_sigma_m=0.02, dropout_prob=0.2), noise(range_resolution_m=0.05),
     noise(range_sigma_per_m=0.01, angle_jitter_deg=0.3)],
)  # fmt: skip
def test_compiled_noise_gives_the_numpy_scans_from_the_same_stream(model: LaserNoise) -> None:
    pytest.importorskip("numba")
    segs = office_segments(3)
    params = LaserParams(n_beams=361, max_range_m=12.0)
    fast = Laser(segs, params, model, noise_backend="numba")
    slow = Laser(segs, params, model, noise_backend="numpy")
    assert (fast.noise_backend, slow.noise_backend) == ("numba", "numpy")
    rngs = np.random.default_rng(7), np.random.default_rng(7)
    for k in range(40):
        pose = Pose(2.0 + 0.3 * k, 1.5 + 0.1 * k, 0.4 * k)
        a, b = fast.scan(pose, rngs[0]), slow.scan(pose, rngs[1])
        np.testing.assert_array_equal(a.ranges, b.ranges)
        np.testing.assert_array_equal(a.valid, b.valid)
    assert rngs[0].random() == rngs[1].random()  # both consumed the same draws


def test_unknown_noise_backend_is_rejected() -> None:
    with pytest.raises(InputError, match="noise_backend"):
        Laser(ROOM, noise_backend="gpu")


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_smooth_wall_at_a_grazing_angle_has_no_mixed_pixels(backend: str) -> None:
    # One straight wall 1 m to the left, seen from 5° to 40° off its direction: the ranges
    # 1/sin(θ) of neighbouring beams differ by up to 2.3 m, yet there is no edge.
    wall = np.array([[-1.0, 1.0, 60.0, 1.0]])
    # Mixed pixels only: no range noise, quantisation or dropouts.
    noise = LaserNoise(
        range_sigma_m=0.0, range_sigma_per_m=0.0, dropout_prob=0.0, range_resolution_m=0.0
    )
    laser = Laser(wall, LaserParams(), noise, noise_backend=backend)
    rng = np.random.default_rng(0)
    grazing = (laser.angles >= np.radians(5.0)) & (laser.angles <= np.radians(40.0))
    exact = 1.0 / np.sin(laser.angles[grazing])
    for _ in range(20):
        scan = laser.scan(Pose(0.0, 0.0, 0.0), rng)
        assert np.allclose(scan.ranges[grazing], exact, rtol=0.0, atol=1e-9)
    # albot2d's former model (kept as an option) blended along this wall: the defect.
    former = Laser(
        wall,
        LaserParams(),
        dataclasses.replace(noise, mixed_pixel_edges="any_jump"),
        noise_backend=backend,
    )
    off_wall = sum(
        int((~np.isclose(former.scan(Pose(), rng).ranges[grazing], exact, atol=1e-9)).sum())
        for _ in range(20)
    )
    assert off_wall > 20


@pytest.mark.parametrize("backend", BACKENDS)
def test_mixed_pixels_come_only_from_occluding_edges(backend: str) -> None:
    # A room with a pillar, its near wall drawn in three collinear pieces, seen from a
    # corner: grazing walls, a wall in pieces and concave corners join smoothly; only the
    # pillar's silhouette edges (and, with moving obstacles, a box's) can mix.
    room = np.vstack([
        [[-4.0, -3.0, -1.0, -3.0], [-1.0, -3.0, 2.5, -3.0], [2.5, -3.0, 6.0, -3.0]],
        ROOM[1:],
    ])  # fmt: skip
    pillar = box_segments(2.0, 1.0, 2.6, 1.6)
    walls = np.vstack([room, pillar])
    mixing = noise(mixed_pixel_prob=1.0, mixed_pixel_min_jump_m=0.2)
    pose = Pose(-3.7, -2.7, 0.6)
    exact = Laser(walls, noise=ZERO).true_ranges(pose)
    laser = Laser(walls, noise=mixing, noise_backend=backend)
    on_pillar = (
        point_segment_distance(
            world_points(Laser(walls, noise=ZERO).scan(pose, np.random.default_rng(0)), pose),
            pillar,
        ).min(axis=1)
        < 1e-9
    )
    edge = np.flatnonzero(on_pillar[1:] != on_pillar[:-1])
    assert len(edge) == 2 and np.all(np.abs(np.diff(exact))[edge] > 0.2)
    jumps = np.flatnonzero(np.abs(np.diff(exact)) > 0.2)
    assert len(jumps) > 10  # the walls far off at a grazing angle
    beside = np.zeros(len(exact), dtype=bool)
    beside[edge] = beside[edge + 1] = True
    changed = np.zeros(len(exact), dtype=bool)
    rng = np.random.default_rng(3)
    for _ in range(20):
        changed |= laser.scan(pose, rng).ranges != exact
    assert changed[beside].any() and not changed[~beside].any()
    # A moving box in front of the far wall: its outline's ends are edges too.
    box = box_segments(3.0, -1.2, 3.4, -0.8)
    with_box = Laser(walls, noise=ZERO).true_ranges(pose, extra_segments=box)
    angle = laser.angles + pose.theta
    hits = np.column_stack([pose.x + with_box * np.cos(angle), pose.y + with_box * np.sin(angle)])
    on_box = point_segment_distance(hits, box).min(axis=1) < 1e-9
    box_edge = np.flatnonzero(on_box[1:] != on_box[:-1])
    assert len(box_edge) == 2
    may_mix = np.zeros(len(exact), dtype=bool)
    may_mix[np.r_[edge, edge + 1, box_edge, box_edge + 1]] = True
    moved = np.zeros(len(exact), dtype=bool)
    for _ in range(20):
        moved |= laser.scan(pose, rng, extra_segments=box).ranges != with_box
    assert moved[np.r_[box_edge, box_edge + 1]].any() and not moved[~may_mix].any()
