"""Numbers over seeds: mean ± sd and the per-seed values, and the verdict words."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from albot2d.evaluation.paper.outputs import OverSeeds

__all__ = ["VERDICTS", "over_seeds", "verdict_of"]

VERDICTS = ("reproduced", "partly", "not reproduced", "not run")


def over_seeds(values: Sequence[float | None], seeds: Sequence[int]) -> OverSeeds:
    """``{"mean", "sd", "n", "per_seed": {seed: value}}``; None values are left out of the
    mean (sd is the sample standard deviation, 0 for one value)."""
    clean = [float(v) for v in values if v is not None and math.isfinite(float(v))]
    arr = np.asarray(clean, dtype=float)
    return {
        "mean": float(arr.mean()) if len(arr) else None,
        "sd": float(arr.std(ddof=1)) if len(arr) > 1 else (0.0 if len(arr) else None),
        "n": len(arr),
        "per_seed": {str(s): (None if v is None else float(v))
                     for s, v in zip(seeds, values, strict=True)},
    }  # fmt: skip


def verdict_of(checks: Sequence[bool]) -> str:
    """All checks pass: reproduced; some: partly; none: not reproduced."""
    if checks and all(checks):
        return "reproduced"
    if any(checks):
        return "partly"
    return "not reproduced"
