"""The surfaces of one view as parallel arrays (``Surfaces``), and a scalar ``Surface`` view of one.

Endpoint order is scan order: endpoint 0 comes from the lower beam index (the robot's
right), endpoint 1 from the higher (its left). ``occluded[i, k]`` says endpoint ``k`` of
surface ``i`` is not a real corner: a nearer reading next to it, a no-return neighbour
or the edge of the field of view hides where the surface really ends.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from albot2d.arrays import readonly
from albot2d.compiled import compiled_kernel
from albot2d.geometry import (
    Pose,
    as_segments,
    segment_angles,
    segment_lengths,
    transform_segments,
)

__all__ = ["Surface", "Surfaces", "transform_segments_fast"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class Surface:
    """One surface: endpoints ``p0``/``p1`` (metres, view frame) and their occlusion flags."""

    p0: tuple[float, float]
    p1: tuple[float, float]
    p0_occluded: bool
    p1_occluded: bool

    @property
    def length_m(self) -> float:
        return float(np.hypot(self.p1[0] - self.p0[0], self.p1[1] - self.p0[1]))


@dataclass(frozen=True, eq=False)
class Surfaces:
    """N surfaces of one view.

    - ``segments``: ``(N, 4)`` endpoints ``[x0, y0, x1, y1]`` in the view (robot) frame.
    - ``occluded``: ``(N, 2)`` bool, per endpoint.
    - ``beams``: ``(N, 2)`` int, first and last beam index of the supporting points
      (``-1`` when the surfaces did not come from a scan, e.g. were transformed).
    - ``uncertain``: ``(N, 2)`` bool, an unoccluded end whose position along the surface
      is known only coarsely (a wall ending at a grazing angle): still a real end for
      tracking, but not precise enough to localise from. ``None`` means all False.
    """

    segments: FloatArray
    occluded: NDArray[np.bool_]
    beams: NDArray[np.int64]
    uncertain: NDArray[np.bool_] | None = None

    def __repr__(self) -> str:
        from albot2d.reprs import compact_fields

        return compact_fields(
            "Surfaces",
            segments=self.segments,
            occluded=self.occluded,
            beams=self.beams,
            uncertain=self.uncertain,
        )

    def __post_init__(self) -> None:
        segs = as_segments(self.segments)
        n = len(segs)
        uncertain = np.zeros((n, 2), bool) if self.uncertain is None else self.uncertain
        object.__setattr__(self, "segments", readonly(segs, np.float64, (n, 4)))
        object.__setattr__(self, "occluded", readonly(self.occluded, np.bool_, (n, 2)))
        object.__setattr__(self, "beams", readonly(self.beams, np.int64, (n, 2)))
        object.__setattr__(self, "uncertain", readonly(uncertain, np.bool_, (n, 2)))

    @property
    def localisable(self) -> NDArray[np.bool_]:
        """``(N, 2)``: endpoints that are real, precisely located ends (usable to localise)."""
        assert self.uncertain is not None  # set in __post_init__
        return ~self.occluded & ~self.uncertain

    @classmethod
    def adopt(
        cls,
        segments: FloatArray,
        occluded: NDArray[np.bool_],
        beams: NDArray[np.int64],
        uncertain: NDArray[np.bool_],
    ) -> Surfaces:
        """Surfaces taking ownership of fresh arrays of the right dtypes and shapes
        (``(N, 4)`` float64, ``(N, 2)`` bool, int64, bool): made read-only, not copied.
        For producers that just built them (the compiled extraction: saves ~10 µs)."""
        out = object.__new__(cls)
        segments.flags.writeable = False
        occluded.flags.writeable = False
        beams.flags.writeable = False
        uncertain.flags.writeable = False
        # Frozen: the fields go straight into the instance dict (what __init__ would set).
        out.__dict__.update(segments=segments, occluded=occluded, beams=beams, uncertain=uncertain)
        return out

    @classmethod
    def empty(cls) -> Surfaces:
        return cls(np.zeros((0, 4)), np.zeros((0, 2), bool), np.zeros((0, 2), np.int64))

    @classmethod
    def from_segments(cls, segments: ArrayLike, occluded: ArrayLike | None = None) -> Surfaces:
        """Surfaces from bare segments (no beams); endpoints unoccluded unless given."""
        segs = as_segments(segments)
        occ = np.zeros((len(segs), 2), bool) if occluded is None else np.asarray(occluded)
        return cls(segs, occ, np.full((len(segs), 2), -1, np.int64))

    def __len__(self) -> int:
        return len(self.segments)

    @property
    def lengths_m(self) -> FloatArray:
        return segment_lengths(self.segments)

    @property
    def angles_rad(self) -> FloatArray:
        return segment_angles(self.segments)

    def select(self, index: ArrayLike) -> Surfaces:
        """A subset by boolean mask or integer indices (order of ``index`` kept)."""
        idx = np.asarray(index)
        assert self.uncertain is not None
        if idx.ndim == 1 and (idx.dtype == np.bool_ or idx.dtype.kind in "iu"):
            if idx.dtype == np.bool_:
                if len(idx) != len(self.segments):
                    raise IndexError(
                        f"boolean index has {len(idx)} entries for {len(self.segments)} surfaces"
                    )
                idx = np.flatnonzero(idx)
            # take() makes fresh arrays of the right dtypes and shapes (as fancy indexing
            # does, at a third of its cost): adopt them (the tracker selects per view).
            return Surfaces.adopt(
                self.segments.take(idx, axis=0), self.occluded.take(idx, axis=0),
                self.beams.take(idx, axis=0), self.uncertain.take(idx, axis=0),
            )  # fmt: skip
        return Surfaces(
            self.segments[idx], self.occluded[idx], self.beams[idx], self.uncertain[idx]
        )

    def transformed(self, pose: ArrayLike | Pose) -> Surfaces:
        """The same surfaces mapped from this view's frame by ``pose`` ([x, y, theta] or a
        ``Pose``)."""
        assert self.uncertain is not None
        # The flags are read-only already and shared; the segments are fresh.
        return Surfaces.adopt(
            transform_segments_fast(pose, self.segments), self.occluded, self.beams,
            self.uncertain,
        )  # fmt: skip

    def surface(self, i: int) -> Surface:
        s = self.segments[i]
        return Surface(
            (float(s[0]), float(s[1])),
            (float(s[2]), float(s[3])),
            bool(self.occluded[i, 0]),
            bool(self.occluded[i, 1]),
        )

    def __iter__(self) -> Iterator[Surface]:
        return (self.surface(i) for i in range(len(self)))


def _transform_kernel() -> Callable[..., FloatArray] | None:
    """``surfaces_numba.transform_kernel`` when numba imports, else None."""
    return compiled_kernel("albot2d.perception.surfaces_numba", "transform_kernel")


def transform_segments_fast(pose: ArrayLike | Pose, segments: ArrayLike) -> FloatArray:
    """``geometry.transform_segments(pose, segments)`` bit for bit, in one compiled call
    when numba imports (a view's few segments: ~2 µs against ~9); ``pose`` may also be a
    ``Pose`` (no array made)."""
    kernel = _transform_kernel()
    if isinstance(pose, Pose):
        x, y, theta = float(pose.x), float(pose.y), float(pose.theta)
        if kernel is None:
            return transform_segments(pose.as_array(), segments)
    else:
        p = np.asarray(pose, dtype=np.float64)
        if kernel is None or p.shape != (3,):
            return transform_segments(pose, segments)
        x, y, theta = float(p[0]), float(p[1]), float(p[2])
    segs = np.ascontiguousarray(as_segments(segments))
    return kernel(x, y, math.cos(theta), math.sin(theta), segs)
