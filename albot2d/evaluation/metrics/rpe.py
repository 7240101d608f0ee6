"""Relative pose error (Kümmerle et al. 2009) of a pose estimate against a relations file.

For each relation (t1, t2, δ*): the estimated relative motion δ = x(t1)⁻¹ ⊕ x(t2) is
compared with δ* as ε = δ*⁻¹ ⊕ δ; translational error ‖(εx, εy)‖ (m), rotational
error |wrap(εθ)| (reported in degrees). Every relation has the same weight and no
global alignment is needed. Results are split into short relations (t2 − t1 < 2 s,
consecutive scans) and long ones (loop closures).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from albot2d.errors import InputError
from albot2d.geometry import between_arrays

__all__ = ["RPEResult", "RPEStats", "relation_errors", "relative_pose_error"]


@dataclass(frozen=True, slots=True)
class RPEStats:
    """Mean ± std of translational (m) and rotational (deg) error over ``relations``."""

    trans_m_mean: float | None
    trans_m_std: float | None
    rot_deg_mean: float | None
    rot_deg_std: float | None
    relations: int

    @classmethod
    def of(cls, trans_m: NDArray[np.float64], rot_rad: NDArray[np.float64]) -> RPEStats:
        if len(trans_m) == 0:
            return cls(None, None, None, None, 0)
        rot_deg = np.degrees(rot_rad)
        return cls(
            float(trans_m.mean()),
            float(trans_m.std()),
            float(rot_deg.mean()),
            float(rot_deg.std()),
            len(trans_m),
        )

    def to_dict(self) -> dict[str, float | int | None]:
        return asdict(self)


@dataclass(frozen=True, slots=True)
class RPEResult:
    """Overall, short (t2 − t1 < ``split_s``) and long relation statistics."""

    overall: RPEStats
    short: RPEStats
    long: RPEStats
    split_s: float

    def to_dict(self) -> dict[str, object]:
        out: dict[str, object] = dict(self.overall.to_dict())
        out["short"] = self.short.to_dict()
        out["long"] = self.long.to_dict()
        out["split_s"] = self.split_s
        return out


def _lookup(times: NDArray[np.float64], query: NDArray[np.float64], tol_s: float) -> NDArray:
    order = np.argsort(times, kind="stable")
    st = times[order]
    pos = np.clip(np.searchsorted(st, query), 1, max(len(st) - 1, 1))
    left = np.clip(pos - 1, 0, len(st) - 1)
    right = np.clip(pos, 0, len(st) - 1)
    pick = np.where(np.abs(st[left] - query) <= np.abs(st[right] - query), left, right)
    found = np.abs(st[pick] - query) <= tol_s
    return np.where(found, order[pick], -1)


def relation_errors(
    timestamps: ArrayLike,
    poses: ArrayLike,
    t1: ArrayLike,
    t2: ArrayLike,
    relations: ArrayLike,
    *,
    tolerance_s: float = 1e-3,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_]]:
    """Per-relation (trans_m, rot_rad, used) for estimated ``poses (N, 3)`` at ``timestamps``.

    A relation whose timestamps have no pose within ``tolerance_s`` is not used (its
    errors are NaN), so estimates that cover only part of a log are still comparable.
    """
    ts = np.asarray(timestamps, dtype=np.float64)
    ps = np.asarray(poses, dtype=np.float64).reshape(-1, 3)
    if len(ts) != len(ps):
        raise InputError(f"{len(ts)} timestamps but {len(ps)} poses")
    a, b = np.asarray(t1, np.float64), np.asarray(t2, np.float64)
    rel = np.asarray(relations, np.float64).reshape(-1, 3)
    if len(ts) == 0:
        nan = np.full(len(a), np.nan)
        return nan, nan.copy(), np.zeros(len(a), bool)
    i, j = _lookup(ts, a, tolerance_s), _lookup(ts, b, tolerance_s)
    used = (i >= 0) & (j >= 0)
    est = between_arrays(ps[np.maximum(i, 0)], ps[np.maximum(j, 0)])
    err = between_arrays(rel, est)
    trans = np.where(used, np.hypot(err[:, 0], err[:, 1]), np.nan)
    rot = np.where(used, np.abs(err[:, 2]), np.nan)
    return trans, rot, used


def relative_pose_error(
    timestamps: ArrayLike,
    poses: ArrayLike,
    t1: ArrayLike,
    t2: ArrayLike,
    relations: ArrayLike,
    *,
    split_s: float = 2.0,
    tolerance_s: float = 1e-3,
) -> RPEResult:
    """Kümmerle RPE statistics, overall and split at ``split_s`` seconds."""
    if not (math.isfinite(split_s) and split_s > 0):
        raise InputError(f"split_s must be > 0, got {split_s!r}")
    trans, rot, used = relation_errors(
        timestamps, poses, t1, t2, relations, tolerance_s=tolerance_s
    )
    span = np.asarray(t2, np.float64) - np.asarray(t1, np.float64)
    short = used & (span < split_s)
    long = used & (span >= split_s)
    return RPEResult(
        RPEStats.of(trans[used], rot[used]),
        RPEStats.of(trans[short], rot[short]),
        RPEStats.of(trans[long], rot[long]),
        split_s,
    )
