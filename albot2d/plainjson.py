"""Values → plain JSON types: the one converter behind report.json, run.json, the log's
PARAM lines and a generated world's features.

Dataclasses become dicts, mappings dicts with string keys, numpy arrays and tuples lists,
numpy scalars Python numbers, paths strings. Non-finite floats are kept (``nan_to_none=
False``, for files written with ``allow_nan``) or become ``None`` (report.json's ``null``).
Anything else is refused with the place it was found.
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Mapping
from typing import Any

import numpy as np

from albot2d.errors import InputError

__all__ = ["to_plain"]


def to_plain(
    value: Any, *, where: str = "value", into: str = "JSON", nan_to_none: bool = False
) -> Any:
    """``value`` as plain JSON types (see the module docstring); ``where`` names the value
    and ``into`` the file in the error for a value that has no JSON form."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        value = dataclasses.asdict(value)
    if isinstance(value, Mapping):
        return {str(k): to_plain(v, where=f"{where}[{k!r}]", into=into, nan_to_none=nan_to_none)
                for k, v in value.items()}  # fmt: skip
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if isinstance(value, list | tuple):
        return [to_plain(v, where=f"{where}[{i}]", into=into, nan_to_none=nan_to_none)
                for i, v in enumerate(value)]  # fmt: skip
    if isinstance(value, bool | np.bool_):
        return bool(value)
    if isinstance(value, int | np.integer):
        return int(value)
    if isinstance(value, float | np.floating):
        return None if nan_to_none and not math.isfinite(value) else float(value)
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    if value is None or isinstance(value, str):
        return value
    raise InputError(f"{where}: cannot store a {type(value).__name__} in {into}")
