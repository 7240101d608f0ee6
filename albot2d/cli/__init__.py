"""The ``albot2d`` command line: one module per subcommand, each with ``register(subparsers)``.

User errors (``InputError``, missing or unwritable files) print one line and exit 2,
with no traceback and no partial output file.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from albot2d.errors import InputError

__all__ = ["build_parser", "main"]


def _command_modules() -> list:
    """The subcommand modules, in the order ``--help`` lists them."""
    import importlib

    names = ["world_cmd", "simulate_cmd", "run_cmd", "replay_cmd", "fuzz_cmd", "experiments_cmd"]
    return [importlib.import_module(f"albot2d.cli.{name}") for name in names]


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="albot2d",
        description="2D robot simulator and the Albot1 view-based cognitive mapper.",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for module in _command_modules():
        module.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.handler(args) or 0)
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


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
