"""Shared pieces of the bad-input corpus (``tests/test_bad_*.py``): the refusal check and
the one-change mutations of the valid inputs in ``tests/bad_inputs.py``."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from albot2d.cli import main
from tests import bad_inputs as bi

__all__ = [
    "frame_line",
    "nothing_written",
    "obstacle",
    "refused",
    "replace_text",
    "set_field",
    "write_log",
]


def refused(capsys: pytest.CaptureFixture[str], argv: list[str], *expected: str) -> str:
    """Run the CLI; assert exit 2 and one stderr line holding every ``expected`` text."""
    code = main(argv)
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert code == 2, captured.err
    assert len(lines) == 1, captured.err
    assert "Traceback" not in captured.err
    assert lines[0].startswith(f"albot2d {argv[0]}: error: ")
    for text in expected:
        assert text in lines[0], lines[0]
    return lines[0]


def nothing_written(*paths: Path) -> None:
    for path in paths:
        assert not path.exists(), path
        assert not list(path.parent.glob(f".{path.name}*")), path  # no temporary leftovers


def set_field(path: str, value: Any) -> Callable[[dict[str, Any]], None]:
    """A mutation setting the field at ``path`` (``walls.0.1``) to ``value``."""

    def mutate(doc: dict[str, Any]) -> None:
        *parents, last = path.split(".")
        target: Any = doc
        for key in parents:
            target = target[int(key)] if isinstance(target, list) else target[key]
        if isinstance(target, list):
            target[int(last)] = value
        else:
            target[last] = value

    return mutate


def obstacle(**changes: Any) -> Callable[[dict[str, Any]], None]:
    def mutate(doc: dict[str, Any]) -> None:
        doc["dynamic_obstacles"] = [bi.person(doc, **changes)]

    return mutate


def frame_line(k: int, **changes: Any) -> Callable[[list[str]], None]:
    """A mutation replacing FLASER frame ``k`` by one with ``changes``."""

    def mutate(lines: list[str]) -> None:
        lines[3 + k] = bi.flaser_line(k, **changes)

    return mutate


def replace_text(old: str, new: str, *, count: int = 1) -> Callable[[list[str]], None]:
    def mutate(lines: list[str]) -> None:
        text = "\n".join(lines).replace(old, new, count)
        lines[:] = text.split("\n")

    return mutate


def write_log(tmp_path: Path, lines: list[str]) -> Path:
    path = tmp_path / "log.clf"
    path.write_text(bi.carmen_text(lines))
    (tmp_path / "log.relations").write_text(bi.relations_text())
    return path
