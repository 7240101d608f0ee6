"""Mapper names → factories, and user mappers given as ``module:Class``.

A plugin's module is imported behind one guard and its class constructed behind another
(``albot2d.plugins``): any failure, ``SystemExit`` included, is one ``InputError`` naming
the plugin and the exception. Its module is found on ``sys.path`` or else in the current
folder, by file location: the current folder is never added to ``sys.path``.

Every factory takes no arguments and returns a fresh object that implements the mapper
protocol. Built-in names: ``albot1``, ``naive``, ``truth`` (simulation only) and
``slam`` (loop-closing SLAM) and ``scan_odometry`` (its scan-matching front end alone),
when the ``[slam]`` extra is installed.
"""

from __future__ import annotations

from collections.abc import Callable

from albot2d.errors import InputError
from albot2d.mapping.protocol import Mapper
from albot2d.plugins import PluginFactory, import_plugin

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


def albot1_option_keys() -> tuple[str, ...]:
    """The keys ``albot1[KEY=VALUE,...]`` accepts: ``preset``, ``deletion`` and every
    ``Albot1Params`` field (``albot1.options.option_table``)."""
    from albot2d.mapping.albot1.options import option_table

    return ("preset", "deletion", *(opt.key for opt in option_table()))


def _albot1_variant(spec: str) -> Callable[[], Mapper]:
    """``albot1[preset=paper_literal,deletion=v1,min_tracked=3,tracking.match_distance_m=0.3]``:
    Albot1 with named options (every ``Albot1Params`` field, ``mapping.albot1.options``),
    so readings of the paper can be compared side by side in one run."""
    from albot2d.mapping.albot1.mapper import Albot1
    from albot2d.mapping.albot1.options import albot1_params_from_spec

    params = albot1_params_from_spec(spec, spec[len("albot1[") : -1])

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
    if not module_name or not attr:
        raise InputError(f"mapper {spec!r}: give a plugin as module:Class")
    module = import_plugin(module_name, f"mapper {spec!r}")
    cls = getattr(module, attr, None)
    if cls is None or not callable(cls):
        raise InputError(f"mapper {spec!r}: module {module_name!r} has no class {attr!r}")
    missing = [name for name in _REQUIRED if not callable(getattr(cls, name, None))]
    if missing:
        raise InputError(
            f"mapper {spec!r} does not implement the mapper protocol: missing {', '.join(missing)}"
        )
    return PluginFactory(spec, cls)


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
