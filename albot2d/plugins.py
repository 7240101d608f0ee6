"""User code loaded by name (``--mapper module:Class``): found by file location, behind a guard.

- :func:`import_plugin` imports a plugin's module. It is looked for where it was found
  before (in this process or the one that started it, see below), then on ``sys.path``,
  then in the current folder, without ever putting the current folder on ``sys.path``
  (which would make every worker process import whatever ``albot2d`` folder lies there
  instead of the installed package). Where the current folder supplied it, its location
  is recorded in the environment variable :data:`PLUGINS_ENV` (a JSON object, module →
  folder), which worker processes inherit and use to import the very same file.
- Any exception while importing (``SyntaxError``, ``RuntimeError``, ``SystemExit`` from a
  ``sys.exit`` at import, ...) becomes one :class:`~albot2d.errors.InputError` naming the
  plugin and the exception; :class:`PluginFactory` does the same for the constructor.
  Only ``KeyboardInterrupt`` passes through (the user stopped the program).
"""

from __future__ import annotations

import importlib
import importlib.util
import json
import os
import sys
from importlib.machinery import PathFinder
from types import ModuleType
from typing import Any

from albot2d.errors import InputError

__all__ = ["PLUGINS_ENV", "PluginFactory", "import_plugin", "plugin_locations"]

#: Environment variable: JSON object {top-level module name: absolute folder}.
PLUGINS_ENV = "ALBOT2D_PLUGINS"
_MAX_ENV_CHARS = 65_536


def _one_line(exc: BaseException) -> str:
    if isinstance(exc, SystemExit):
        return f"SystemExit({exc.code!r}): the plugin called sys.exit"
    text = " ".join(str(exc).split())
    if len(text) > 200:
        text = text[:197] + "..."
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def plugin_locations() -> dict[str, str]:
    """The plugin folders recorded in :data:`PLUGINS_ENV` (checked: a bad value is an
    ``InputError`` naming the variable)."""
    text = os.environ.get(PLUGINS_ENV)
    if not text:
        return {}
    problem = f"environment variable {PLUGINS_ENV}: expected a JSON object of module: folder"
    if len(text) > _MAX_ENV_CHARS:
        raise InputError(f"{problem}, got {len(text)} characters")
    try:
        value = json.loads(text)
    except (ValueError, RecursionError):
        raise InputError(f"{problem}, got {text[:60]!r}") from None
    if not isinstance(value, dict) or not all(
        isinstance(k, str) and k.isidentifier() and isinstance(v, str) and os.path.isabs(v)
        for k, v in value.items()
    ):
        raise InputError(f"{problem} (absolute paths), got {text[:60]!r}")
    return value


def _record(top: str, folder: str) -> None:
    locations = plugin_locations()
    locations[top] = folder
    os.environ[PLUGINS_ENV] = json.dumps(locations, sort_keys=True)


def _load_from(top: str, folder: str) -> ModuleType | None:
    """Import the top-level module or package ``top`` from ``folder`` (``None``: not there)."""
    spec = PathFinder.find_spec(top, [folder])
    if spec is None or spec.loader is None:
        return None  # absent, or a bare folder (a namespace package) that is not code
    module = importlib.util.module_from_spec(spec)
    sys.modules[top] = module
    try:
        spec.loader.exec_module(module)
    except BaseException:
        sys.modules.pop(top, None)
        raise
    return module


def _loaded_where_recorded(top: str) -> bool:
    recorded = plugin_locations().get(top)
    return recorded is not None and _load_from(top, recorded) is not None


def _import(name: str) -> ModuleType:
    top = name.partition(".")[0]
    # Where the starting process found it; else on sys.path; else in the current folder.
    if top in sys.modules or _loaded_where_recorded(top):
        return importlib.import_module(name)
    if importlib.util.find_spec(top) is None:
        cwd = os.getcwd()
        if _load_from(top, cwd) is None:
            raise ImportError(f"no module named {top!r} on sys.path or in {cwd}")
        _record(top, cwd)
    return importlib.import_module(name)


def import_plugin(name: str, what: str) -> ModuleType:
    """Import module ``name`` of a plugin (``what`` names it in errors, e.g. ``mapper
    'm:C'``); any failure is one ``InputError``."""
    if not all(part.isidentifier() for part in name.split(".")):
        raise InputError(f"{what}: {name!r} is not a module name")
    try:
        return _import(name)
    except KeyboardInterrupt:
        raise
    except InputError:
        raise
    except ImportError as exc:
        raise InputError(f"{what}: cannot import module {name!r}: {_one_line(exc)}") from None
    except BaseException as exc:
        raise InputError(f"{what}: importing module {name!r} failed: {_one_line(exc)}") from None


class PluginFactory:
    """Makes a plugin's object (``cls()``); any exception while constructing, ``SystemExit``
    included, is one ``InputError`` naming the plugin. ``name`` is the class's ``name``."""

    def __init__(self, spec: str, cls: Any) -> None:
        self.spec = spec
        self.cls = cls
        self.name = getattr(cls, "name", None)

    def __call__(self) -> Any:
        try:
            return self.cls()
        except KeyboardInterrupt:
            raise
        except BaseException as exc:
            raise InputError(
                f"mapper {self.spec!r}: constructing {getattr(self.cls, '__name__', 'it')} "
                f"failed: {_one_line(exc)}"
            ) from None

    def __repr__(self) -> str:
        return f"PluginFactory({self.spec!r})"
