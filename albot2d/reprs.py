"""Compact ``repr`` text for values that hold big arrays (scans, surfaces, local maps).

Printing a value in a notebook or a debugger should show what it is in one line, not
thousands of numbers: arrays are summarised by shape and dtype.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["array_summary", "compact_fields", "number"]


def number(value: Any) -> str:
    """A float with 6 significant digits, an int or anything else as ``repr``."""
    if isinstance(value, float | np.floating):
        return f"{float(value):.6g}"
    if isinstance(value, np.integer):
        return str(int(value))
    return repr(value)


def array_summary(value: Any) -> str:
    """``<(181,) float64>`` for an array, ``None`` or the value's own repr otherwise."""
    if isinstance(value, np.ndarray):
        return f"<{value.shape} {value.dtype}>"
    return number(value)


def compact_fields(name: str, **fields: Any) -> str:
    """``Name(a=…, b=<(12, 4) float64>)``: arrays summarised, floats shortened."""
    return f"{name}(" + ", ".join(f"{k}={array_summary(v)}" for k, v in fields.items()) + ")"
