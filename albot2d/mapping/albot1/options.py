"""``albot1[key=value,…]``: every field of ``Albot1Params`` by name, from the dataclasses.

A mapper spec ``albot1[preset=paper_literal,min_tracked=3,tracking.match_distance_m=0.3]``
names a preset (``Albot1Params.PRESETS``; default ``default``), a deletion rule
(``deletion=NAME``: ``GlobalMapParams.preset``) and any field overrides on top of them:

- a top-level field (``min_tracked``, ``move_using_pi``, …) by its name;
- a field of a parameter group as ``GROUP.FIELD`` (groups: ``extraction``, ``tracking``,
  ``triangulation``, ``deletion`` — the ``global_map`` field, so ``global_map.FIELD`` is
  the same), or by its bare name when no other group has a field of that name.

Values are parsed by the field's annotated type: ``true``/``false`` for booleans, integers,
numbers (``inf`` allowed), ``none`` where ``None`` is allowed, strings for the named
choices (each dataclass checks its own values and names the bad one). The list of keys
(``option_table``) is generated from the dataclasses, so ``--help`` cannot drift from them.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import types
import typing
from typing import Any, Literal, NamedTuple

from albot2d.errors import InputError

__all__ = ["GROUPS", "OptionKey", "albot1_params_from_spec", "option_help", "option_table"]

#: group name in ``albot1[GROUP.FIELD=…]`` → the ``Albot1Params`` field holding it
GROUPS: dict[str, str] = {
    "extraction": "extraction",
    "tracking": "tracking",
    "triangulation": "triangulation",
    "deletion": "global_map",
}
_SPECIAL = ("preset", "deletion")


class OptionKey(NamedTuple):
    """One settable key: ``group`` is the ``Albot1Params`` field of its group (``""`` for a
    top-level field), ``type_text`` its annotated type, ``default`` its default value."""

    key: str
    group: str
    field: str
    annotation: Any
    type_text: str
    default: Any


def _type_text(annotation: Any) -> str:
    origin = typing.get_origin(annotation)
    if origin is Literal:
        return "|".join(str(a) for a in typing.get_args(annotation))
    if origin in (typing.Union, types.UnionType):
        return " or ".join(_type_text(a) for a in typing.get_args(annotation))
    if annotation is type(None):
        return "none"
    return getattr(annotation, "__name__", str(annotation))


def _fields(cls: type) -> list[tuple[str, Any, Any]]:
    hints = typing.get_type_hints(cls)
    out = []
    for f in dataclasses.fields(cls):
        if f.default is not dataclasses.MISSING:
            default = f.default
        elif f.default_factory is not dataclasses.MISSING:
            default = f.default_factory()
        else:  # pragma: no cover - every parameter field has a default
            default = None
        out.append((f.name, hints[f.name], default))
    return out


@functools.cache
def option_table() -> tuple[OptionKey, ...]:
    """Every settable key: top-level fields first, then each group's fields as
    ``GROUP.FIELD``, in declaration order."""
    from albot2d.mapping.albot1.mapper import Albot1Params

    group_fields = set(GROUPS.values())
    keys: list[OptionKey] = []
    for name, annotation, default in _fields(Albot1Params):
        if name not in group_fields:
            keys.append(OptionKey(name, "", name, annotation, _type_text(annotation), default))
    defaults = Albot1Params()
    for group, attr in GROUPS.items():
        cls = type(getattr(defaults, attr))
        for name, annotation, default in _fields(cls):
            keys.append(
                OptionKey(f"{group}.{name}", attr, name, annotation, _type_text(annotation),
                          default)
            )  # fmt: skip
    return tuple(keys)


@functools.cache
def _lookup() -> dict[str, OptionKey]:
    """Key → option: ``GROUP.FIELD``, ``global_map.FIELD``, top-level names, and bare
    group-field names that are unambiguous."""
    table = option_table()
    out: dict[str, OptionKey] = {}
    bare: dict[str, list[OptionKey]] = {}
    for opt in table:
        out[opt.key] = opt
        if opt.group:
            out[f"{opt.group}.{opt.field}"] = opt
            bare.setdefault(opt.field, []).append(opt)
    for name, opts in bare.items():
        if len(opts) == 1 and name not in out and name not in _SPECIAL:
            out[name] = opts[0]
    return out


def _parse_value(spec: str, key: str, text: str, annotation: Any) -> Any:
    """``text`` as a value of ``annotation``; an ``InputError`` naming spec, key and text."""
    options = typing.get_args(annotation) if typing.get_origin(annotation) in (
        typing.Union, types.UnionType) else (annotation,)  # fmt: skip
    low = text.strip().lower()
    if type(None) in options and low in ("none", "null"):
        return None
    for option in options:
        if option is type(None):
            continue
        if option is bool:
            if low in ("true", "yes", "on", "1"):
                return True
            if low in ("false", "no", "off", "0"):
                return False
        elif option is int:
            try:
                return int(text)
            except ValueError:
                pass
        elif option is float:
            try:
                value = float(text)
            except ValueError:
                continue
            if not math.isnan(value):
                return value
        elif typing.get_origin(option) is Literal:
            if text in typing.get_args(option):
                return text
            raise InputError(
                f"mapper {spec!r}: {key} must be one of "
                f"{', '.join(map(str, typing.get_args(option)))}, got {text!r}"
            )
        elif option is str:
            return text
    raise InputError(f"mapper {spec!r}: {key} must be {_type_text(annotation)}, got {text!r}")


def albot1_params_from_spec(spec: str, body: str) -> Any:
    """``Albot1Params`` for the options ``body`` (``"k=v,k=v"``) of the mapper ``spec``."""
    from albot2d.mapping.albot1.deletion import GlobalMapParams
    from albot2d.mapping.albot1.mapper import Albot1Params

    lookup = _lookup()
    options: dict[str, str] = {}
    for item in filter(None, (part.strip() for part in body.split(","))):
        key, eq, value = item.partition("=")
        key = key.strip()
        if not eq:
            raise InputError(f"mapper {spec!r}: {item!r} is not key=value")
        if key not in _SPECIAL and key not in lookup:
            raise InputError(
                f"mapper {spec!r}: unknown key {key!r}; keys: preset, deletion and "
                "the Albot1Params fields (albot2d run --help lists them)"
            )
        if key in options:
            raise InputError(f"mapper {spec!r}: {key} given twice")
        options[key] = value.strip()
    try:
        params = Albot1Params.preset(options.pop("preset", "default"))
        if "deletion" in options:
            params = dataclasses.replace(
                params, global_map=GlobalMapParams.preset(options.pop("deletion"))
            )
        top: dict[str, Any] = {}
        groups: dict[str, dict[str, Any]] = {}
        for key, text in options.items():
            opt = lookup[key]
            value = _parse_value(spec, opt.key, text, opt.annotation)
            if opt.group:
                groups.setdefault(opt.group, {})[opt.field] = value
            else:
                top[opt.field] = value
        for attr, fields in groups.items():
            top[attr] = dataclasses.replace(getattr(params, attr), **fields)
        return dataclasses.replace(params, **top)
    except InputError as exc:
        message = str(exc)
        if spec in message:
            raise
        raise InputError(f"mapper {spec!r}: {message}") from None


def option_help() -> str:
    """The keys of ``albot1[...]`` with their types and defaults, for ``--help``."""
    from albot2d.mapping.albot1.deletion import DELETION_PRESETS
    from albot2d.mapping.albot1.mapper import PRESETS

    lines = [
        "albot1[KEY=VALUE,...] keys (any field of Albot1Params; a group's field also by its "
        "bare name when unique):",
        f"  preset={'|'.join(p for p in PRESETS if p != 'paper')} (default: default)",
        f"  deletion={'|'.join(DELETION_PRESETS)} (the global map's deletion rule)",
    ]
    for opt in option_table():
        default = opt.default
        if isinstance(default, float) and math.isinf(default):
            default = "inf"
        lines.append(f"  {opt.key}={opt.type_text} (default {default})")
    return "\n".join(lines)
