"""Exact, vectorised 2D raycasting against line segments: ``RayCaster``.

``RayCaster(segments)`` is built once per world: a uniform-grid index of the segments cut
into one-cell pieces (``raycast_grid``). A cast of ``B`` beams from one origin then costs
a fixed number of numpy calls (``raycast_kernel``):

1. the pieces under the bounding box of the beams (the fan of rays out to ``max_range``),
   copied row run by row run out of the index (no per-cell Python loop);
2. for each piece, the run of beams whose directions lie between its endpoints' directions
   (one binary search over the sorted beam directions);
3. for each (beam, piece) pair in those runs the exact distance to the piece's line,
   reduced per beam with ``np.maximum.at`` on its reciprocal.

With long ranges in dense worlds an occlusion cut first casts against the pieces near the
laser and looks further only along the beams that saw nothing (see ``RayCaster``).

With numba (a default dependency) a compiled kernel (``raycast_numba``) walks each
beam through the same grid instead, nearest cell first, for the same ranges (bit for bit
except beams grazing a piece end, see below) several times faster; ``backend`` chooses.

Only pieces in range are touched, so a scan's cost follows the walls near the laser, not
the size of the world. Results are exact segment intersections, not grid approximations.

Numerical conventions (all tested):

- A ray through a vertex shared by two walls is never lost: direction intervals are
  half-open and both walls compare the ray against the very same computed vertex angle.
- A ray parallel to a wall never hits it, except a wall seen exactly edge-on (the origin on
  its line, within ``contact_tolerance_m``) whose near end is hit by the ray pointing at it.
- An origin within ``contact_tolerance_m`` of a wall is inside it: every range is 0.
- A ray passing a lone segment end within float precision of its own direction may hit
  or miss that end (both are right to rounding); elsewhere ranges match an exact
  intersection to ~1e-12 relative.
- Zero-length segments (shorter than ``MIN_SEGMENT_LENGTH_M``) are dropped.
- No hit within ``max_range``: the range is ``inf``.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from albot2d.compiled import compiled_kernel
from albot2d.errors import InputError
from albot2d.geometry import point_segment_distance
from albot2d.sim.raycast_grid import (
    MIN_SEGMENT_LENGTH_M,
    SegmentGrid,
    clean_segments,
    piece_table,
)
from albot2d.sim.raycast_kernel import BeamFan, beam_directions, cast_pieces

__all__ = [
    "BACKENDS",
    "MIN_SEGMENT_LENGTH_M",
    "NEAR_PASS_MIN_PIECES",
    "NEAR_PASS_PIECES",
    "SURFACE_TOLERANCE_M",
    "BeamFan",
    "RayCaster",
    "cast_brute_force",
    "numba_available",
]

FloatArray = NDArray[np.float64]

_HALF_PI = 0.5 * math.pi


#: With more pieces than this under the fan's box, cast a near pass first (see RayCaster).
NEAR_PASS_MIN_PIECES = 2000
#: The near pass reaches out to about this many pieces.
NEAR_PASS_PIECES = 600
#: Beams still open after the near pass are grouped into at most this many boxes.
_MAX_FAR_BOXES = 3
#: ``RayCaster(backend=...)``: "auto" takes the compiled kernel when numba is installed.
BACKENDS = ("auto", "numpy", "numba")
_NO_PIECES = np.zeros((3, 0), dtype=np.complex128)


def _numba_kernel() -> Callable[..., None] | None:
    """``raycast_numba.cast_beams``, imported on first use (numba takes a while to import);
    None when the compiled kernels are off."""
    return compiled_kernel("albot2d.sim.raycast_numba", "cast_beams")


def _edges_kernel() -> Callable[..., None] | None:
    """``raycast_numba.depth_edges`` (see ``_numba_kernel``)."""
    return compiled_kernel("albot2d.sim.raycast_numba", "depth_edges")


def numba_available() -> bool:
    """Whether the compiled kernel can be used (``albot2d.compiled.kernels``)."""
    return _numba_kernel() is not None


def _resolve_backend(backend: str) -> str:
    if backend == "numpy" or (backend == "auto" and not numba_available()):
        return "numpy"
    if not numba_available():
        raise InputError("backend='numba' needs numba (off under ALBOT2D_KERNELS=numpy)")
    return "numba"


class RayCaster:
    """Exact raycasting against fixed segments (``(N, 4)`` ``[x1, y1, x2, y2]``, metres).

    ``cell_size_m`` is the grid pitch of the spatial index (default: from the segment
    density, about eight pieces per cell). ``contact_tolerance_m`` is how close the origin
    must be to a wall's line to count as on it (see the module docstring).

    Occlusion cut: when the box around the fan holds more than ``near_pass_min_pieces``
    pieces (long ranges in dense worlds), the beams are first cast against the pieces
    near the laser only (a range holding about ``near_pass_pieces``); the beams that hit
    something there are done, and only the others are cast again against the pieces under
    the bounding boxes of their own rays.

    ``backend``: "numpy" is the vectorised kernel above; "numba" a compiled per-beam walk
    through the same grid (``raycast_numba``; numba), which gives the
    same ranges (bit for bit, except beams grazing a piece end) several times faster and
    needs no occlusion cut; "auto" (default) takes numba when it is installed. The
    compiled kernel is built on first use and cached on disk.
    A RayCaster is immutable after construction and safe to share between threads.
    """

    def __init__(
        self,
        segments: ArrayLike,
        *,
        cell_size_m: float | None = None,
        contact_tolerance_m: float = 1e-9,
        near_pass_min_pieces: int = NEAR_PASS_MIN_PIECES,
        near_pass_pieces: int = NEAR_PASS_PIECES,
        backend: str = "auto",
    ) -> None:
        if backend not in BACKENDS:
            raise InputError(f"backend must be one of {BACKENDS}, got {backend!r}")
        if not (math.isfinite(contact_tolerance_m) and contact_tolerance_m >= 0.0):
            raise InputError(f"contact_tolerance_m must be >= 0, got {contact_tolerance_m!r}")
        for name, value, least in (
            ("near_pass_min_pieces", near_pass_min_pieces, 0),
            ("near_pass_pieces", near_pass_pieces, 1),
        ):
            if isinstance(value, bool) or not isinstance(value, int) or value < least:
                raise InputError(f"{name} must be an integer >= {least}, got {value!r}")
        self.grid = SegmentGrid(segments, cell_size_m)
        self.contact_tolerance_m = float(contact_tolerance_m)
        self.near_pass_min_pieces = near_pass_min_pieces
        self.near_pass_pieces = near_pass_pieces
        # The name, not the kernel: a RayCaster pickles small and loads numba where needed.
        self._backend = _resolve_backend(backend)
        self._layout = self.grid.layout
        self._vertex = _vertex_ids(self.grid.segments)
        self._n_vertices = int(self._vertex.max(initial=-1)) + 1

    @property
    def backend(self) -> str:
        """The kernel in use: "numpy" or "numba"."""
        return self._backend

    @property
    def segments(self) -> FloatArray:
        return self.grid.segments

    @property
    def n_segments(self) -> int:
        return len(self.grid.segments)

    @property
    def n_pieces(self) -> int:
        return self.grid.n_pieces

    @property
    def cell_size_m(self) -> float:
        return self.grid.cell_size_m

    def pieces_in_box(self, xmin: float, ymin: float, xmax: float, ymax: float) -> np.ndarray:
        return self.grid.pieces_in_box(xmin, ymin, xmax, ymax)

    def cast(
        self,
        origin: Sequence[float] | NDArray[np.floating],
        angles: ArrayLike | BeamFan,
        max_range: float,
        *,
        heading: float = 0.0,
        extra_segments: ArrayLike | None = None,
    ) -> FloatArray:
        """Distance along each beam to the first segment hit; ``inf`` when none within range.

        ``angles`` are beam directions (radians) in the world frame, rotated by ``heading``;
        pass a prepared ``BeamFan`` to save re-sorting them on every call. ``extra_segments``
        (``(M, 4)``, world frame, e.g. moving obstacles) are hit together with the index.
        Returns ``(B,)`` float64 in the order of ``angles``.
        """
        fan = angles if isinstance(angles, BeamFan) else BeamFan.from_angles(angles)
        try:
            x, y = origin
            ox, oy = float(x), float(y)
        except (TypeError, ValueError):
            raise InputError(f"ray origin must be two numbers (x, y), got {origin!r}") from None
        r_max = float(max_range)
        if not (math.isfinite(ox) and math.isfinite(oy)):
            raise InputError(f"ray origin must be finite, got ({ox}, {oy})")
        if not r_max > 0.0:
            raise InputError(f"max_range must be > 0, got {max_range!r}")
        extra = None
        if extra_segments is not None:
            cleaned = clean_segments(extra_segments, "extra_segments")
            extra = piece_table(cleaned) if len(cleaned) else None
        # The kernel compares directions in [-pi, pi] with the fan centred on mid.
        mid = math.remainder(fan.mid_rad + float(heading), 2.0 * math.pi)
        directions = beam_directions(fan, heading)
        tol = self.contact_tolerance_m
        # Pieces within this of the origin are checked for contact; the fan's box pads.
        pad = 1e-9 * (1.0 + r_max + abs(ox) + abs(oy))
        if self._backend == "numba":
            ranges = np.empty(fan.n_beams)
            scan = np.array([ox, oy, mid, r_max, tol, pad])
            grid = self.grid
            kernel = _numba_kernel()
            assert kernel is not None  # the backend was resolved to numba
            kernel(
                grid.table,
                grid.cell_start,
                self._layout,
                _NO_PIECES if extra is None else extra,
                directions,
                fan.ext_rel,
                scan,
                ranges,
            )
            if fan.order is not None:
                unsorted = np.empty_like(ranges)
                unsorted[fan.order] = ranges
                return unsorted
            return ranges
        reach = 2.0 * tol + pad
        box = _fan_box(ox, oy, mid, fan.half_span_rad, r_max, reach)
        starts, ends = self.grid.runs(*box)
        n_box = sum(ends) - sum(starts)
        # Occlusion cut: most beams stop near the laser; look further only along the rest.
        r_near = r_max * math.sqrt(self.near_pass_pieces / max(n_box, 1))
        if n_box <= self.near_pass_min_pieces or r_near >= r_max:
            table = _with(self.grid.gather(starts, ends), extra)
            return cast_pieces(table, ox, oy, mid, directions, fan, r_max, tol)
        near_box = _fan_box(ox, oy, mid, fan.half_span_rad, r_near, reach)
        table = _with(self.grid.pieces_in_box(*near_box), extra)
        ranges = cast_pieces(table, ox, oy, mid, directions, fan, r_near, tol)
        still_open = np.isinf(ranges)
        if not still_open.any():
            return ranges
        boxes = _ray_boxes(ox, oy, fan.angles[still_open] + heading, r_max)
        far = [self.grid.pieces_in_box(*b) for b in boxes]
        table = _with(far[0] if len(far) == 1 else np.concatenate(far, axis=1), extra)
        far_ranges = cast_pieces(table, ox, oy, mid, directions, fan, r_max, tol)
        ranges[still_open] = far_ranges[still_open]
        return ranges

    def segments_through(
        self, points: ArrayLike, *, extra_segments: ArrayLike | None = None
    ) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
        """Which segments pass through which of the ``(P, 2)`` ``points`` (world frame, e.g.
        beam hits), within ``SURFACE_TOLERANCE_M``: pairs ``(point, segment)`` as two index
        arrays, sorted by point; ``segment`` is ``0 … n_segments - 1`` for the index's
        segments and ``n_segments + j`` for ``extra_segments[j]``. A point where walls meet
        or overlap is on several; a point on none appears in no pair."""
        pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        point, seg = self._static_through(pts)
        extra = _clean_extra(extra_segments)
        if len(extra):
            near = point_segment_distance(pts, extra) <= SURFACE_TOLERANCE_M
            ep, es = np.nonzero(near)
            point = np.concatenate([point, ep])
            seg = np.concatenate([seg, es + self.n_segments])
            order = np.argsort(point, kind="stable")
            point, seg = point[order], seg[order]
        return point, seg

    def same_surface(
        self, p: ArrayLike, q: ArrayLike, *, extra_segments: ArrayLike | None = None
    ) -> NDArray[np.bool_]:
        """Whether ``p[k]`` and ``q[k]`` (``(P, 2)`` points on the walls) lie on one
        continuous run of wall: some segment through ``p[k]`` and some segment through
        ``q[k]`` are the same or share an endpoint (a corner, or a wall drawn in pieces).

        Neighbouring beams whose hits are not on one surface straddle an occluding edge,
        where a real laser's footprint can return a mixed pixel. A point on no segment is
        on no surface. (The laser asks this through ``depth_edges``, whose compiled kernel
        makes the same test inline.)"""
        pa = np.asarray(p, dtype=np.float64).reshape(-1, 2)
        qa = np.asarray(q, dtype=np.float64).reshape(-1, 2)
        n = len(pa)
        if len(qa) != n:
            raise InputError(f"same_surface needs as many points q as p, got {len(qa)} and {n}")
        extra = _clean_extra(extra_segments)
        point, seg = self.segments_through(np.concatenate([pa, qa]), extra_segments=extra)
        vertex = self._vertex
        if len(extra):
            vertex = np.concatenate([vertex, _vertex_ids(extra) + self._n_vertices])
        n_vertices = int(vertex.max(initial=-1)) + 1
        # One key per (pair k, corner of a segment through the point): p's and q's share
        # one exactly when a segment through each is the same or meets the other's end.
        k = point % max(n, 1)
        keys = (k[:, None] * n_vertices + vertex[seg]).ravel()
        from_p = np.repeat(point < n, 2)
        shared = np.intersect1d(keys[from_p], keys[~from_p])
        out = np.zeros(n, dtype=np.bool_)
        out[shared // max(n_vertices, 1)] = True
        return out

    def depth_edges(
        self,
        origin: Sequence[float],
        angles: ArrayLike,
        ranges: ArrayLike,
        hit: ArrayLike,
        min_jump_m: float,
        *,
        extra_segments: ArrayLike | None = None,
    ) -> NDArray[np.bool_]:
        """``(B - 1,)``: whether beams ``k`` and ``k + 1`` straddle an occluding edge: both
        ``hit``, their ``ranges`` differ by more than ``min_jump_m``, and their hits (from
        ``origin`` along the world-frame ``angles``) are not on one surface
        (``same_surface``). A real laser's footprint can mix the two returns only there."""
        ox, oy = (float(v) for v in origin)
        a = np.asarray(angles, dtype=np.float64)
        r = np.asarray(ranges, dtype=np.float64)
        h = np.asarray(hit, dtype=np.bool_)
        if not (len(a) == len(r) == len(h)):
            raise InputError(
                f"depth_edges needs one angle, range and hit flag per beam, got "
                f"{len(a)}, {len(r)} and {len(h)}"
            )
        extra = _clean_extra(extra_segments)
        if self._backend == "numba":
            kernel = _edges_kernel()
            assert kernel is not None  # the backend was resolved to numba
            out = np.empty(max(len(r) - 1, 0), dtype=np.bool_)
            grid = self.grid
            own = _vertex_ids(extra) + self._n_vertices
            kernel(ox, oy, a, r, h, float(min_jump_m), grid.table, grid.piece_segment,
                   grid.cell_start, self._layout, self._vertex,
                   piece_table(extra) if len(extra) else _NO_PIECES, own,
                   SURFACE_TOLERANCE_M, out)  # fmt: skip
            return out
        edges = np.abs(r[1:] - r[:-1]) > min_jump_m
        edges &= h[1:]
        edges &= h[:-1]
        at = np.flatnonzero(edges)
        if len(at):
            pair = np.concatenate([at, at + 1])
            xy = np.column_stack([ox + r[pair] * np.cos(a[pair]), oy + r[pair] * np.sin(a[pair])])
            smooth = self.same_surface(xy[: len(at)], xy[len(at) :], extra_segments=extra)
            edges[at[smooth]] = False
        return edges

    def _static_through(self, pts: FloatArray) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
        """``segments_through`` for the index's segments: only the pieces in the grid cells
        around each point are measured."""
        none = np.zeros(0, dtype=np.intp)
        if len(pts) == 0 or self.n_pieces == 0:
            return none, none
        grid = self.grid
        cells = grid.cells_near(pts[:, 0], pts[:, 1], SURFACE_TOLERANCE_M)
        owner = np.repeat(np.arange(len(pts)), cells.shape[1])
        cells = cells.ravel()
        start, end = grid.cell_start[cells], grid.cell_start[cells + 1]
        counts = end - start
        owner = np.repeat(owner, counts)
        if len(owner) == 0:
            return none, none
        piece = np.arange(len(owner)) - np.repeat(np.cumsum(counts) - counts - start, counts)
        table = grid.table
        z = pts[owner, 0] + 1j * pts[owner, 1]
        on = _point_piece_distance(z, table[0, piece], table[1, piece]) <= SURFACE_TOLERANCE_M
        point, seg = owner[on], grid.piece_segment[piece[on]]
        # A cell listed twice for a point, or a segment cut at a grid line through the point,
        # gives a pair twice.
        key = np.unique(point * self.n_segments + seg)
        return key // self.n_segments, key % self.n_segments


#: How far (metres) a beam's hit point may lie from the segment it hit (rounding only).
SURFACE_TOLERANCE_M = 1e-6


def _clean_extra(extra_segments: ArrayLike | None) -> FloatArray:
    if extra_segments is None:
        return np.zeros((0, 4))
    return clean_segments(extra_segments, "extra_segments")


def _vertex_ids(segs: FloatArray) -> NDArray[np.intp]:
    """``(N, 2)``: one id per distinct endpoint, so segments meeting at a corner (the same
    coordinates, bit for bit, as polygon rings give) share one."""
    if len(segs) == 0:
        return np.zeros((0, 2), dtype=np.intp)
    ends = np.concatenate([segs[:, :2], segs[:, 2:]])
    _, ids = np.unique(ends, axis=0, return_inverse=True)
    ids = ids.reshape(-1).astype(np.intp)
    return np.stack([ids[: len(segs)], ids[len(segs) :]], axis=1)


def _point_piece_distance(
    z: NDArray[np.complex128], a: NDArray[np.complex128], b: NDArray[np.complex128]
) -> FloatArray:
    """Distance from points ``z`` to segments ``a → b`` (complex coordinates, elementwise)."""
    e = b - a
    t = np.clip((np.conj(e) * (z - a)).real / np.maximum((e * np.conj(e)).real, 1e-300), 0, 1)
    return np.abs(z - a - t * e)


def _with(table: np.ndarray, extra: np.ndarray | None) -> np.ndarray:
    return table if extra is None else np.concatenate([table, extra], axis=1)


def _ray_boxes(
    ox: float, oy: float, angles: FloatArray, r: float
) -> list[tuple[float, float, float, float]]:
    """Bounding boxes of the rays ``origin + [0, r] e^{i a}``, their directions split into at
    most ``_MAX_FAR_BOXES`` groups at the widest gaps around the circle."""
    a = np.sort(np.mod(angles, 2.0 * math.pi))
    m = len(a)
    gaps = np.diff(a, append=a[0] + 2.0 * math.pi)  # gaps[i] follows a[i]; the last wraps
    ends = np.sort(np.argsort(gaps)[m - min(_MAX_FAR_BOXES, m) :])  # last index of a group
    start = (int(ends[-1]) + 1) % m
    a = np.roll(a, -start)
    bounds = [0, *np.sort((ends - start) % m + 1).tolist()]
    xs, ys = ox + r * np.cos(a), oy + r * np.sin(a)
    pad = 1e-9 * (1.0 + r + abs(ox) + abs(oy))
    boxes = []
    for lo, hi in itertools.pairwise(bounds):
        gx, gy = xs[lo:hi], ys[lo:hi]
        boxes.append(
            (
                min(float(gx.min()), ox) - pad,
                min(float(gy.min()), oy) - pad,
                max(float(gx.max()), ox) + pad,
                max(float(gy.max()), oy) + pad,
            )
        )
    return boxes


def _fan_box(
    ox: float, oy: float, mid: float, half: float, r: float, reach: float = 0.0
) -> tuple[float, float, float, float]:
    """Axis-aligned bounding box of the rays ``origin + [0, r] * e^{i a}``, a in mid ± half,
    and of the square ``origin ± reach`` (where contact with a wall is checked)."""
    if half >= math.pi - 1e-12:
        r = max(r, reach)
        return ox - r, oy - r, ox + r, oy + r
    lo, hi = mid - half, mid + half
    xs = [ox - reach, ox + reach, ox + r * math.cos(lo), ox + r * math.cos(hi)]
    ys = [oy - reach, oy + reach, oy + r * math.sin(lo), oy + r * math.sin(hi)]
    k = math.ceil(lo / _HALF_PI)
    while k * _HALF_PI <= hi:
        quadrant = k % 4
        if quadrant == 0:
            xs.append(ox + r)
        elif quadrant == 1:
            ys.append(oy + r)
        elif quadrant == 2:
            xs.append(ox - r)
        else:
            ys.append(oy - r)
        k += 1
    # Pad by a hair: the bounding box is also rounded, and a piece may touch the boundary.
    pad = 1e-9 * (1.0 + r + abs(ox) + abs(oy))
    return min(xs) - pad, min(ys) - pad, max(xs) + pad, max(ys) + pad


def cast_brute_force(
    segments: ArrayLike,
    origin: ArrayLike,
    angles: ArrayLike,
    max_range: float,
    *,
    contact_tolerance_m: float = 1e-9,
) -> FloatArray:
    """Reference: every beam against every segment, textbook ray/segment intersection.

    O(B·N) time and memory; for tests and small inputs. Same conventions as ``RayCaster``:
    a segment seen exactly edge-on is hit at its near end, an origin within
    ``contact_tolerance_m`` of a segment gives all-zero ranges, ``inf`` means no hit.
    """
    segs = clean_segments(segments)
    o = np.asarray(origin, dtype=np.float64).reshape(2)
    a = np.asarray(angles, dtype=np.float64).reshape(-1)
    if len(segs) == 0:
        return np.full(len(a), np.inf)
    if point_segment_distance(o[None, :], segs).min() <= contact_tolerance_m:
        return np.zeros(len(a))
    d = np.column_stack([np.cos(a), np.sin(a)])[:, None, :]  # (B, 1, 2)
    p, q = segs[None, :, :2] - o, segs[None, :, 2:] - o  # (1, N, 2)
    e = q - p
    cross_de = d[..., 0] * e[..., 1] - d[..., 1] * e[..., 0]
    cross_pd = p[..., 0] * d[..., 1] - p[..., 1] * d[..., 0]
    # A ray (nearly) parallel to a segment divides by (almost) zero: t and u are then
    # huge, infinite or NaN and the hit test below rejects them, as it should.
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        t = (p[..., 0] * e[..., 1] - p[..., 1] * e[..., 0]) / cross_de
        u = cross_pd / cross_de
    hit = (cross_de != 0.0) & (t >= 0.0) & (u >= 0.0) & (u <= 1.0)
    # Collinear: the ray runs along the segment's line; it meets the segment's near end.
    tp, tq = (p * d).sum(axis=-1), (q * d).sum(axis=-1)
    along = (cross_de == 0.0) & (cross_pd == 0.0) & (np.maximum(tp, tq) >= 0.0)
    t = np.where(along, np.maximum(np.minimum(tp, tq), 0.0), t)
    t = np.where(hit | along, t, np.inf).min(axis=1, initial=np.inf)
    return np.where(t <= max_range, t, np.inf)
