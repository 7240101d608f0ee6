"""Mapper registry: built-in names, user ``module:Class`` plugins, and clear errors."""

from __future__ import annotations

import importlib.util
import sys
import textwrap
from pathlib import Path

import pytest

from albot2d.errors import InputError
from albot2d.mapping import Mapper
from albot2d.mapping.registry import BUILTIN_MAPPERS, mapper_factory, report_name, resolve_mappers


def test_builtins_build_protocol_mappers() -> None:
    for name, factory in BUILTIN_MAPPERS.items():
        extra = ("kiss_icp", "gtsam")
        if name in ("slam", "scan_odometry") and not all(map(importlib.util.find_spec, extra)):
            continue  # optional extra not installed (tests/test_slam.py covers the error)
        m = factory()
        assert isinstance(m, Mapper), name
        assert m.name == name


def test_user_plugin_by_module_and_class(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    (tmp_path / "my_mapper.py").write_text(
        textwrap.dedent(
            """
            from albot2d.mapping.baselines import NaiveIntegration

            class Mine(NaiveIntegration):
                name = "mine"

            class Broken:
                def observe(self, frame): ...
            """
        )
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    try:
        factories = resolve_mappers(["albot1", "my_mapper:Mine"])
        assert list(factories) == ["albot1", "mine"]  # the class's ``name`` attribute
        assert isinstance(factories["mine"](), Mapper)
        # A class without a usable name attribute is reported under its class name.
        unnamed = type("Unnamed", (factories["mine"].cls,), {"name": ""})  # type: ignore[attr-defined]
        assert report_name("my_mapper:Unnamed", unnamed) == "Unnamed"
        with pytest.raises(InputError, match="missing pose"):
            mapper_factory("my_mapper:Broken")
        with pytest.raises(InputError, match="no class 'Nope'"):
            mapper_factory("my_mapper:Nope")
    finally:
        sys.modules.pop("my_mapper", None)


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        (
            "albot2",
            "unknown mapper 'albot2'; built-in mappers: albot1, naive, scan_odometry, slam, truth",
        ),
        ("no_such_module_xyz:Cls", "cannot import module 'no_such_module_xyz'"),
    ],
)
def test_bad_mapper_specs(spec: str, message: str) -> None:
    with pytest.raises(InputError, match=message):
        mapper_factory(spec)


def test_duplicate_names_rejected() -> None:
    with pytest.raises(InputError, match="given twice"):
        resolve_mappers(["naive", "naive"])
