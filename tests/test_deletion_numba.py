"""The compiled (numba) sight-line test of the deletion rule gives the numpy path's shares,
bit for bit: random scenes (surfaces across, along and behind the view's, degenerate ones,
sample counts other than 8) and the updates of a simulated office run. Skipped where numba
is not installed."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from albot2d.geometry import Pose
from albot2d.mapping.albot1.deletion import visible_share

pytest.importorskip("numba")


def random_segments(rng: np.random.Generator, n: int) -> np.ndarray:
    a = rng.uniform(-6.0, 6.0, (n, 2))
    ang = rng.uniform(-np.pi, np.pi, n)
    length = rng.uniform(0.0, 4.0, n) * (rng.random(n) > 0.1)  # some zero-length
    return np.hstack([a, a + length[:, None] * np.column_stack([np.cos(ang), np.sin(ang)])])


def assert_same(segs: np.ndarray, view: np.ndarray, robot: Pose, beyond: float, k: int) -> None:
    want = visible_share(segs, view, robot, beyond, k, backend="numpy")
    got = visible_share(segs, view, robot, beyond, k, backend="numba")
    assert got.dtype == want.dtype and got.shape == want.shape
    np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize("seed", range(40))
def test_numba_share_equals_numpy_on_random_scenes(seed: int) -> None:
    rng = np.random.default_rng(seed)
    view = random_segments(rng, int(rng.integers(0, 14)))
    # Old surfaces: jittered copies of view surfaces (near the beyond_m limit) and clutter.
    near = view + rng.normal(0.0, 0.4, view.shape) * (rng.random((len(view), 1)) < 0.8)
    segs = np.vstack([near, random_segments(rng, int(rng.integers(0, 10)))])
    x, y = rng.uniform(-1.0, 1.0, 2)
    robot = Pose(float(x), float(y), float(rng.uniform(-np.pi, np.pi)))
    assert_same(segs, view, robot, float(rng.uniform(0.0, 1.0)), int(rng.integers(1, 12)))


def test_numba_share_equals_numpy_on_an_office_run() -> None:
    from albot2d.evaluation.run.setup import RunSpec, build_run
    from albot2d.geometry import transform_segments
    from albot2d.mapping import Albot1

    run = build_run(RunSpec(tour_length_m=25.0))
    m = Albot1()
    checked = 0
    for frame in itertools.islice(run.simulator.drive(run.tour, run.profile), 1500):
        before = m.map.snapshot()
        n_maps = len(m.route)
        m.observe(frame)
        for lm in m.route.maps[n_maps:]:
            view = transform_segments(lm.pose.as_array(), lm.view.segments)
            if len(before.segments):
                assert_same(before.segments, view, lm.pose, 0.5, 8)
                checked += 1
    assert checked > 50


# -- the touching test without building P -------------------------------------------------
def a_view(rng: np.random.Generator, n: int) -> tuple[np.ndarray, Pose]:
    """A laser-like view: surfaces in scan order over 180°, some meeting at corners (a
    repeated vertex), seen from a random pose."""
    x, y = rng.uniform(-3.0, 3.0, 2)
    robot = Pose(float(x), float(y), float(rng.uniform(-np.pi, np.pi)))
    bearings = np.sort(rng.uniform(-np.pi / 2, np.pi / 2, 2 * n))
    ranges = rng.uniform(0.5, 8.0, 2 * n)
    pts = np.column_stack([ranges * np.cos(bearings), ranges * np.sin(bearings)])
    corner = rng.random(n) < 0.3
    for i in np.flatnonzero(corner[1:]) + 1:
        pts[2 * i] = pts[2 * i - 1]
    c, s = np.cos(robot.theta), np.sin(robot.theta)
    world = np.column_stack([robot.x + c * pts[:, 0] - s * pts[:, 1],
                             robot.y + s * pts[:, 0] + c * pts[:, 1]])  # fmt: skip
    return world.reshape(-1, 4), robot


@pytest.mark.parametrize("seed", range(30))
def test_quick_touching_is_geos_touching_on_random_views(seed: int) -> None:
    """The kernel's sure answers agree with GEOS's line test on P; the mask (GEOS for the
    unsure) equals GEOS's on every surface. Old surfaces are put near P's edge: copies of
    the view's surfaces pushed ~r out, across the lateral axis, and clutter."""
    import shapely

    from albot2d.mapping.albot1.deletion import (
        GlobalMapParams,
        quick_touch_ring,
        quick_touching_mask,
        touching_mask,
        view_polygon,
    )
    from albot2d.mapping.albot1.deletion_numba import classify_touching

    rng = np.random.default_rng(seed)
    params = GlobalMapParams()
    segs, robot = a_view(rng, int(rng.integers(1, 15)))
    ring = quick_touch_ring(segs, robot, params)
    assert ring is not None  # a laser view is a simple polygon
    radial = segs.reshape(-1, 2) - [robot.x, robot.y]
    radial /= np.maximum(np.hypot(radial[:, :1], radial[:, 1:]), 1e-9)
    pushed = segs + (radial * rng.uniform(0.45, 0.55, (len(radial), 1))).reshape(-1, 4)
    side = np.array([-np.sin(robot.theta), np.cos(robot.theta)])
    across = np.hstack([[robot.x, robot.y] + side * 2.0, [robot.x, robot.y] - side * 2.0])
    across = across + rng.normal(0.0, 0.3, (20, 4))
    old = np.vstack([pushed, across, random_segments(rng, 40) * 2.0])
    poly = view_polygon(segs, robot)
    geos = shapely.intersects(poly, shapely.linestrings(old.reshape(-1, 2, 2)))
    r = params.enlarge_m
    status = classify_touching(np.ascontiguousarray(old), ring, robot.x, robot.y,
                               np.cos(robot.theta), np.sin(robot.theta),
                               1.011 * r + 1e-6, 0.997 * r - 1e-6, 1e-6)  # fmt: skip
    assert not (geos & (status == 0)).any() and not (~geos & (status == 1)).any()
    assert (status != 2).mean() > 0.5
    built = []

    def polygon():  # type: ignore[no-untyped-def]
        built.append(1)
        return poly

    quick = quick_touching_mask(ring, polygon, old, robot, r)
    np.testing.assert_array_equal(quick, touching_mask(poly, old, robot))
    assert len(built) == int((status == 2).any())


def test_ring_check_refuses_what_it_cannot_vouch_for() -> None:
    from albot2d.mapping.albot1.deletion_numba import ring_is_clearly_simple

    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    bowtie = np.array([[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]])
    spike = np.array([[0.0, 0.0], [2.0, 0.0], [1.0, 0.0], [1.0, 1.0]])  # folds back
    touching = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [1.0, 0.0], [0.0, 2.0]])
    assert ring_is_clearly_simple(square, 1e-6)
    for ring in (bowtie, spike, touching, square[:2], np.vstack([square, square[-1:]])):
        assert not ring_is_clearly_simple(ring, 1e-6)


def test_global_map_with_and_without_quick_touching_agree_on_an_office_run() -> None:
    """Whole runs: every update report (but P, built lazily) and the final map equal the
    GEOS path's (P built and tested for every update), for two deletion rules."""
    from albot2d.evaluation.run.setup import RunSpec, build_run
    from albot2d.mapping import Albot1, Albot1Params, GlobalMapParams, UpdateReport

    run = build_run(RunSpec(tour_length_m=25.0))
    frames = list(itertools.islice(run.simulator.drive(run.tour, run.profile), 2000))
    for rule in ("visible", "paper"):
        outputs = []
        for quick in (True, False):
            reports: list[tuple[object, ...]] = []

            def record(
                rep: UpdateReport, lm: object, out: list[tuple[object, ...]] = reports
            ) -> None:
                out.append(tuple(rep[:7]))

            params = Albot1Params(global_map=GlobalMapParams.preset(rule))
            m = Albot1(params, on_update=record)
            with pytest.MonkeyPatch.context() as mp:
                if not quick:
                    mp.setattr(
                        "albot2d.mapping.albot1.global_map.quick_touch_ring", lambda *a: None
                    )
                for frame in frames:
                    m.observe(frame)
            snap = m.global_map()
            outputs.append((reports, snap.segments.tobytes(), snap.map_ids.tobytes()))
        assert len(outputs[0][0]) > 100
        assert outputs[0] == outputs[1], rule


@pytest.mark.parametrize("seed", range(4))
def test_compiled_facing_and_seen_side_equal_the_numpy_masks(seed: int) -> None:
    from albot2d.mapping.albot1.deletion import facing_mask, facing_seen_mask, seen_side_mask

    rng = np.random.default_rng(seed)
    segs = random_segments(rng, 300)
    segs[:20, 2:] = segs[:20, :2]  # points: zero direction
    for robot in (Pose(0.0, 0.0, 0.0), Pose(*rng.uniform(-3.0, 3.0, 2), rng.uniform(-4.0, 4.0))):
        segs[20:25] = [robot.x, robot.y, robot.x + 1.0, robot.y]  # starting at the robot
        for test, side in itertools.product(
            ("both_endpoints", "midpoint", "any_endpoint"), ("any", "front")
        ):
            want = facing_mask(segs, robot, test)  # type: ignore[arg-type]
            if side == "front":
                want &= seen_side_mask(segs, robot)
            got = facing_seen_mask(segs, robot, test, side)  # type: ignore[arg-type]
            assert got.dtype == np.bool_
            np.testing.assert_array_equal(got, want)
    assert facing_seen_mask(np.zeros((0, 4)), Pose(), "midpoint", "front").shape == (0,)
