"""The plain geometry the laser-hit check (``checks.simulator.FrameChecker``) measures with,
independently of the simulator's ray caster: ``SegmentGrid`` (which points lie within a
distance of any segment) and ``ray_ranges`` (the exact range along rays to the nearest
segment). Each has a numpy path and, with numba, a compiled kernel
(``albot2d.evaluation.checks.simulator_numba``) doing the same float operations."""

from __future__ import annotations

import functools
import math
from types import ModuleType

import numpy as np
from numpy.typing import NDArray

from albot2d.compiled import compiled_module

__all__ = ["SegmentGrid", "ray_ranges"]

FloatArray = NDArray[np.float64]


class SegmentGrid:
    """Segments bucketed on a square grid, to ask which points lie within a distance
    (at most ``reach_m``) of any of them: each cell lists every segment that comes within
    ``reach_m`` plus half the cell's diagonal of its centre, so a point's own cell lists
    every segment within ``reach_m`` of the point. Cells are ``cell_m`` wide (half a metre:
    three times faster than a metre on the fuzzing worlds, finer gains little), wider when
    the grid would have more than ``max_cells``."""

    def __init__(
        self, segments: FloatArray, reach_m: float, cell_m: float = 0.5, max_cells: int = 10**6
    ) -> None:
        self.segments = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
        self.reach_m = float(reach_m)
        s = self.segments
        lo = np.minimum(s[:, :2], s[:, 2:]) - self.reach_m
        hi = np.maximum(s[:, :2], s[:, 2:]) + self.reach_m
        extent = hi.max(axis=0) - lo.min(axis=0)
        self.cell_m = max(float(cell_m), math.sqrt(float(extent[0] * extent[1]) / max_cells))
        self.origin = lo.min(axis=0)
        self.shape = (np.floor((hi.max(axis=0) - self.origin) / self.cell_m) + 1).astype(np.int64)
        c0 = np.floor((lo - self.origin) / self.cell_m).astype(np.int64)
        c1 = np.floor((hi - self.origin) / self.cell_m).astype(np.int64)
        span = c1 - c0 + 1
        count = span[:, 0] * span[:, 1]  # the cells of each segment's enlarged bounding box
        seg = np.repeat(np.arange(len(s)), count)
        j = np.arange(len(seg)) - np.repeat(np.cumsum(count) - count, count)
        cx = c0[seg, 0] + j % span[seg, 0]
        cy = c0[seg, 1] + j // span[seg, 0]
        centres = self.origin + (np.column_stack([cx, cy]) + 0.5) * self.cell_m
        near = _pair_distance(centres, s[seg]) <= self.reach_m + 0.5 * math.sqrt(2) * self.cell_m
        cell = cx[near] * self.shape[1] + cy[near]
        order = np.argsort(cell, kind="stable")
        self._segment_of = seg[near][order]
        self._start = np.searchsorted(cell[order], np.arange(self.shape[0] * self.shape[1] + 1))

    def within(
        self, points: FloatArray, distance_m: FloatArray, backend: str = "auto"
    ) -> NDArray[np.bool_]:
        """``(P,)``: each point lies within its ``distance_m`` (≤ ``reach_m``) of a segment
        (``backend``: "numpy", or "auto": the compiled kernel when numba imports)."""
        pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        if np.any(distance_m > self.reach_m):
            raise ValueError(f"distances beyond the grid's reach {self.reach_m} m")
        kernels = _kernels() if backend != "numpy" else None
        if kernels is not None:
            return kernels.within_kernel(
                np.ascontiguousarray(pts), np.broadcast_to(distance_m, len(pts)).astype(float),
                float(self.origin[0]), float(self.origin[1]), self.cell_m, int(self.shape[0]),
                int(self.shape[1]), self._start, self._segment_of, self.segments,
            )  # fmt: skip
        c = np.floor((pts - self.origin) / self.cell_m).astype(np.int64)
        inside = np.all((c >= 0) & (c < self.shape), axis=1)  # outside: beyond reach
        cell = np.where(inside, c[:, 0] * self.shape[1] + c[:, 1], 0)
        first = np.where(inside, self._start[cell], 0)
        count = np.where(inside, self._start[cell + 1] - first, 0)
        point = np.repeat(np.arange(len(pts)), count)
        seg = self._segment_of[np.repeat(first, count) + np.arange(len(point))
                               - np.repeat(np.cumsum(count) - count, count)]  # fmt: skip
        close = _pair_distance(pts[point], self.segments[seg]) <= np.asarray(distance_m)[point]
        return np.bincount(point[close], minlength=len(pts)) > 0


@functools.cache
def _kernels() -> ModuleType | None:
    """The compiled grid query (``sim_invariants_numba``) on first use; None without numba."""
    return compiled_module("albot2d.evaluation.checks.simulator_numba")


def _pair_distance(points: FloatArray, segments: FloatArray) -> FloatArray:
    """Distance from each point ``(K, 2)`` to its segment ``(K, 4)`` (a zero-length segment
    is its point)."""
    a, d = segments[:, :2], segments[:, 2:] - segments[:, :2]
    w = points - a
    length2 = np.einsum("ij,ij->i", d, d)
    t = np.clip(np.einsum("ij,ij->i", w, d) / np.where(length2 > 0.0, length2, 1.0), 0.0, 1.0)
    return np.hypot(w[:, 0] - t * d[:, 0], w[:, 1] - t * d[:, 1])


# Rays intersected with the segments per chunk (bounds the (rays, segments) work arrays).
_RAY_CHUNK = 256


def ray_ranges(
    origins: FloatArray, angles: FloatArray, segments: FloatArray, backend: str = "auto"
) -> FloatArray:
    """Exact distance along each ray (``origins (M, 2)``, world ``angles (M, K)``, NaN: no
    ray) to the nearest of ``segments``; inf where a ray hits nothing (``backend``:
    "numpy", or "auto": the compiled kernel when numba imports)."""
    out = np.full(angles.shape, np.inf)
    if len(segments) == 0 or len(origins) == 0:
        return out
    kernels = _kernels() if backend != "numpy" else None
    if kernels is not None:
        return kernels.ray_ranges_kernel(
            np.ascontiguousarray(origins, dtype=np.float64),
            np.ascontiguousarray(angles, dtype=np.float64),
            np.ascontiguousarray(segments, dtype=np.float64),
        )
    p, e = segments[:, :2], segments[:, 2:] - segments[:, :2]
    for lo in range(0, len(origins), _RAY_CHUNK):
        o = origins[lo : lo + _RAY_CHUNK, None, None, :]
        a = angles[lo : lo + _RAY_CHUNK, :, None]
        dx, dy = np.cos(a), np.sin(a)
        wx, wy = p[:, 0] - o[..., 0], p[:, 1] - o[..., 1]
        with np.errstate(divide="ignore", invalid="ignore"):
            denom = dx * e[:, 1] - dy * e[:, 0]
            t = (wx * e[:, 1] - wy * e[:, 0]) / denom
            u = (wx * dy - wy * dx) / denom
            hit = (denom != 0.0) & (t >= 0.0) & (u >= 0.0) & (u <= 1.0)
        out[lo : lo + _RAY_CHUNK] = np.where(hit, t, np.inf).min(axis=-1)
    return out
