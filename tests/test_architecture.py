"""The house's layout, checked from the source: layers import only downwards, no import
circles, matplotlib only in the viz layer, commands never import each other, and every
package says in its docstring what it owns."""

from __future__ import annotations

import ast
import collections
from pathlib import Path

import networkx as nx
import pytest

ROOT = Path(__file__).resolve().parent.parent

# Bottom up. A module may import from its own package, from any package of a lower layer,
# and nothing else (within the core layer anything; within the interface layer anything but
# the CLI).
LAYERS: tuple[frozenset[str], ...] = (
    frozenset({"albot2d", "albot2d.geometry"}),  # core helpers
    frozenset({"worldgen", "albot2d.logs"}),  # procedural worlds; recorded-data formats
    frozenset({"albot2d.sim"}),
    frozenset({"albot2d.perception"}),
    frozenset({"albot2d.mapping", "albot2d.control"}),
    frozenset({"albot2d.evaluation"}),
    frozenset({"albot2d.studies"}),
    frozenset({"albot2d.cli", "albot2d.viz", "albot2d.envs"}),  # interfaces
)
INTERFACES = LAYERS[-1]


def _modules() -> dict[str, Path]:
    found = {}
    for path in sorted([*ROOT.glob("albot2d/**/*.py"), *ROOT.glob("worldgen/**/*.py")]):
        name = ".".join(path.relative_to(ROOT).with_suffix("").parts)
        found[name.removesuffix(".__init__")] = path
    return found


MODULES = _modules()


def _target(name: str) -> str | None:
    while name and name not in MODULES:
        name = name.rpartition(".")[0]
    return name or None


def _imports(path: Path) -> list[tuple[str, int, bool]]:
    """(imported module, line, at module level) for every project import in ``path``."""
    out = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            for alias in node.names:
                full = f"{node.module}.{alias.name}"
                target = full if full in MODULES else _target(node.module)
                if target:
                    out.append((target, node.lineno, node.col_offset == 0))
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if target := _target(alias.name):
                    out.append((target, node.lineno, node.col_offset == 0))
    return out


def package_of(module: str) -> str:
    parts = module.split(".")
    if parts[0] == "worldgen":
        return "worldgen"
    if module == "albot2d.__main__":
        return "albot2d.cli"  # ``python -m albot2d`` is the CLI
    if len(parts) > 1 and (ROOT / "albot2d" / parts[1]).is_dir():
        return f"albot2d.{parts[1]}"
    return "albot2d"


def layer_of(package: str) -> int:
    for i, layer in enumerate(LAYERS):
        if package in layer:
            return i
    raise AssertionError(f"package {package} is in no layer: add it to LAYERS")


EDGES = {module: _imports(path) for module, path in MODULES.items()}


def test_every_package_is_in_a_layer() -> None:
    for module in MODULES:
        layer_of(package_of(module))


def test_layers_import_only_downwards() -> None:
    upward = []
    for module, imports in EDGES.items():
        here = package_of(module)
        for target, line, _ in imports:
            there = package_of(target)
            if here == there:
                continue
            a, b = layer_of(here), layer_of(there)
            if b < a or (a == b == 0) or (a == b and here in INTERFACES and there != "albot2d.cli"):
                continue
            upward.append(f"{MODULES[module].relative_to(ROOT)}:{line} imports {target}")
    assert upward == []


def test_no_import_circles() -> None:
    graph = nx.DiGraph()
    for module, imports in EDGES.items():
        graph.add_node(module)
        graph.add_edges_from((module, t) for t, _, _ in imports if t != module)
    circles = [sorted(c) for c in nx.strongly_connected_components(graph) if len(c) > 1]
    assert circles == []


def test_commands_never_import_each_other() -> None:
    commands = {m for m in MODULES if m.startswith("albot2d.cli.") and m.endswith("_cmd")}
    crossing = [f"{m} imports {t}" for m in commands for t, _, _ in EDGES[m] if t in commands - {m}]
    assert len(commands) >= 6 and crossing == []


def test_matplotlib_is_imported_only_in_the_viz_layer_and_lazily() -> None:
    offenders = []
    for module, path in MODULES.items():
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names = (
                [a.name for a in node.names] if isinstance(node, ast.Import)
                else [node.module or ""] if isinstance(node, ast.ImportFrom) else []
            )  # fmt: skip
            if not any(n.split(".")[0] == "matplotlib" for n in names):
                continue
            lazy = node.col_offset > 0
            if package_of(module) not in INTERFACES or not lazy:
                offenders.append(f"{path.relative_to(ROOT)}:{node.lineno}")
    assert offenders == []


def test_evaluation_is_a_handful_of_sub_packages() -> None:
    evaluation = ROOT / "albot2d" / "evaluation"
    loose = sorted(p.name for p in evaluation.glob("*.py") if p.name != "__init__.py")
    subpackages = sorted(p.name for p in evaluation.iterdir() if (p / "__init__.py").exists())
    assert loose == []
    assert subpackages == ["checks", "fuzz", "metrics", "paper", "run"]


@pytest.mark.parametrize(
    "package",
    sorted({m for m, p in MODULES.items() if p.name == "__init__.py"}),
)
def test_every_package_says_what_it_owns(package: str) -> None:
    tree = ast.parse(MODULES[package].read_text(encoding="utf-8"))
    doc = ast.get_docstring(tree)
    assert doc and len(doc.split()) >= 8, f"{package}: no docstring saying what it owns"
    names = {t.id for n in tree.body if isinstance(n, ast.Assign | ast.AnnAssign)
             for t in (n.targets if isinstance(n, ast.Assign) else [n.target])
             if isinstance(t, ast.Name)}  # fmt: skip
    assert "__all__" in names, f"{package}: no __all__"


def test_the_checker_sees_a_planted_upward_import(tmp_path: Path) -> None:
    """The checks above can fail: an upward import and a circle are found."""
    planted = tmp_path / "m.py"
    planted.write_text("import os\nfrom albot2d.evaluation.run import setup\n")
    ((target, line, top),) = _imports(planted)
    assert (target, line, top) == ("albot2d.evaluation.run.setup", 2, True)
    assert layer_of(package_of(target)) > layer_of(package_of("albot2d.sim.robot"))
    counts = collections.Counter(package_of(m) for m in MODULES)
    assert counts["albot2d.evaluation"] > 20 and counts["worldgen"] > 10
