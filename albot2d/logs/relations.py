"""Kümmerle et al. (2009) relations files: read, write, and build them from a truth trajectory.

A relations line is ``t1 t2 x y z roll pitch yaw`` (``shared/data/SOURCES.md`` §1.2): the true
motion ``pose(t1)⁻¹ ⊕ pose(t2)``, with ``x, y`` in the frame of the pose at ``t1``. The 2D
fields ``z, roll, pitch`` are written as 0 and ignored on reading. Scoring estimates against
relations is the evaluation layer's job; this module only handles the files and the selection.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from albot2d.arrays import readonly
from albot2d.errors import InputError
from albot2d.geometry import between_arrays
from albot2d.logs.carmen import TIMESTAMP_LIMIT_S
from albot2d.logs.carmen_writer import format_float
from albot2d.logs.textio import atomic_text_output, read_number_table
from albot2d.validation import COORDINATE_LIMIT_M, check_positive, check_positive_int

__all__ = [
    "Relations",
    "RelationsOptions",
    "match_timestamps",
    "read_relations",
    "relations_from_truth",
    "write_relations",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

_FIELDS = ("t1", "t2", "x", "y", "z", "roll", "pitch", "yaw")
# Timestamps as in the logs; motions within the coordinate limit (angles too).
_LIMITS = (TIMESTAMP_LIMIT_S, TIMESTAMP_LIMIT_S, *(COORDINATE_LIMIT_M,) * 6)


def _frozen(values: ArrayLike, shape_tail: tuple[int, ...]) -> FloatArray:
    arr = np.array(values, dtype=np.float64, copy=True)
    return readonly(arr, shape=(0, *shape_tail) if arr.size == 0 else None, copy=False)


@dataclass(frozen=True, eq=False)
class Relations:
    """``N`` relations: timestamps ``t1``, ``t2`` ``(N,)`` and ``motion`` ``(N, 3)`` [x, y, yaw]."""

    t1: FloatArray
    t2: FloatArray
    motion: FloatArray

    def __post_init__(self) -> None:
        t1, t2 = _frozen(self.t1, ()), _frozen(self.t2, ())
        motion = _frozen(self.motion, (3,))
        if t1.ndim != 1 or t2.shape != t1.shape or motion.shape != (len(t1), 3):
            raise ValueError(
                f"Relations need t1 (N,), t2 (N,), motion (N, 3); got {t1.shape}, "
                f"{t2.shape}, {motion.shape}"
            )
        object.__setattr__(self, "t1", t1)
        object.__setattr__(self, "t2", t2)
        object.__setattr__(self, "motion", motion)

    def __len__(self) -> int:
        return len(self.t1)


def read_relations(path: str | os.PathLike[str]) -> Relations:
    """Read a relations file (plain or gzip); ``#`` comments and blank lines are skipped."""
    table = read_number_table(path, _FIELDS, "relation", _LIMITS)
    return Relations(t1=table[:, 0], t2=table[:, 1], motion=table[:, [2, 3, 7]])


def write_relations(
    path: str | os.PathLike[str],
    relations: Relations,
    *,
    timestamp_decimals: int | None = None,
    header: Iterable[str] = (),
) -> None:
    """Write ``relations`` atomically (gzip if ``path`` ends in .gz).

    Motions are written exactly (``repr``); timestamps with ``timestamp_decimals`` places (None:
    exact) — use the log's timestamp precision so ``t1``/``t2`` read back equal to the log's.
    """
    with atomic_text_output(path) as out:
        for line in header:
            out.write(f"# {line}\n")
        out.write("# t1 t2 x y z roll pitch yaw\n")
        for t1, t2, (x, y, yaw) in zip(
            relations.t1.tolist(), relations.t2.tolist(), relations.motion.tolist(), strict=True
        ):
            stamps = (
                f"{format_float(t1, timestamp_decimals)} {format_float(t2, timestamp_decimals)}"
            )
            out.write(f"{stamps} {x!r} {y!r} 0.0 0.0 0.0 {yaw!r}\n")


def match_timestamps(
    query: ArrayLike, reference: ArrayLike, *, tolerance_s: float = 1e-4, what: str = "timestamp"
) -> IntArray:
    """Index into sorted ``reference`` of the nearest entry to each ``query`` time.

    Raises :class:`InputError` naming the first ``query`` farther than ``tolerance_s`` from every
    reference time. (The MIT relations file rounds the log's microsecond stamps to 10 µs.)
    """
    q = np.asarray(query, dtype=np.float64)
    ref = np.asarray(reference, dtype=np.float64)
    if ref.ndim != 1 or len(ref) == 0:
        raise InputError(f"no reference timestamps to match {what}s against")
    if np.any(np.diff(ref) < 0):
        raise InputError("reference timestamps must be sorted")
    hi = np.clip(np.searchsorted(ref, q), 1, max(len(ref) - 1, 1))
    lo = hi - 1
    nearest = np.where(np.abs(ref[lo] - q) <= np.abs(ref[hi] - q), lo, hi)
    error = np.abs(ref[nearest] - q)
    bad = np.flatnonzero(~(error <= tolerance_s))
    if len(bad):
        k = int(bad[0])
        raise InputError(
            f"{what} [{k}] = {float(q.flat[k])!r} matches no reference time within {tolerance_s} s "
            f"(nearest {float(ref[nearest.flat[k]])!r}); {len(bad)} unmatched"
        )
    return nearest.astype(np.int64)


@dataclass(frozen=True)
class RelationsOptions:
    """Which scan pairs :func:`relations_from_truth` turns into relations.

    Like the real benchmark, a mix of short relations (every scan with the one
    ``consecutive_step`` later) and loop-closing ones: every ``long_range_every``-th scan is an
    anchor and is paired with the scan nearest to it in position among those at least
    ``long_range_min_gap_s`` later, if that scan is within ``long_range_max_distance_m``.
    Defaults mirror mit-csail (≈ 1040 short, ≈ 130 revisits ≥ 15 s apart within 2 m).
    """

    consecutive_step: int = 1
    long_range_every: int = 10
    long_range_min_gap_s: float = 30.0
    long_range_max_distance_m: float = 2.0

    def __post_init__(self) -> None:
        check_positive_int(self, "consecutive_step", "long_range_every")
        check_positive(self, "long_range_min_gap_s", "long_range_max_distance_m")


def relations_from_truth(
    timestamps: ArrayLike, true_poses: ArrayLike, *, options: RelationsOptions | None = None
) -> Relations:
    """Relations (short ones first, then loop-closing ones) from a truth trajectory.

    ``timestamps`` ``(N,)`` strictly increasing; ``true_poses`` ``(N, 3)``. Deterministic: the
    same trajectory always gives the same relations, in the same order.
    """
    opts = options or RelationsOptions()
    t = np.asarray(timestamps, dtype=np.float64)
    poses = np.asarray(true_poses, dtype=np.float64)
    if t.ndim != 1 or poses.shape != (len(t), 3):
        raise InputError(f"need timestamps (N,) and poses (N, 3), got {t.shape} and {poses.shape}")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(poses))):
        raise InputError("timestamps and true poses must be finite")
    if np.any(np.diff(t) <= 0):
        k = int(np.flatnonzero(np.diff(t) <= 0)[0]) + 1
        raise InputError(f"timestamps must increase strictly; [{k}] = {t[k]!r} after {t[k - 1]!r}")
    first = np.arange(max(len(t) - opts.consecutive_step, 0))
    pairs = [np.column_stack([first, first + opts.consecutive_step]), _loop_pairs(t, poses, opts)]
    i, j = _unique_rows(np.concatenate(pairs)).T
    return Relations(t1=t[i], t2=t[j], motion=between_arrays(poses[i], poses[j]))


def _loop_pairs(t: FloatArray, poses: FloatArray, opts: RelationsOptions) -> IntArray:
    """Anchor → nearest revisit pairs, found through a grid of ``max_distance`` cells."""
    if len(t) == 0:
        return np.empty((0, 2), dtype=np.int64)
    cell_size = opts.long_range_max_distance_m
    cells = np.floor(poses[:, :2] / cell_size).astype(np.int64)
    order = np.lexsort((cells[:, 1], cells[:, 0]))
    keys, starts = np.unique(cells[order], axis=0, return_index=True)
    ends = np.append(starts[1:], len(order))
    bucket = {tuple(k): order[s:e] for k, s, e in zip(keys.tolist(), starts, ends, strict=True)}
    pairs: list[tuple[int, int]] = []
    for anchor in range(0, len(t), opts.long_range_every):
        cx, cy = cells[anchor]
        near = [bucket.get((cx + dx, cy + dy)) for dx in (-1, 0, 1) for dy in (-1, 0, 1)]
        candidates = np.concatenate([c for c in near if c is not None])
        candidates = candidates[t[candidates] - t[anchor] >= opts.long_range_min_gap_s]
        if len(candidates) == 0:
            continue
        dist = np.hypot(*(poses[candidates, :2] - poses[anchor, :2]).T)
        # Lowest index among equally near candidates keeps the choice independent of bucketing.
        best = np.lexsort((candidates, dist))[0]
        if dist[best] <= opts.long_range_max_distance_m:
            pairs.append((anchor, int(candidates[best])))
    return np.array(pairs, dtype=np.int64).reshape(-1, 2)


def _unique_rows(pairs: IntArray) -> IntArray:
    """Drop repeated pairs, keeping the first occurrence and the order."""
    _, first = np.unique(pairs, axis=0, return_index=True)
    return pairs[np.sort(first)]
