"""Checked conversions of command-line option values, shared by every subcommand.

Each raises ``InputError`` naming the option and the bad value, so ``main`` prints one line.
"""

from __future__ import annotations

import argparse
import math
from typing import TYPE_CHECKING, TypeAlias

from albot2d.errors import InputError

if TYPE_CHECKING:
    # argparse names the type of ``add_subparsers()``'s result only privately
    Subcommands: TypeAlias = argparse._SubParsersAction[argparse.ArgumentParser]

__all__ = [
    "ParamValue",
    "Subcommands",
    "parse_param",
    "positive_int",
    "positive_number",
    "seed_value",
    "world_params",
]

#: A ``--param NAME=VALUE`` value, as ``parse_param`` reads it.
ParamValue: TypeAlias = int | float | bool | str


def positive_number(text: str | None, option: str, *, allow_zero: bool = False) -> float | None:
    """A finite number > 0 (or ≥ 0 with ``allow_zero``); ``None`` passes through."""
    if text is None:
        return None
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and (value > 0 or (allow_zero and value == 0))):
        kind = "non-negative" if allow_zero else "positive"
        raise InputError(f"{option} must be a {kind} number, got {text!r}")
    return value


def positive_int(text: str | None, option: str, *, allow_zero: bool = False) -> int | None:
    """An integer > 0 (or ≥ 0 with ``allow_zero``); ``None`` passes through."""
    if text is None:
        return None
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value < 0 or (value == 0 and not allow_zero):
        kind = "non-negative" if allow_zero else "positive"
        raise InputError(f"{option} must be a {kind} integer, got {text!r}")
    return value


def seed_value(text: str | None, option: str = "--seed") -> int | None:
    """A non-negative integer seed; ``None`` passes through."""
    if text is None:
        return None
    try:
        seed = int(text)
    except ValueError:
        seed = -1
    if seed < 0:
        raise InputError(f"{option} must be a non-negative integer, got {text!r}")
    return seed


def parse_param(text: str) -> tuple[str, ParamValue]:
    """``NAME=VALUE`` → (name, value); the value becomes an int, float, bool or string."""
    name, sep, raw = text.partition("=")
    name = name.strip()
    if not sep or not name:
        raise InputError(f"--param expects NAME=VALUE, got {text!r}")
    if not name.isidentifier():
        # A dotted name is a mapper's option (e.g. triangulation.position_endpoint), which
        # --param (the world generator's) cannot set: say where it goes instead.
        raise InputError(
            f"--param {text!r}: {name!r} is not a world generator parameter name; "
            "mapper options go in --mapper 'albot1[KEY=VALUE]'"
        )
    raw = raw.strip()
    for convert in (int, float):
        try:
            return name, convert(raw)
        except ValueError:
            pass
    if raw.lower() in ("true", "false"):
        return name, raw.lower() == "true"
    return name, raw


def world_params(args: argparse.Namespace) -> dict[str, ParamValue]:
    """Generator parameters from ``--param NAME=VALUE`` and ``--width``/``--height``."""
    params: dict[str, ParamValue] = {}
    for text in getattr(args, "param", None) or []:
        name, value = parse_param(text)
        if name in params:
            raise InputError(f"--param {name} given twice")
        params[name] = value
    for option, name in (("--width", "width_m"), ("--height", "height_m")):
        size = positive_number(getattr(args, option[2:]), option)
        if size is not None:
            if name in params:
                raise InputError(f"give {option} or --param {name}, not both")
            params[name] = size
    return params
