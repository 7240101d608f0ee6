"""SE(2) pose algebra and segment math."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import example, given
from hypothesis import strategies as st

from albot2d.geometry import (
    Pose,
    between_arrays,
    compose_arrays,
    invert_arrays,
    point_segment_distance,
    polygon_ring_segments,
    segment_angles,
    segment_lengths,
    transform_segments,
    undirected_angle_difference,
    wrap_angle,
)
from tests.strategies import poses, segment_arrays


def close(a: Pose, b: Pose, tol: float = 1e-6) -> bool:
    return (
        abs(a.x - b.x) < tol
        and abs(a.y - b.y) < tol
        and abs(float(wrap_angle(a.theta - b.theta))) < tol
    )


def test_compose_known_values() -> None:
    a = Pose(1.0, 2.0, math.pi / 2)
    b = Pose(1.0, 0.0, 0.0)
    assert close(a @ b, Pose(1.0, 3.0, math.pi / 2))


@given(poses())
def test_inverse_is_identity(p: Pose) -> None:
    assert close(p @ p.inverse(), Pose(), tol=1e-6)
    assert close(p.inverse() @ p, Pose(), tol=1e-6)


@given(poses(), poses(), poses())
def test_compose_is_associative(a: Pose, b: Pose, c: Pose) -> None:
    assert close((a @ b) @ c, a @ (b @ c), tol=1e-6)


@given(poses(), poses())
def test_between_recovers_relative(a: Pose, b: Pose) -> None:
    assert close(a @ a.between(b), b, tol=1e-6)


@given(st.lists(poses(), min_size=1, max_size=10), st.lists(poses(), min_size=1, max_size=10))
def test_array_versions_match_scalar(a: list[Pose], b: list[Pose]) -> None:
    n = min(len(a), len(b))
    A = np.array([p.as_array() for p in a[:n]])
    B = np.array([p.as_array() for p in b[:n]])
    C = compose_arrays(A, B)
    D = between_arrays(A, B)
    Inv = invert_arrays(A)
    assert C.shape == A.shape == D.shape == Inv.shape
    for k in range(n):
        assert close(Pose.from_array(C[k]), a[k] @ b[k])
        assert close(Pose.from_array(D[k]), a[k].between(b[k]))
        assert close(Pose.from_array(Inv[k]), a[k].inverse())


@given(st.floats(-1e4, 1e4))
@example(math.pi)
@example(-math.pi)
def test_wrap_angle_range(a: float) -> None:
    w = wrap_angle(a)
    assert -math.pi <= w < math.pi
    assert math.isclose(math.cos(w), math.cos(a), abs_tol=1e-9)
    assert math.isclose(math.sin(w), math.sin(a), abs_tol=1e-9)


@given(segment_arrays(), poses())
def test_transform_segments_preserves_lengths_and_shape(segs: np.ndarray, p: Pose) -> None:
    out = transform_segments(p.as_array(), segs)
    assert out.shape == segs.shape
    np.testing.assert_allclose(segment_lengths(out), segment_lengths(segs), atol=1e-6)


def test_segment_angles_and_difference() -> None:
    segs = np.array([[0, 0, 1, 0], [0, 0, 0, 1], [1, 1, 0, 1]], dtype=float)
    np.testing.assert_allclose(segment_angles(segs), [0.0, math.pi / 2, math.pi])
    d = undirected_angle_difference(segment_angles(segs)[0], segment_angles(segs)[2])
    assert d == pytest.approx(0.0)
    assert undirected_angle_difference(0.0, math.pi / 2) == pytest.approx(math.pi / 2)


def test_point_segment_distance_known() -> None:
    segs = np.array([[0, 0, 2, 0], [0, 0, 0, 0]], dtype=float)
    pts = np.array([[1, 1], [3, 0], [-1, -1]], dtype=float)
    d = point_segment_distance(pts, segs)
    assert d.shape == (3, 2)
    np.testing.assert_allclose(d[:, 0], [1.0, 1.0, math.sqrt(2)])
    np.testing.assert_allclose(d[:, 1], [math.sqrt(2), 3.0, math.sqrt(2)])


def test_polygon_ring_segments_closes_ring() -> None:
    ring = [(0, 0), (1, 0), (1, 1), (0, 0)]
    segs = polygon_ring_segments(ring)
    assert segs.shape == (3, 4)
    np.testing.assert_allclose(segs[-1], [1, 1, 0, 0])


def test_bad_shapes_raise_clear_errors() -> None:
    with pytest.raises(ValueError, match=r"\(N, 4\)"):
        segment_lengths(np.zeros((3, 3)))
    with pytest.raises(ValueError, match="3 numbers"):
        Pose.from_array([1, 2])
