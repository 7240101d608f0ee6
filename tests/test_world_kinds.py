"""World kinds are records in one registry: a kind defined in another module joins the CLI's
``--kind`` choices, its help and ``generate`` with no edit anywhere else."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from albot2d.errors import InputError
from worldgen.kinds import WorldKind, get_kind, register_kind, world_kinds
from worldgen.params import OfficeParams

ROOT = Path(__file__).resolve().parent.parent

# Imports the toy kind's module, then runs the real CLI in the same process.
CLI_WITH_TOY = (
    "import sys; import tests.toy_kind; from albot2d.cli import main; sys.exit(main(sys.argv[1:]))"
)


def _cli(*argv: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", CLI_WITH_TOY, *argv],
        cwd=ROOT, capture_output=True, text=True, timeout=120, check=False,
    )  # fmt: skip


def test_a_kind_registered_from_another_module_is_listed_and_generated(tmp_path: Path) -> None:
    help_text = _cli("world", "--help")
    assert help_text.returncode == 0, help_text.stderr
    listed = " ".join(help_text.stdout.split()).split("world kind:")[1].split("--from")[0]
    assert "toy" in listed and "office" in listed
    out = tmp_path / "toy.json"
    done = _cli("world", "--kind", "toy", "--seed", "3", "--out", str(out))
    assert done.returncode == 0, done.stderr
    world = json.loads(out.read_text())
    assert world["kind"] == "toy" and world["seed"] == 3
    # the toy hall is 12 x 8 m less 0.2 m on each side: the floor is that rectangle
    exterior = world["free_space"]["exterior"]
    assert sorted(map(tuple, exterior)) == [(0.2, 0.2), (0.2, 7.8), (11.8, 0.2), (11.8, 7.8)]
    assert len(world["walls"]) == 4 and world["roadmap"]["edges"]
    run = _cli(
        "simulate", "--kind", "toy", "--max-frames", "5", "--no-png", "--out", str(tmp_path / "s")
    )
    assert run.returncode == 0, run.stderr


def test_every_builtin_kind_is_one_module_with_one_record() -> None:
    import pkgutil

    import worldgen.kinds

    modules = {m.name for m in pkgutil.iter_modules(worldgen.kinds.__path__)}
    records = {k.layout.__module__.rsplit(".", 1)[1] for k in world_kinds().values()}
    assert records == {m for m in modules if not m.startswith("_")}
    assert {"corridors", "rooms", "open", "office", "fig6", "mixed"} <= set(world_kinds())


def test_a_taken_name_and_a_malformed_record_are_refused() -> None:
    office = get_kind("office")
    assert register_kind(office) is office  # the same record again: nothing happens
    with pytest.raises(InputError, match="'office' is taken"):
        register_kind(WorldKind("office", OfficeParams, office.layout, "another office"))
    with pytest.raises(InputError, match="identifier"):
        WorldKind("two words", OfficeParams, office.layout, "x")
    with pytest.raises(InputError, match="CommonParams"):
        WorldKind("bad", dict, office.layout, "x")  # type: ignore[arg-type]
    with pytest.raises(InputError, match="unknown world kind 'maze'; valid kinds: corridors"):
        get_kind("maze")
