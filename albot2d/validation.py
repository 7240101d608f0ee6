"""Checks that parameter dataclasses run in ``__post_init__``; each error names field and value."""

from __future__ import annotations

import dataclasses
import math
from typing import Any

from albot2d.errors import InputError

__all__ = [
    "check_finite",
    "check_in_range",
    "check_non_negative",
    "check_positive",
    "check_positive_int",
    "params_from_mapping",
]


def _owner(obj: object) -> str:
    return type(obj).__name__


def check_finite(obj: object, name: str) -> float:
    value = getattr(obj, name)
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise InputError(f"{_owner(obj)}.{name} must be a number, got {value!r}")
    if not math.isfinite(value):
        raise InputError(f"{_owner(obj)}.{name} must be finite, got {value!r}")
    return float(value)


def check_positive(obj: object, *names: str) -> None:
    for name in names:
        if check_finite(obj, name) <= 0.0:
            raise InputError(f"{_owner(obj)}.{name} must be > 0, got {getattr(obj, name)!r}")


def check_non_negative(obj: object, *names: str) -> None:
    for name in names:
        if check_finite(obj, name) < 0.0:
            raise InputError(f"{_owner(obj)}.{name} must be >= 0, got {getattr(obj, name)!r}")


def check_positive_int(obj: object, *names: str) -> None:
    for name in names:
        value = getattr(obj, name)
        if isinstance(value, bool) or not isinstance(value, int) or value <= 0:
            raise InputError(f"{_owner(obj)}.{name} must be a positive integer, got {value!r}")


def check_in_range(obj: object, name: str, low: float, high: float) -> None:
    value = check_finite(obj, name)
    if not low <= value <= high:
        raise InputError(f"{_owner(obj)}.{name} must be in [{low}, {high}], got {value!r}")


def params_from_mapping(cls: type, values: dict[str, Any], *, where: str = "") -> Any:
    """Build the frozen params dataclass ``cls`` from a mapping, rejecting unknown names.

    Misspelled options fail loudly with the list of valid names instead of being swallowed.
    """
    fields = {f.name for f in dataclasses.fields(cls)}
    unknown = sorted(set(values) - fields)
    if unknown:
        prefix = f"{where}: " if where else ""
        raise InputError(
            f"{prefix}unknown parameter(s) {', '.join(unknown)} for {cls.__name__}; "
            f"valid: {', '.join(sorted(fields))}"
        )
    return cls(**values)
