"""Read-only numpy arrays for frozen values: the one helper every value type uses.

Frozen dataclasses (scans, surfaces, relations, worlds, the raycaster's tables) hold numpy
arrays; marking them read-only keeps the value immutable. ``readonly`` copies by default,
so the caller's array stays writable and later changes to it cannot leak in.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, DTypeLike

__all__ = ["readonly"]


def readonly(
    values: ArrayLike,
    dtype: DTypeLike | None = None,
    shape: tuple[int, ...] | None = None,
    *,
    copy: bool = True,
) -> np.ndarray[Any, Any]:
    """``values`` as a read-only array (of ``dtype``, reshaped to ``shape`` when given).

    ``copy=False`` marks an array the caller has just built and hands over (no copy).
    """
    out = np.array(values, dtype=dtype, copy=True) if copy else np.asarray(values, dtype=dtype)
    if shape is not None:
        out = out.reshape(shape)
    out.flags.writeable = False
    return out
