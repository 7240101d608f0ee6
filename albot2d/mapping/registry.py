"""Mapper names → factories, and user mappers given as ``module:Class``.

Every factory takes no arguments and returns a fresh object that implements the mapper
protocol. Built-in names: ``albot1``, ``naive``, ``truth`` (simulation only) and
``slam`` (loop-closing SLAM) and ``scan_odometry`` (its scan-matching front end alone),
when the ``[slam]`` extra is installed.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable

from albot2d.errors import InputError
from albot2d.mapping.protocol import Mapper

__all__ = [
    "BUILTIN_MAPPERS",
    "albot1_option_keys",
    "mapper_factory",
    "report_name",
    "resolve_mappers",
]


def _albot1() -> Mapper:
    from albot2d.mapping.albot1.mapper import Albot1

    return Albot1()


def _naive() -> Mapper:
    from albot2d.mapping.baselines import NaiveIntegration

    return NaiveIntegration()


def _truth() -> Mapper:
    from albot2d.mapping.baselines import GroundTruthIntegration

    return GroundTruthIntegration()


def _slam() -> Mapper:
    from albot2d.mapping.slam import LoopClosingSLAM

    return LoopClosingSLAM()


def _scan_odometry() -> Mapper:
    from albot2d.mapping.slam import ScanMatchingSLAM

    return ScanMatchingSLAM()


BUILTIN_MAPPERS: dict[str, Callable[[], Mapper]] = {
    "albot1": _albot1,
    "naive": _naive,
    "truth": _truth,
    "slam": _slam,
    "scan_odometry": _scan_odometry,
}

_REQUIRED = ("observe", "pose", "global_map", "trajectory", "counts", "timings_ms")


_ALBOT1_OPTIONS = (
    "preset",
    "deletion",
    "min_tracked",
    "position_endpoint",
    "match_candidates",
)


def albot1_option_keys() -> tuple[str, ...]:
    """The keys ``albot1[KEY=VALUE,...]`` accepts."""
    return _ALBOT1_OPTIONS


def _albot1_variant(spec: str) -> Callable[[], Mapper]:
    """``albot1[preset=original,deletion=v1,min_tracked=3,position_endpoint=current_real]``:
    Albot1 with named options, so readings of the paper can be compared side by side in
    one run."""
    body = spec[len("albot1[") : -1]
    options: dict[str, str] = {}
    for item in filter(None, (part.strip() for part in body.split(","))):
        key, eq, value = item.partition("=")
        if not eq or key.strip() not in _ALBOT1_OPTIONS:
            raise InputError(
                f"mapper {spec!r}: options are key=value with keys {', '.join(_ALBOT1_OPTIONS)}"
            )
        options[key.strip()] = value.strip()
    from albot2d.mapping.albot1.deletion import GlobalMapParams
    from albot2d.mapping.albot1.mapper import Albot1, Albot1Params

    overrides: dict[str, object] = {}
    if "deletion" in options:
        overrides["global_map"] = GlobalMapParams.preset(options["deletion"])
    if "min_tracked" in options:
        try:
            overrides["min_tracked"] = int(options["min_tracked"])
        except ValueError:
            raise InputError(
                f"mapper {spec!r}: min_tracked must be an integer, got {options['min_tracked']!r}"
            ) from None
    params = Albot1Params.preset(options.get("preset", "paper"), **overrides)
    # options of a nested parameter group: (option, group field of Albot1Params)
    for option, group in (("position_endpoint", "triangulation"), ("match_candidates", "tracking")):
        if option in options:
            import dataclasses

            inner = dataclasses.replace(getattr(params, group), **{option: options[option]})
            params = dataclasses.replace(params, **{group: inner})

    def make() -> Mapper:
        mapper = Albot1(params)
        mapper.name = spec
        return mapper

    return make


def mapper_factory(spec: str) -> Callable[[], Mapper]:
    """A factory for a built-in name, ``albot1[key=value,…]`` or a ``module:Class`` that
    implements the protocol."""
    if spec in BUILTIN_MAPPERS:
        return BUILTIN_MAPPERS[spec]
    if spec.startswith("albot1[") and spec.endswith("]"):
        return _albot1_variant(spec)
    if ":" not in spec:
        raise InputError(
            f"unknown mapper {spec!r}; built-in mappers: {', '.join(sorted(BUILTIN_MAPPERS))}; "
            "or give your own as module:Class"
        )
    module_name, _, attr = spec.partition(":")
    try:
        module = importlib.import_module(module_name)
    except ImportError as exc:
        raise InputError(f"mapper {spec!r}: cannot import module {module_name!r}: {exc}") from exc
    cls = getattr(module, attr, None)
    if cls is None or not callable(cls):
        raise InputError(f"mapper {spec!r}: module {module_name!r} has no class {attr!r}")
    missing = [name for name in _REQUIRED if not callable(getattr(cls, name, None))]
    if missing:
        raise InputError(
            f"mapper {spec!r} does not implement the mapper protocol: missing {', '.join(missing)}"
        )
    return cls


def report_name(spec: str, factory: Callable[[], Mapper]) -> str:
    """The name a mapper is reported under: a built-in's name, else the class's ``name``
    attribute when it is a non-empty string, else the class name."""
    if spec in BUILTIN_MAPPERS or spec.startswith("albot1["):
        return spec
    name = getattr(factory, "name", None)
    return name if isinstance(name, str) and name else spec.partition(":")[2]


def resolve_mappers(specs: list[str]) -> dict[str, Callable[[], Mapper]]:
    """Factories keyed by report name (a built-in name, or a plugin's ``name``)."""
    out: dict[str, Callable[[], Mapper]] = {}
    for spec in specs:
        factory = mapper_factory(spec)
        name = report_name(spec, factory)
        if name in out:
            raise InputError(f"mapper {name!r} given twice")
        out[name] = factory
    return out
