"""Exact raycasting: shapely reference, hits on walls, rigid invariance, index = brute force."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import example, given
from hypothesis import strategies as st

from albot2d.errors import InputError
from albot2d.frames import beam_angles
from albot2d.geometry import Pose, point_segment_distance, transform_segments
from albot2d.sim.raycast import (
    NEAR_PASS_MIN_PIECES,
    BeamFan,
    RayCaster,
    cast_brute_force,
    numba_available,
)
from tests.raycast_helpers import (
    BACKENDS,
    EXACT_M,
    assert_same_ranges,
    assume_not_touching,
    box_segments,
    coord,
    grazing,
    office_segments,
    ring_segments,
    segment_sets,
    shapely_ranges,
)

FAN = beam_angles(181, math.pi)
heading = st.floats(-math.pi, math.pi, allow_nan=False)


def make_caster(backend: str, segments: object, **kwargs: object) -> RayCaster:
    return RayCaster(segments, backend=backend, **kwargs)  # type: ignore[arg-type]


@pytest.mark.parametrize("backend", BACKENDS)
def test_box_room_matches_closed_form(backend: str) -> None:
    segs = box_segments(-2.0, -1.0, 3.0, 4.0)
    o = (0.5, 0.25)
    angles = np.linspace(-math.pi, math.pi, 721)
    got = make_caster(backend, segs).cast(o, angles, 100.0)
    c, s = np.cos(angles), np.sin(angles)
    with np.errstate(divide="ignore"):
        tx = np.where(c > 0, (3.0 - o[0]) / c, (-2.0 - o[0]) / c)
        ty = np.where(s > 0, (4.0 - o[1]) / s, (-1.0 - o[1]) / s)
    want = np.minimum(np.where(c != 0, tx, np.inf), np.where(s != 0, ty, np.inf))
    np.testing.assert_allclose(got, want, rtol=0.0, atol=EXACT_M)


@pytest.mark.parametrize("backend", BACKENDS)
def test_hand_made_world_matches_shapely(backend: str) -> None:
    segs = np.vstack(
        [box_segments(0, 0, 10, 8), box_segments(3, 3, 4, 4), [[6, 1, 9, 6], [1, 6, 2, 7.5]]]
    )
    for o, th in [((1.0, 1.0), 0.3), ((7.5, 2.0), 2.0), ((5.0, 6.0), -1.2)]:
        angles = FAN + th
        got = make_caster(backend, segs).cast(o, angles, 30.0)
        assert_same_ranges(got, shapely_ranges(segs, o, angles, 30.0), 30.0)


@given(segs=segment_sets(), ox=coord, oy=coord, th=heading, r_max=st.floats(1.0, 80.0))
@pytest.mark.parametrize("backend", BACKENDS)
def test_random_segments_match_shapely(
    backend: str, segs: np.ndarray, ox: float, oy: float, th: float, r_max: float
) -> None:
    assume_not_touching(segs, ox, oy)
    angles = beam_angles(37, math.pi) + th
    got = make_caster(backend, segs).cast((ox, oy), angles, r_max)
    want = shapely_ranges(segs, (ox, oy), angles, r_max)
    assert_same_ranges(got, want, r_max, segs, (ox, oy), angles)


@given(
    segs=segment_sets(),
    ox=coord,
    oy=coord,
    th=heading,
    cell=st.one_of(st.none(), st.floats(0.3, 30.0)),
    near_pass=st.sampled_from([0, 2, 20, NEAR_PASS_MIN_PIECES]),
)
@pytest.mark.parametrize("backend", BACKENDS)
def test_index_equals_brute_force_and_hits_lie_on_walls(
    backend: str,
    segs: np.ndarray,
    ox: float,
    oy: float,
    th: float,
    cell: float | None,
    near_pass: int,
) -> None:
    assume_not_touching(segs, ox, oy)
    r_max = 60.0
    caster = make_caster(
        backend,
        segs,
        cell_size_m=cell,
        near_pass_min_pieces=near_pass,
        near_pass_pieces=near_pass + 1,
    )
    angles = FAN + th
    got = caster.cast((ox, oy), angles, r_max)
    want = cast_brute_force(segs, (ox, oy), angles, r_max)
    assert_same_ranges(got, want, r_max, segs, (ox, oy), angles)
    hit = np.isfinite(got)
    assert np.all(got[hit] <= r_max * (1 + 1e-12))
    # A ray grazing a segment end meets the line at a float-precision angle: exempt.
    hit &= ~grazing(segs, (ox, oy), angles)
    r, a = got[hit], angles[hit]  # misses are inf: keep them out of the products
    pts = np.column_stack([ox + r * np.cos(a), oy + r * np.sin(a)])
    if len(pts):
        assert point_segment_distance(pts, segs).min(axis=1).max() < EXACT_M


@given(
    segs=segment_sets(),
    ox=coord,
    oy=coord,
    th=heading,
    move=st.tuples(coord, coord, heading),
)
@pytest.mark.parametrize("backend", BACKENDS)
def test_rigid_motion_of_world_and_laser_leaves_scan_unchanged(
    backend: str,
    segs: np.ndarray,
    ox: float,
    oy: float,
    th: float,
    move: tuple[float, float, float],
) -> None:
    assume_not_touching(segs, ox, oy)  # the contact decision may flip under rounding
    r_max = 40.0
    before = make_caster(backend, segs).cast((ox, oy), FAN + th, r_max)
    m = Pose(*move)
    moved_origin = m.transform_points(np.array([[ox, oy]]))[0]
    after = make_caster(backend, transform_segments(m.as_array(), segs)).cast(
        moved_origin, FAN + th + m.theta, r_max
    )
    ok = grazing(segs, (ox, oy), FAN + th)
    both = np.isfinite(before) & np.isfinite(after) & ~ok
    np.testing.assert_allclose(after[both], before[both], rtol=1e-9, atol=1e-9)
    differ = (np.isfinite(before) != np.isfinite(after)) & ~ok
    assert np.all(np.abs(np.where(np.isfinite(before), before, after)[differ] - r_max) < 1e-7)


@given(
    n=st.integers(3, 40),
    radii=st.lists(st.floats(0.5, 20.0), min_size=40, max_size=40),
    spin=heading,
    cell=st.one_of(st.none(), st.floats(0.2, 5.0)),
)
@example(n=4, radii=[1.0] * 40, spin=math.pi / 4, cell=None)
@pytest.mark.parametrize("backend", BACKENDS)
def test_closed_polygon_around_origin_leaks_no_ray(
    backend: str, n: int, radii: list[float], spin: float, cell: float | None
) -> None:
    """Rays aimed exactly at shared vertices (and everywhere else) always hit."""
    phi = spin + np.arange(n) * (2 * math.pi / n)
    pts = np.column_stack([np.cos(phi), np.sin(phi)]) * np.asarray(radii[:n])[:, None]
    segs = ring_segments(pts)
    caster = make_caster(backend, segs, cell_size_m=cell)
    at_vertices = np.arctan2(pts[:, 1], pts[:, 0])
    angles = np.concatenate([at_vertices, np.linspace(-math.pi, math.pi, 360, endpoint=False)])
    got = caster.cast((0.0, 0.0), angles, 100.0)
    assert np.isfinite(got).all()
    np.testing.assert_allclose(got[:n], np.asarray(radii[:n]), rtol=1e-12)


@pytest.mark.parametrize("backend", BACKENDS)
def test_ray_through_box_corners(backend: str) -> None:
    caster = make_caster(backend, box_segments(-1.0, -1.0, 1.0, 1.0))
    corners = np.array([1, 3, 5, 7]) * (math.pi / 4)
    np.testing.assert_allclose(caster.cast((0.0, 0.0), corners, 5.0), math.sqrt(2), rtol=1e-12)


@pytest.mark.parametrize("backend", BACKENDS)
def test_ray_parallel_to_wall_misses_it(backend: str) -> None:
    caster = make_caster(backend, [[0.0, 1.0, 5.0, 1.0]])
    assert caster.cast((0.0, 0.0), [0.0], 10.0)[0] == np.inf


@pytest.mark.parametrize("backend", BACKENDS)
def test_wall_seen_edge_on_is_hit_at_its_near_end(backend: str) -> None:
    caster = make_caster(backend, [[2.0, 0.0, 5.0, 0.0], [0.0, -3.0, 0.0, -7.0]])
    got = caster.cast((0.0, 0.0), [0.0, 1e-3, -math.pi / 2, math.pi], 10.0)
    np.testing.assert_allclose(got[[0, 2]], [2.0, 3.0], rtol=1e-12)
    assert np.isinf(got[[1, 3]]).all()


@pytest.mark.parametrize("origin", [(0.0, 0.0), (1.0, 0.0), (-0.3, 0.0), (0.5, 1e-12)])
@pytest.mark.parametrize("backend", BACKENDS)
def test_origin_on_a_wall_gives_zero_ranges(backend: str, origin: tuple[float, float]) -> None:
    caster = make_caster(backend, np.vstack([[[-1.0, 0.0, 1.0, 0.0]], box_segments(-5, -5, 5, 5)]))
    got = caster.cast(origin, FAN, 30.0)
    assert np.all(got == 0.0)


@pytest.mark.parametrize("backend", BACKENDS)
def test_zero_length_segments_are_ignored(backend: str) -> None:
    walls = box_segments(-3.0, -2.0, 4.0, 5.0)
    dots = np.array([[1.0, 0.0, 1.0, 0.0], [0.0, 1.0, 0.0, 1.0]])
    with_dots = make_caster(backend, np.vstack([walls, dots])).cast((0.0, 0.0), FAN, 30.0)
    np.testing.assert_array_equal(
        with_dots, make_caster(backend, walls).cast((0.0, 0.0), FAN, 30.0)
    )


@pytest.mark.parametrize("backend", BACKENDS)
def test_no_segments_and_out_of_range_give_inf(backend: str) -> None:
    assert np.isinf(make_caster(backend, np.zeros((0, 4))).cast((0.0, 0.0), FAN, 30.0)).all()
    far = make_caster(backend, box_segments(-50.0, -50.0, 50.0, 50.0))
    assert np.isinf(far.cast((0.0, 0.0), FAN, 30.0)).all()
    assert np.isfinite(far.cast((0.0, 0.0), FAN, 80.0)).all()


@pytest.mark.parametrize("backend", BACKENDS)
def test_extra_segments_are_seen_with_the_static_walls(backend: str) -> None:
    walls = box_segments(-10.0, -10.0, 10.0, 10.0)
    caster = make_caster(backend, walls)
    mover = box_segments(2.0, -0.5, 3.0, 0.5)
    alone = caster.cast((0.0, 0.0), FAN, 30.0)
    seen = caster.cast((0.0, 0.0), FAN, 30.0, extra_segments=mover)
    want = shapely_ranges(np.vstack([walls, mover]), (0.0, 0.0), FAN, 30.0)
    assert_same_ranges(seen, want, 30.0)
    assert seen[90] == pytest.approx(2.0) and alone[90] == pytest.approx(10.0)
    only_extra = make_caster(backend, np.zeros((0, 4))).cast(
        (0.0, 0.0), FAN, 30.0, extra_segments=mover
    )
    assert np.isfinite(only_extra).sum() > 0


@pytest.mark.parametrize("backend", BACKENDS)
def test_unsorted_angles_and_prepared_fans_agree(backend: str) -> None:
    segs = office_segments(4)
    caster = make_caster(backend, segs)
    rng = np.random.default_rng(3)
    angles = rng.uniform(-math.pi, math.pi, 200)
    got = caster.cast((6.0, 5.5), angles, 30.0)
    order = np.argsort(angles)
    np.testing.assert_array_equal(got[order], caster.cast((6.0, 5.5), angles[order], 30.0))
    fan = BeamFan.from_angles(FAN)
    np.testing.assert_allclose(
        caster.cast((6.0, 5.5), fan, 30.0, heading=0.7),
        caster.cast((6.0, 5.5), FAN + 0.7, 30.0),
        rtol=1e-12,
    )


@pytest.mark.parametrize("sigma_deg", [0.01, 0.3, 5.0])
@pytest.mark.parametrize("backend", BACKENDS)
def test_jittered_fan_equals_a_fan_built_from_the_turned_angles(
    backend: str, sigma_deg: float
) -> None:
    """Small jitter takes the cheap path, large jitter (beams out of order) a rebuild."""
    caster = make_caster(backend, office_segments(4))
    fan = BeamFan.from_angles(FAN)
    offsets = np.random.default_rng(1).normal(0.0, math.radians(sigma_deg), len(FAN))
    turned = fan.jittered(offsets)
    np.testing.assert_array_equal(turned.angles, FAN + offsets)
    want = caster.cast((6.0, 5.5), FAN + offsets + 0.4, 30.0)
    got = caster.cast((6.0, 5.5), turned, 30.0, heading=0.4)
    np.testing.assert_allclose(got, want, rtol=1e-12)


@pytest.mark.parametrize("near_pass", [0, NEAR_PASS_MIN_PIECES])
@pytest.mark.parametrize("backend", BACKENDS)
def test_office_grid_full_circle_matches_brute_force(backend: str, near_pass: int) -> None:
    segs = office_segments(6)
    caster = make_caster(
        backend, segs, near_pass_min_pieces=near_pass, near_pass_pieces=near_pass // 20 + 1
    )
    angles = np.linspace(-math.pi, math.pi, 720, endpoint=False)
    for o in [(2.0, 2.0), (13.1, 9.7), (4.0, 6.0), (23.5, 0.5)]:
        got = caster.cast(o, angles, 30.0)
        want = cast_brute_force(segs, o, angles, 30.0)
        assert_same_ranges(got, want, 30.0, segs, o, angles)


def test_near_pass_at_long_range_matches_single_pass() -> None:
    """In a dense world at 80 m the occlusion cut kicks in; it must not change a range."""
    segs = office_segments(30)
    cut = RayCaster(segs, backend="numpy")
    plain = RayCaster(segs, near_pass_min_pieces=10**9, backend="numpy")
    rng = np.random.default_rng(7)
    for _ in range(12):
        o = (float(rng.uniform(1, 119)), float(rng.uniform(1, 119)))
        angles = FAN + rng.uniform(-math.pi, math.pi)
        np.testing.assert_array_equal(cut.cast(o, angles, 80.0), plain.cast(o, angles, 80.0))
    box = (0.0, 0.0, 120.0, 120.0)
    assert cut.grid.count(*box) > NEAR_PASS_MIN_PIECES  # the cut really ran


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("turns", [-7, -1, 1, 3, 40])
def test_headings_and_angles_any_number_of_turns_away_give_the_same_scan(
    backend: str, turns: int
) -> None:
    """A fan is the same fan whichever multiple of 2 pi its angles or the heading carry."""
    caster = make_caster(backend, office_segments(4))
    fan = BeamFan.from_angles(FAN)
    want = caster.cast((6.0, 5.5), fan, 30.0, heading=0.4)
    assert np.isfinite(want).all()
    shift = 2.0 * math.pi * turns
    np.testing.assert_allclose(
        caster.cast((6.0, 5.5), fan, 30.0, heading=0.4 + shift), want, rtol=1e-9
    )
    np.testing.assert_allclose(caster.cast((6.0, 5.5), FAN + 0.4 + shift, 30.0), want, rtol=1e-9)


@pytest.mark.parametrize("backend", BACKENDS)
def test_contact_is_checked_all_around_the_origin(backend: str) -> None:
    """A wall within the contact tolerance behind a forward-looking laser still touches it."""
    # Clutter further behind keeps the index from handing out whole rows of pieces.
    clutter = [[x, -0.9, x, 0.9] for x in np.linspace(-0.9, -0.3, 30)]
    walls = [[-0.08, -0.5, -0.08, 0.5], *clutter, *box_segments(-1.0, -1.0, 1.0, 1.0)]
    caster = make_caster(backend, walls, contact_tolerance_m=0.1, cell_size_m=0.05)
    assert caster.cell_size_m < 0.08  # the wall is in a cell the fan's own box misses
    assert np.all(caster.cast((0.0, 0.0), FAN, 30.0) == 0.0)
    assert np.all(caster.cast((0.2, 0.0), FAN, 30.0) > 0.0)


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"segments": [[0, 0, np.nan, 1]]}, "segments[0]"),
        ({"segments": [[0, 0, 1]]}, "segments"),
        ({"segments": [[0, 0, 1, 1]], "cell_size_m": 0.0}, "cell_size_m"),
        ({"segments": [[0, 0, 1, 1]], "contact_tolerance_m": -1.0}, "contact_tolerance_m"),
        ({"segments": [[0, 0, 1, 1]], "near_pass_min_pieces": 1.5}, "near_pass_min_pieces"),
        ({"segments": [[0, 0, 1, 1]], "near_pass_pieces": 0}, "near_pass_pieces"),
        ({"segments": [[0, 0, 1, 1]], "backend": "cuda"}, "backend"),
    ],
)
def test_bad_construction_names_the_input(kwargs: dict, field: str) -> None:
    with pytest.raises(InputError, match=field.replace("[", r"\[")):
        RayCaster(**kwargs)


def test_bad_cast_arguments_name_the_input() -> None:
    caster = RayCaster(box_segments(0, 0, 1, 1))
    with pytest.raises(InputError, match="max_range"):
        caster.cast((0.5, 0.5), FAN, 0.0)
    with pytest.raises(InputError, match="origin"):
        caster.cast((0.5, np.nan), FAN, 5.0)
    with pytest.raises(InputError, match="origin"):
        caster.cast((0.5,), FAN, 5.0)
    with pytest.raises(InputError, match="angles"):
        caster.cast((0.5, 0.5), [], 5.0)
    with pytest.raises(InputError, match=r"extra_segments\[1\]"):
        caster.cast((0.5, 0.5), FAN, 5.0, extra_segments=[[0, 0, 1, 1], [0, np.inf, 1, 1]])


def _same_surface_brute_force(segs: np.ndarray, p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Every point against every segment; corners by exact coordinates."""
    through_p = point_segment_distance(p, segs) <= 1e-6
    through_q = point_segment_distance(q, segs) <= 1e-6
    ends = [segs[:, :2], segs[:, 2:]]
    out = []
    for k in range(len(p)):
        a, b = np.flatnonzero(through_p[k]), np.flatnonzero(through_q[k])
        corners_a = {tuple(e[i]) for e in ends for i in a}
        corners_b = {tuple(e[i]) for e in ends for i in b}
        out.append(bool(corners_a & corners_b))
    return np.array(out, dtype=bool)


@given(
    seed=st.integers(0, 2**32 - 1),
    cell=st.one_of(st.none(), st.floats(0.3, 8.0)),
    spread=st.floats(0.0, 0.6),
)
@pytest.mark.parametrize("backend", BACKENDS)
def test_same_surface_equals_brute_force_on_an_office(
    backend: str, seed: int, cell: float | None, spread: float
) -> None:
    """Points on walls (often at corners, on wall pieces cut at grid lines, or off every
    wall) are on one surface exactly when a segment through each shares a corner."""
    segs = office_segments(4)
    caster = make_caster(backend, segs, cell_size_m=cell)
    rng = np.random.default_rng(seed)
    n = 40
    k = rng.integers(0, len(segs), n)
    t = rng.choice([0.0, 1.0, 0.5, rng.random()], n)
    p = segs[k, :2] + t[:, None] * (segs[k, 2:] - segs[k, :2])
    # q: along the same wall, onto a neighbour through a corner, or anywhere on the walls.
    k2 = np.where(rng.random(n) < 0.5, k, rng.integers(0, len(segs), n))
    t2 = np.clip(t + rng.normal(0.0, spread, n), 0.0, 1.0)
    q = segs[k2, :2] + t2[:, None] * (segs[k2, 2:] - segs[k2, :2])
    q[::7] += 0.01  # off every wall
    got = caster.same_surface(p, q)
    np.testing.assert_array_equal(got, _same_surface_brute_force(segs, p, q))
    np.testing.assert_array_equal(caster.same_surface(p, p), _same_surface_brute_force(segs, p, p))


@pytest.mark.parametrize("backend", BACKENDS)
def test_same_surface_with_extra_segments(backend: str) -> None:
    room = box_segments(0.0, 0.0, 10.0, 8.0)
    box = box_segments(4.0, 4.0, 5.0, 5.0)
    caster = make_caster(backend, room)
    p = np.array([[4.5, 4.0], [4.0, 4.5], [4.5, 4.0], [2.0, 0.0], [10.0, 3.0]])
    q = np.array([[5.0, 4.5], [4.0, 4.9], [2.0, 0.0], [10.0, 1.0], [10.0, 8.0]])
    want = [True, True, False, True, True]  # box corner, box side, box→wall, wall corner ×2
    np.testing.assert_array_equal(caster.same_surface(p, q, extra_segments=box), want)
    # Without the box its points lie on nothing.
    np.testing.assert_array_equal(caster.same_surface(p, q), [False, False, False, True, True])
    assert list(caster.segments_through(p[:1], extra_segments=box)[1]) == [4]
    with pytest.raises(InputError, match="as many points"):
        caster.same_surface(p, q[:2])


@given(seed=st.integers(0, 2**32 - 1), jump=st.sampled_from([0.0, 0.05, 0.2, 1.0]))
def test_depth_edges_are_the_same_on_both_backends_and_follow_same_surface(
    seed: int, jump: float
) -> None:
    """On scans of an office with a moving box, both backends mark the same beam pairs,
    and those are exactly the pairs that jump by more than ``jump`` with hits on two
    surfaces by brute force."""
    segs = office_segments(4)
    box = box_segments(5.0, 5.0, 5.6, 5.4)
    rng = np.random.default_rng(seed)
    origin = (float(rng.uniform(0.3, 15.7)), float(rng.uniform(0.3, 15.7)))
    angles = FAN + float(rng.uniform(-math.pi, math.pi))
    casters = [
        make_caster(b, segs) for b in ("numpy", "numba") if b == "numpy" or numba_available()
    ]
    r = casters[0].cast(origin, angles, 30.0, extra_segments=box)
    hit = np.isfinite(r)
    r = np.minimum(r, 30.0)
    got = [c.depth_edges(origin, angles, r, hit, jump, extra_segments=box) for c in casters]
    for g in got[1:]:
        np.testing.assert_array_equal(g, got[0])
    xy = np.column_stack([origin[0] + r * np.cos(angles), origin[1] + r * np.sin(angles)])
    both = np.vstack([segs, box])
    one = _same_surface_brute_force(both, xy[:-1], xy[1:])
    want = hit[1:] & hit[:-1] & (np.abs(np.diff(r)) > jump) & ~one
    np.testing.assert_array_equal(got[0], want)
