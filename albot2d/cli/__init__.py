"""The ``albot2d`` command line: one module per subcommand, each with ``register(subparsers)``.

User errors (``InputError``, missing or unwritable files, a bad environment variable)
print one line and exit 2, with no traceback and no partial output file. SIGTERM is
handled like Ctrl-C (exit 130, everything cleaned up). Output piped into a reader that
stops early (``albot2d run --out D | head -1``) ends quietly with exit 0, as Unix tools
do. ``albot2d`` alone prints the help; ``albot2d --version`` the version. Help texts are
the modules' docstrings without their reStructuredText markup.
"""

from __future__ import annotations

import argparse
import os
import re
import sys
from collections.abc import Sequence
from typing import NoReturn

from albot2d.compiled import kernels
from albot2d.errors import InputError

__all__ = ["build_parser", "main", "plain_text"]

_RST_LITERAL = re.compile(r"``(.+?)``", re.DOTALL)


def _command_modules() -> list:
    """The subcommand modules, in the order ``--help`` lists them."""
    import importlib

    names = ["world_cmd", "simulate_cmd", "run_cmd", "replay_cmd", "fuzz_cmd", "experiments_cmd"]
    return [importlib.import_module(f"albot2d.cli.{name}") for name in names]


def plain_text(text: str | None) -> str | None:
    """A docstring as terminal text: ````--out DIR```` → ``--out DIR``."""
    return None if text is None else _RST_LITERAL.sub(r"\1", text)


class _Parser(argparse.ArgumentParser):
    """argparse with usage errors on one line (like every other error) and exit code 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    from albot2d import __version__

    parser = _Parser(
        prog="albot2d",
        description="2D robot simulator and the Albot1 view-based cognitive mapper.",
        epilog="Run `albot2d COMMAND --help` for a command's options. Real logs: see "
        "`albot2d replay --help` (ALBOT2D_DATA).",
    )
    parser.add_argument("--version", action="version", version=f"albot2d {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for module in _command_modules():
        module.register(sub)
    for command in sub.choices.values():
        command.description = plain_text(command.description)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help, --version, a usage error: return its status
        return exc.code if isinstance(exc.code, int) else 2
    if args.command is None:
        parser.print_help()
        return 0
    from albot2d.cli.environment import check_environment, sigterm_as_interrupt

    try:
        kernels()  # the environment is input too: a bad ALBOT2D_KERNELS fails before any work
        check_environment(args.command)
        with sigterm_as_interrupt():
            status = int(args.handler(args) or 0)
        sys.stdout.flush()  # a closed pipe shows here, not at exit after main returned
        return status
    except BrokenPipeError:
        _quiet_closed_stdout()
        return 0
    except InputError as exc:
        print(f"albot2d {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        where = f"{exc.filename}: " if getattr(exc, "filename", None) else ""
        print(f"albot2d {args.command}: error: {where}{exc.strerror or exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"albot2d {args.command}: interrupted", file=sys.stderr)
        return 130
    except SystemError as exc:
        if not _interrupted(exc):
            raise
        print(f"albot2d {args.command}: interrupted", file=sys.stderr)
        return 130


def _interrupted(exc: BaseException) -> bool:
    """Whether ``exc`` is a Ctrl-C (or SIGTERM) in disguise: an interrupt that arrived
    while a compiled kernel was being called comes out of numba's dispatcher as a
    ``SystemError`` ("returned a result with an exception set") caused by it."""
    seen: set[int] = set()
    cause: BaseException | None = exc
    while cause is not None and id(cause) not in seen:
        if isinstance(cause, KeyboardInterrupt):
            return True
        seen.add(id(cause))
        cause = cause.__cause__ or cause.__context__
    return False


def _quiet_closed_stdout() -> None:
    """The reader of stdout went away: the output it wanted has been read, so stop as
    ``head`` expects (exit 0, nothing on stderr). Python flushes stdout once more at exit,
    which would fail again on the closed pipe; stdout is pointed at /dev/null first (the
    recipe of Python's signal documentation)."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError):  # stdout without a file descriptor (a test's capture)
        pass


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
