"""Checks that parameter dataclasses and readers run; each error names field and value.

Also the physical limits every input shares: :data:`COORDINATE_LIMIT_M` bounds every
coordinate and size in metres (world files, log poses, relations), so that no later
computation (grids, spatial indexes, squared distances) overflows or loses all precision.
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from albot2d.errors import InputError
from albot2d.limits import COORDINATE_LIMIT_M, MAX_JSON_DEPTH, MAX_SEEDS

__all__ = [
    "COORDINATE_LIMIT_M",
    "MAX_JSON_DEPTH",
    "check_at_most",
    "check_coordinates",
    "check_finite",
    "check_in_range",
    "check_non_negative",
    "check_positive",
    "check_positive_int",
    "params_from_mapping",
    "parse_json",
    "parse_seed_list",
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


def check_positive_int(obj: object, *names: str, maximum: int | None = None) -> None:
    """Each named field must be an integer > 0 (and <= ``maximum``, a named cap, if given)."""
    for name in names:
        value = getattr(obj, name)
        if isinstance(value, bool) or not isinstance(value, int) or value <= 0:
            raise InputError(f"{_owner(obj)}.{name} must be a positive integer, got {value!r}")
        if maximum is not None and value > maximum:
            raise InputError(f"{_owner(obj)}.{name} must be <= {maximum}, got {value!r}")


def check_in_range(obj: object, name: str, low: float, high: float) -> None:
    value = check_finite(obj, name)
    if not low <= value <= high:
        raise InputError(f"{_owner(obj)}.{name} must be in [{low}, {high}], got {value!r}")


def check_at_most(obj: object, name: str, maximum: float, why: str = "") -> None:
    """``obj.name`` must be a finite number <= ``maximum`` (a named cap; ``why`` explains it)."""
    value = check_finite(obj, name)
    if value > maximum:
        reason = f" ({why})" if why else ""
        raise InputError(f"{_owner(obj)}.{name} must be <= {maximum:g}{reason}, got {value!r}")


def check_coordinates(values: ArrayLike, what: str, limit: float = COORDINATE_LIMIT_M) -> None:
    """Every number in ``values`` must be finite and within ±``limit``; names the first bad row."""
    arr = np.asarray(values, dtype=np.float64)
    bad = ~(np.abs(arr) <= limit)  # NaN compares False, so it is caught too
    if bad.any():
        index = tuple(int(i) for i in np.argwhere(bad)[0])
        row = index[:1] if arr.ndim > 1 else index
        shown = arr[row].tolist() if arr.ndim > 1 else arr[index].item()
        where = "".join(f"[{i}]" for i in row)
        raise InputError(f"{what}{where} is {shown!r}, outside the limit of ±{limit:g} m")


def parse_json(
    text: str,
    source: str,
    *,
    max_depth: int = MAX_JSON_DEPTH,
    object_pairs_hook: Callable[[list[tuple[str, Any]]], Any] | None = None,
) -> Any:
    """Parse JSON ``text``; every failure is one ``InputError`` naming ``source``.

    Covers what ``json`` raises beyond ``JSONDecodeError``: ``RecursionError`` for deep
    nesting and ``ValueError`` for integers with more digits than Python converts; then
    refuses documents nested deeper than ``max_depth``.
    """
    try:
        doc = json.loads(text, object_pairs_hook=object_pairs_hook)
    except json.JSONDecodeError as exc:
        raise InputError(
            f"{source}: not valid JSON: {exc.msg} at line {exc.lineno} column {exc.colno}"
        ) from None
    except RecursionError:
        raise InputError(f"{source}: JSON nested deeper than {max_depth} levels") from None
    except ValueError as exc:  # e.g. "Exceeds the limit (4300 digits) for integer string"
        raise InputError(f"{source}: not valid JSON: {str(exc)[:120]}") from None
    if _json_depth(doc, max_depth) > max_depth:
        raise InputError(f"{source}: JSON nested deeper than {max_depth} levels")
    return doc


def _json_depth(doc: Any, limit: int) -> int:
    """How deep lists and objects nest in ``doc`` (stops past ``limit``); iterative."""
    deepest = 0
    stack: list[tuple[Any, int]] = [(doc, 1)]
    while stack:
        value, depth = stack.pop()
        if isinstance(value, dict | list):
            deepest = max(deepest, depth)
            if depth > limit:
                return depth
            items = value.values() if isinstance(value, dict) else value
            stack.extend((item, depth + 1) for item in items if isinstance(item, dict | list))
    return deepest


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


def parse_seed_list(text: str, option: str = "--seeds") -> list[int]:
    """``A-B`` (inclusive), ``A,B,C``, ``N`` or a mix (``0-4,9``) → sorted distinct seeds
    >= 0, at most ``MAX_SEEDS``; anything else is an ``InputError`` naming ``option``."""
    seeds: set[int] = set()
    for part in text.split(","):
        lo, dash, hi = part.strip().partition("-")
        try:
            a = int(lo)
            b = int(hi) if dash else a
        except ValueError:
            raise InputError(f"{option}: expected A-B, A,B,C or N, got {text!r}") from None
        if a < 0 or b < a:
            raise InputError(f"{option}: {part.strip()!r} is not a range of seeds >= 0")
        if b - a >= MAX_SEEDS or len(seeds) + b - a >= MAX_SEEDS:
            raise InputError(f"{option}: at most {MAX_SEEDS} seeds, got {part.strip()!r}")
        seeds.update(range(a, b + 1))
    return sorted(seeds)
