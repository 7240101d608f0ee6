"""Line extraction: surfaces, endpoints and occlusion flags on scans of exactly known geometry."""

from __future__ import annotations

import functools
import math
from collections.abc import Callable

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from albot2d.errors import InputError
from albot2d.frames import Scan
from albot2d.geometry import Pose, point_segment_distance
from albot2d.perception import ExtractionParams, Surfaces, extract_surfaces
from albot2d.perception.extraction import numba_available
from tests.perception_helpers import box, scan_of

WALL_TOL_M = 0.003  # noise-free endpoints lie on their wall to within a few mm


def on_wall(surfaces: Surfaces, wall: np.ndarray, tol: float = WALL_TOL_M) -> np.ndarray:
    """Indices of the surfaces whose both endpoints lie on ``wall`` (given in the view frame)."""
    d = point_segment_distance(surfaces.segments.reshape(-1, 2), np.asarray(wall)[None, :])
    return np.flatnonzero(d.reshape(-1, 2).max(axis=1) <= tol)


def endpoint_spacing(r: float, n_beams: int = 361, fov: float = math.pi) -> float:
    """How far apart consecutive beams land at range ``r`` on a facing wall."""
    return r * fov / (n_beams - 1)


# Every scene runs on the numpy reference and on the compiled kernel (no environment
# variable needed): both must pass the same hand-worked checks.
BACKENDS = ["numpy", pytest.param("numba", marks=pytest.mark.skipif(
    not numba_available(), reason="numba not installed"))]  # fmt: skip


@pytest.fixture(scope="module", params=BACKENDS)
def extract(request: pytest.FixtureRequest) -> Callable[..., Surfaces]:
    """``extract_surfaces`` on one backend."""
    return functools.partial(extract_surfaces, backend=request.param)


# --- parameters -----------------------------------------------------------------------


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("breakpoint_lambda_deg", 0.0),
        ("breakpoint_lambda_deg", 95.0),
        ("range_sigma_m", -0.01),
        ("split_distance_m", 0.0),
        ("merge_distance_m", float("nan")),
        ("min_points", 1),
        ("min_points", 5.0),
        ("max_range_m", 0.0),
        ("continuation_distance_m", -1.0),
    ],
)
def test_bad_params_name_field_and_value(field: str, value: float) -> None:
    with pytest.raises(InputError, match=rf"{field}.*{value!r}"):
        ExtractionParams(**{field: value})


def test_lambda_not_wider_than_beam_spacing_is_rejected(extract: Callable[..., Surfaces]) -> None:
    scan = scan_of(np.array([[3.0, -5.0, 3.0, 5.0]]), n_beams=19)  # 10° spacing
    with pytest.raises(InputError, match="breakpoint_lambda_deg"):
        extract(scan)


# --- hand-built geometry ----------------------------------------------------------------


def test_single_wall_across_the_field_of_view(extract: Callable[..., Surfaces]) -> None:
    wall = np.array([3.0, -10.0, 3.0, 10.0])
    surfaces = extract(scan_of(wall[None, :], n_beams=181, fov_rad=math.pi / 2))
    assert len(surfaces) == 1
    s = surfaces.segments[0]
    # The ±45° edge beams hit the wall at y = ∓3; endpoint 0 comes from beam 0 (the right).
    np.testing.assert_allclose(s, [3.0, -3.0, 3.0, 3.0], atol=WALL_TOL_M)
    assert surfaces.occluded.tolist() == [[True, True]]  # both at the field-of-view edges
    assert surfaces.beams.tolist() == [[0, 180]]


def test_wall_endpoints_use_the_laser_mount(extract: Callable[..., Surfaces]) -> None:
    mount = Pose(0.25, -0.1, 0.2)
    wall = np.array([2.5, -1.5, 2.0, 2.0])
    surfaces = extract(scan_of(wall[None, :], laser_pose=mount))
    assert len(surfaces) == 1
    assert len(on_wall(surfaces, wall)) == 1
    # Both wall ends are seen: the surface spans them to within one beam spacing.
    ends = surfaces.segments[0].reshape(2, 2)
    np.testing.assert_allclose(ends[0], wall[:2], atol=0.03)
    np.testing.assert_allclose(ends[1], wall[2:], atol=0.03)
    assert surfaces.occluded.tolist() == [[True, True]]  # no return beyond either end


def test_concave_corner_gives_two_surfaces_sharing_an_unoccluded_corner(
    extract: Callable[..., Surfaces],
) -> None:
    walls = np.array([[3.0, -5.0, 3.0, 3.0], [3.0, 3.0, -2.0, 3.0]])
    surfaces = extract(scan_of(walls))
    assert len(surfaces) == 2
    assert on_wall(surfaces, walls[0]).tolist() == [0]
    assert on_wall(surfaces, walls[1]).tolist() == [1]
    corner = np.array([3.0, 3.0])
    tol = endpoint_spacing(math.hypot(3.0, 3.0))
    assert np.hypot(*(surfaces.segments[0, 2:] - corner)) < tol
    assert np.hypot(*(surfaces.segments[1, :2] - corner)) < tol
    assert surfaces.occluded.tolist() == [[True, False], [False, True]]
    assert surfaces.beams[0, 1] == surfaces.beams[1, 0]  # the corner beam is shared
    assert surfaces.beams[1, 1] == 360


def test_box_in_front_of_a_wall(extract: Callable[..., Surfaces]) -> None:
    wall = np.array([4.0, -6.0, 4.0, 6.0])
    obstacle = box(2.0, -1.0, 0.3, 0.3)  # shows its front (x=1.7) and top (y=-0.7) faces
    surfaces = extract(scan_of(np.vstack([wall[None, :], obstacle])))
    wall_parts = on_wall(surfaces, wall)
    front = on_wall(surfaces, obstacle[3])
    top = on_wall(surfaces, obstacle[2])
    assert len(wall_parts) == 2 and len(front) == 1 and len(top) == 1
    assert len(surfaces) == 4
    right_part, left_part = wall_parts
    # Scan order: right wall part, box front, box top, left wall part.
    assert [right_part, front[0], top[0], left_part] == [0, 1, 2, 3]
    # The wall's ends at the box's shadow are occluded; its far ends meet no return.
    assert surfaces.occluded[right_part].tolist() == [True, True]
    assert surfaces.occluded[left_part].tolist() == [True, True]
    # The box's ends are real: its outer edges stand in front of the wall, and the
    # convex corner between its faces is inside a continuous run.
    assert surfaces.occluded[front[0]].tolist() == [False, False]
    assert surfaces.occluded[top[0]].tolist() == [False, False]
    corner = np.array([1.7, -0.7])
    assert np.hypot(*(surfaces.segments[front[0], 2:] - corner)) < 0.02
    assert np.hypot(*(surfaces.segments[top[0], :2] - corner)) < 0.02


def test_no_return_beams_break_a_wall_and_occlude_its_ends(
    extract: Callable[..., Surfaces],
) -> None:
    wall = np.array([[3.0, -3.0, 3.0, 3.0]])
    scan = scan_of(wall, n_beams=181, fov_rad=math.pi / 2)
    valid = scan.valid.copy()
    valid[85:95] = False
    gap_scan = Scan(scan.ranges, scan.angles, valid, scan.max_range_m)
    surfaces = extract(gap_scan)
    assert len(surfaces) == 2
    assert surfaces.beams.tolist() == [[0, 84], [95, 180]]
    assert surfaces.occluded.tolist() == [[True, True], [True, True]]
    assert len(on_wall(surfaces, wall[0])) == 2


def test_max_range_param_counts_far_readings_as_no_return(extract: Callable[..., Surfaces]) -> None:
    walls = np.array([[3.0, -3.0, 3.0, 0.0], [6.0, 0.0, 6.0, 3.0]])
    scan = scan_of(walls, n_beams=181, fov_rad=math.pi / 2)
    assert len(extract(scan)) == 2
    near_only = extract(scan, ExtractionParams(max_range_m=5.0))
    assert len(near_only) == 1
    assert near_only.occluded.tolist() == [[True, True]]


def test_grazing_end_is_occluded_only_with_the_continuation_check(
    extract: Callable[..., Surfaces],
) -> None:
    # Far down a corridor wall the beams thin out and a breakpoint cuts the wall: the
    # next reading is farther, yet it continues the same line, so the end is not a corner.
    wall = np.array([[-1.0, -1.0, 30.0, -1.0]])
    scan = scan_of(wall, n_beams=181, fov_rad=math.pi / 2)
    with_check = extract(scan)
    without = extract(scan, ExtractionParams(continuation_distance_m=0.0))
    assert with_check.segments[0, 2] < 10.0  # the wall is cut well before its far end
    assert with_check.occluded[0].tolist() == [True, True]
    assert without.occluded[0].tolist() == [True, False]


def test_tiny_runs_give_no_surfaces(extract: Callable[..., Surfaces]) -> None:
    post = box(3.0, 0.0, 0.02, 0.02)  # a few beams only
    assert len(extract(scan_of(post))) == 0
    empty = Scan(np.full(181, 30.0), np.linspace(-1, 1, 181), np.zeros(181, bool), 30.0)
    assert len(extract(empty)) == 0


# --- noise and invariants -----------------------------------------------------------


@given(
    distance=st.floats(1.0, 4.0),
    heading=st.floats(-0.4, 0.4),
    seed=st.integers(0, 2**32 - 1),
)
def test_noisy_long_wall_is_not_split(
    extract: Callable[..., Surfaces], distance: float, heading: float, seed: int
) -> None:
    wall = np.array([[distance, -distance, distance, distance]])
    scan = scan_of(wall, Pose(0.0, 0.0, heading), noise_sigma=0.01, rng=np.random.default_rng(seed))
    surfaces = extract(scan)
    assert len(surfaces) == 1
    # The fitted line lies on the wall to within the noise.
    ends = surfaces.segments.reshape(2, 2)
    view_wall = Pose(0.0, 0.0, heading).inverse().transform_points(wall.reshape(2, 2))
    d = point_segment_distance(ends, view_wall.reshape(1, 4))
    assert d.max() < 0.05


@st.composite
def cluttered_scenes(draw: st.DrawFn) -> tuple[np.ndarray, Pose]:
    walls = [box(0.0, 0.0, draw(st.floats(3.0, 8.0)), draw(st.floats(3.0, 8.0)))]
    for _ in range(draw(st.integers(0, 5))):
        walls.append(
            box(
                draw(st.floats(-2.5, 2.5)),
                draw(st.floats(-2.5, 2.5)),
                draw(st.floats(0.05, 0.6)),
                draw(st.floats(0.05, 0.6)),
            )
        )
    return np.vstack(walls), Pose(0.0, 0.0, draw(st.floats(-math.pi, math.pi)))


@given(cluttered_scenes(), st.sampled_from([181, 361]), st.integers(0, 2**32 - 1))
def test_extraction_invariants(
    extract: Callable[..., Surfaces], scene: tuple[np.ndarray, Pose], n_beams: int, seed: int
) -> None:
    world, pose = scene
    params = ExtractionParams()
    scan = scan_of(world, pose, n_beams=n_beams, noise_sigma=0.005, rng=np.random.default_rng(seed))
    surfaces = extract(scan, params)
    a, b = surfaces.beams[:, 0], surfaces.beams[:, 1]
    assert np.all(b - a + 1 >= params.min_points)
    assert np.all(a[1:] >= b[:-1])  # scan order; neighbours share at most a split beam
    pts = scan.points(valid_only=False)
    for i in range(len(surfaces)):
        assert scan.valid[a[i] : b[i] + 1].all()
        support = pts[a[i] : b[i] + 1]
        seg = surfaces.segments[i]
        # Every supporting point fits the line; the endpoints are the end points projected.
        rel, along = support - seg[:2], seg[2:] - seg[:2]
        line_d = np.abs(rel[:, 0] * along[1] - rel[:, 1] * along[0]) / surfaces.lengths_m[i]
        assert line_d.max() <= max(params.split_distance_m, params.merge_distance_m) + 1e-9
        # ... except a corner shared with the neighbour, placed at the lines' intersection.
        corner_0 = i > 0 and np.array_equal(seg[:2], surfaces.segments[i - 1, 2:])
        corner_1 = i + 1 < len(surfaces) and np.array_equal(seg[2:], surfaces.segments[i + 1, :2])
        if not corner_0:
            assert np.hypot(*(seg[:2] - support[0])) <= params.split_distance_m + 1e-9
        if not corner_1:
            assert np.hypot(*(seg[2:] - support[-1])) <= params.split_distance_m + 1e-9
    # The first and last beams of the scan are always occluded ends.
    assert np.all(surfaces.occluded[a == 0, 0])
    assert np.all(surfaces.occluded[b == n_beams - 1, 1])
    again = extract(scan, params)
    np.testing.assert_array_equal(again.segments, surfaces.segments)


@given(cluttered_scenes())
def test_mirrored_scan_gives_mirrored_surfaces(scene: tuple[np.ndarray, Pose]) -> None:
    # Mirroring the world in the x axis reverses the scan: same surfaces, reversed order,
    # endpoints and occlusion flags swapped. Catches any left/right bias. (Default
    # backend only: a scene symmetric about the x axis itself can break the symmetry at
    # exact ties, on both backends; tests/test_oracles_extraction.py pins that case.)
    world, pose = scene
    scan = scan_of(world, pose, n_beams=181)
    mirror = Scan(scan.ranges[::-1], -scan.angles[::-1], scan.valid[::-1], scan.max_range_m)
    s, m = extract_surfaces(scan), extract_surfaces(mirror)
    assert len(s) == len(m)
    expected = m.segments[::-1][:, [2, 3, 0, 1]] * np.array([1.0, -1.0, 1.0, -1.0])
    np.testing.assert_allclose(s.segments, expected, atol=1e-9)
    np.testing.assert_array_equal(s.occluded, m.occluded[::-1, ::-1])
    np.testing.assert_array_equal(s.beams, 180 - m.beams[::-1, ::-1])
