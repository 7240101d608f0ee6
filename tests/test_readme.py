"""The README and the guides in docs/ work as written: their Python blocks run, and their
commands run without a single warning (``-W error``), shortened where they would take
minutes."""

from __future__ import annotations

import re
import shlex
import shutil
import sys
import warnings
from pathlib import Path

import pytest

from albot2d.cli import main

ROOT = Path(__file__).resolve().parents[1]
# The README first (its commands draw figures), then every guide in docs/.
DOCUMENTS = {
    path.relative_to(ROOT).as_posix(): path.read_text(encoding="utf-8")
    for path in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
}
SHARED_DATA = ROOT.parent / "shared" / "data"
SKIP_MARK = "<!-- not run by tests/test_readme.py"
_BLOCK = re.compile(r"(<!--[^\n]*-->\n)?```(\w+)\n(.*?)```", re.DOTALL)
_PLACEHOLDER = re.compile(r"^[A-Z][A-Z0-9_]*$|[\[\]|…]|\.\.\.")


def python_blocks() -> list[tuple[int, str, str | None]]:
    """(file:line, code, reason to skip) of every ```python block."""
    out = []
    for name, text in DOCUMENTS.items():
        for m in _BLOCK.finditer(text):
            if m.group(2) != "python":
                continue
            line = text[: m.start(3)].count("\n") + 1
            skip = m.group(1) if m.group(1) and m.group(1).startswith(SKIP_MARK) else None
            out.append((f"{name}:{line}", m.group(3), skip))
    return out


def readme_commands() -> list[str]:
    """Every complete ``albot2d …`` command in the README and docs/ (bash blocks and inline
    code), without the usage synopses (those with placeholders such as DIR or [--option])."""
    found = []
    for text in DOCUMENTS.values():
        for m in _BLOCK.finditer(text):
            if m.group(2) == "bash":
                lines = m.group(3).replace("\\\n", " ").splitlines()  # continuation lines joined
                found += [line.split("#")[0].strip() for line in lines]
        found += [" ".join(c.split()) for c in re.findall(r"`((?:\w+=\S+ )?albot2d [^`]+)`", text)]
    commands = []
    for text in found:
        words = shlex.split(text)
        words = words[1:] if words and "=" in words[0] else words  # ENV=value albot2d …
        if not words or words[0] != "albot2d":
            continue
        if any(_PLACEHOLDER.search(w) for w in words[1:]) or text in commands:
            continue
        if len(words) == 2 and not words[1].startswith("-"):
            continue  # `albot2d run` named in the text, not a command to type
        commands.append(text)
    return commands


def shortened(words: list[str], drawn: set[str]) -> list[str] | None:
    """The command made quick (fewer frames or episodes; figures only the first time a
    command runs), or None to leave it out."""
    command = words[0]
    if command in drawn and command in ("run", "replay", "fuzz"):
        words = [*words, "--no-figures"]
    drawn.add(command)
    if command == "experiments":
        return None  # minutes even when quick: tests/test_experiments_cli.py runs --quick
    if command == "fuzz":
        if "--backend" in words:
            return None  # needs a dask cluster
        k = words.index("--episodes")
        return [*words[: k + 1], "1", *words[k + 2 :], "--workers", "1"]
    if command in ("run", "simulate", "replay") and "--max-frames" not in words:
        return [*words, "--max-frames", "60" if command == "replay" else "40"]
    return words


@pytest.mark.parametrize(("where", "code", "skip"), python_blocks(),
                         ids=[b[0] for b in python_blocks()])  # fmt: skip
def test_python_block_runs(
    where: str, code: str, skip: str | None, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    if skip:
        pytest.skip(skip.strip())
    monkeypatch.chdir(tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        exec(compile(code, where, "exec"), {"__name__": "__readme__"})


def test_the_readme_has_a_library_example_and_commands() -> None:
    assert any("Simulator(" in code and "observe(" in code for _, code, _ in python_blocks())
    commands = readme_commands()
    for expected in (
        "albot2d run --out out/",
        "albot2d simulate --kind rooms --seed 1 --profile dataset3 --max-frames 200 --out sim1/",
        "albot2d world --kind office --seed 3 --out office.json --png office.png",
    ):
        assert expected in commands


def test_readme_commands_run_without_warnings(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr(sys, "path", list(sys.path))  # main() adds the cwd for plugins
    ran: list[str] = []
    drawn: set[str] = set()
    for k, text in enumerate(readme_commands()):
        folder = tmp_path / f"command{k}"  # each in a fresh folder, as a new user would
        folder.mkdir()
        shutil.copy(ROOT / "docs" / "mapper_template.py", folder)
        monkeypatch.chdir(folder)
        words = shlex.split(text)
        env = {}
        if "=" in words[0]:
            name, _, _ = words.pop(0).partition("=")
            if not SHARED_DATA.is_dir():
                continue  # the real log is not here (see tests/conftest.py's shared_data)
            env[name] = str(SHARED_DATA)
        args = shortened(words[1:], drawn)
        if args is None:
            continue
        with monkeypatch.context() as m:
            for name, value in env.items():
                m.setenv(name, value)
            with warnings.catch_warnings():
                warnings.simplefilter("error")
                code = main(args)
        out = capsys.readouterr()
        assert code == 0, f"{text}: exit {code}\n{out.err}"
        assert "Warning" not in out.err, f"{text}:\n{out.err}"
        ran.append(args[0])
    assert {"run", "simulate", "world", "fuzz"} <= set(ran)
