"""World kinds: one record per kind (name, parameters class, layout function), one registry.

A kind is a module of this package that defines ``KIND = WorldKind(...)``: adding such a
file adds the kind to ``world_kinds()``, the CLI's ``--kind`` choices and ``generate``, with
nothing else to edit. A kind defined elsewhere joins with ``register_kind(WorldKind(...))``
(in the process that generates with it) or through the ``albot2d.world_kinds`` entry-point
group of an installed package (seen by every process, campaign workers included).

A layout function ``(rect, params, rng) -> Layout`` fills the rectangle ``[x0, y0, x1, y1]``
with free floor, clutter, doorways and the features the kind promises. Modules whose name
starts with ``_`` are shared building blocks, not kinds.
"""

from __future__ import annotations

import importlib
import pkgutil
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from importlib.metadata import entry_points
from types import MappingProxyType
from typing import Any

import numpy as np

from albot2d.errors import InputError
from worldgen.kinds._plan import Layout
from worldgen.params import CommonParams

__all__ = ["ENTRY_POINT_GROUP", "Layout", "WorldKind", "get_kind", "register_kind", "world_kinds"]

ENTRY_POINT_GROUP = "albot2d.world_kinds"

LayoutFunction = Callable[[np.ndarray, Any, np.random.Generator], Layout]


@dataclass(frozen=True)
class WorldKind:
    """One world kind.

    - ``name``: what ``--kind`` and ``generate(kind=...)`` call it;
    - ``params``: its parameters dataclass (a ``CommonParams``; its defaults are the kind's);
    - ``layout``: ``(rect, params, rng) -> Layout``;
    - ``summary``: one line for ``--help`` and the docs;
    - ``reports_doorways``: the world's features always list doorways (kinds with rooms).
    """

    name: str
    params: type[CommonParams]
    layout: LayoutFunction
    summary: str
    reports_doorways: bool = False

    def __post_init__(self) -> None:
        if not self.name.isidentifier():
            raise InputError(f"world kind name must be an identifier, got {self.name!r}")
        if not (isinstance(self.params, type) and issubclass(self.params, CommonParams)):
            raise InputError(f"world kind {self.name!r}: params must be a CommonParams class")
        if not callable(self.layout):
            raise InputError(f"world kind {self.name!r}: layout must be callable")


_REGISTRY: dict[str, WorldKind] = {}
_discovered = False


def register_kind(kind: WorldKind) -> WorldKind:
    """Add ``kind`` to the registry (the same record again is a no-op; another record under
    a taken name is an InputError)."""
    _discover()
    return _add(kind, where="register_kind")


def world_kinds() -> Mapping[str, WorldKind]:
    """Every known kind by name: this package's modules (by module name), then entry points
    and ``register_kind`` calls in the order they came."""
    _discover()
    return MappingProxyType(_REGISTRY)


def get_kind(name: str) -> WorldKind:
    """The kind called ``name`` (InputError naming the valid kinds otherwise)."""
    kinds = world_kinds()
    if name not in kinds:
        raise InputError(f"unknown world kind {name!r}; valid kinds: {', '.join(kinds)}")
    return kinds[name]


def _add(kind: WorldKind, *, where: str) -> WorldKind:
    if not isinstance(kind, WorldKind):
        raise InputError(f"{where}: expected a WorldKind, got {type(kind).__name__}")
    known = _REGISTRY.get(kind.name)
    if known is not None and known != kind:
        raise InputError(f"{where}: world kind {kind.name!r} is taken")
    _REGISTRY[kind.name] = kind
    return kind


def _discover() -> None:
    global _discovered
    if _discovered:
        return
    _discovered = True
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
        if info.name.startswith("_"):
            continue
        module = importlib.import_module(f"{__name__}.{info.name}")
        kind = getattr(module, "KIND", None)
        if kind is not None:
            _add(kind, where=f"{module.__name__}.KIND")
    for point in entry_points(group=ENTRY_POINT_GROUP):
        try:
            kind = point.load()
        except Exception as exc:  # a broken plugin must not stop the built-in kinds
            raise InputError(
                f"world kind entry point {point.name!r} ({point.value}) failed to load: "
                f"{type(exc).__name__}: {exc}"
            ) from None
        _add(kind, where=f"entry point {point.name!r}")
