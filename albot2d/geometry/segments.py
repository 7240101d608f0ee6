"""Vectorised math on line segments stored as ``(N, 4)`` arrays of ``[x1, y1, x2, y2]``.

Every function takes and returns numpy arrays; shape in = shape out along the
leading axis. Nothing here loops in Python over segments.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from albot2d.geometry.pose import transform_points

__all__ = [
    "as_segments",
    "point_segment_distance",
    "polygon_ring_segments",
    "segment_angles",
    "segment_lengths",
    "segment_midpoints",
    "transform_segments",
    "undirected_angle_difference",
]

FloatArray = NDArray[np.float64]


def as_segments(segments: ArrayLike) -> FloatArray:
    """Return ``segments`` as a float64 ``(N, 4)`` array (an empty input gives ``(0, 4)``)."""
    arr = np.asarray(segments, dtype=np.float64)
    if arr.size == 0:
        return np.zeros((0, 4), dtype=np.float64)
    if arr.ndim != 2 or arr.shape[1] != 4:
        raise ValueError(f"segments need shape (N, 4) [x1, y1, x2, y2], got {arr.shape}")
    return arr


def segment_lengths(segments: ArrayLike) -> FloatArray:
    s = as_segments(segments)
    return np.hypot(s[:, 2] - s[:, 0], s[:, 3] - s[:, 1])


def segment_angles(segments: ArrayLike) -> FloatArray:
    """Directed angle (radians) from the first to the second endpoint of each segment."""
    s = as_segments(segments)
    return np.arctan2(s[:, 3] - s[:, 1], s[:, 2] - s[:, 0])


def segment_midpoints(segments: ArrayLike) -> FloatArray:
    s = as_segments(segments)
    return 0.5 * (s[:, :2] + s[:, 2:])


def undirected_angle_difference(a: ArrayLike, b: ArrayLike) -> FloatArray:
    """Smallest angle between two undirected lines of directions ``a`` and ``b``, in [0, pi/2]."""
    d = np.abs(np.asarray(a, dtype=np.float64) - np.asarray(b, dtype=np.float64)) % np.pi
    return np.minimum(d, np.pi - d)


def transform_segments(pose: ArrayLike, segments: ArrayLike) -> FloatArray:
    """Map segments from the frame of ``pose`` (``[x, y, theta]``) into its parent frame."""
    s = as_segments(segments)
    pts = transform_points(pose, s.reshape(-1, 2))
    return pts.reshape(-1, 4)


def point_segment_distance(points: ArrayLike, segments: ArrayLike) -> FloatArray:
    """Pairwise distances, shape ``(P, S)``, from ``(P, 2)`` points to ``(S, 4)`` segments."""
    p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    s = as_segments(segments)
    a = s[None, :, :2]
    d = s[None, :, 2:] - a
    rel = p[:, None, :] - a
    len2 = np.einsum("...k,...k->...", d, d)
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.where(len2 > 0.0, np.einsum("...k,...k->...", rel, d) / len2, 0.0)
    t = np.clip(t, 0.0, 1.0)
    closest = a + t[..., None] * d
    return np.hypot(p[:, None, 0] - closest[..., 0], p[:, None, 1] - closest[..., 1])


def polygon_ring_segments(coords: ArrayLike) -> FloatArray:
    """Edges of a closed ring as segments; a repeated closing vertex is accepted and dropped."""
    c = np.asarray(coords, dtype=np.float64).reshape(-1, 2)
    if len(c) > 1 and np.array_equal(c[0], c[-1]):
        c = c[:-1]
    if len(c) < 2:
        return np.zeros((0, 4), dtype=np.float64)
    nxt = np.roll(c, -1, axis=0)
    return np.hstack([c, nxt])
