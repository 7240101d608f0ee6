"""The errors albot2d raises on purpose: ``InputError`` for bad user input (the CLI turns it
into one line and exit code 2) and ``InvariantError`` for a failed invariant check (the
tests and the fuzzer record it as a violation)."""

from __future__ import annotations

__all__ = ["InputError", "InvariantError", "fail"]


class InputError(ValueError):
    """Bad user input: names the file and line, or the parameter, and the offending value."""


class InvariantError(AssertionError):
    """An invariant failed: ``invariant`` is its name (one of
    ``albot2d.evaluation.checks.INVARIANTS``)."""

    def __init__(self, invariant: str, message: str) -> None:
        super().__init__(f"{invariant}: {message}")
        self.invariant = invariant
        self.message = message


def fail(invariant: str, message: str) -> None:
    """Raise the InvariantError of ``invariant``."""
    raise InvariantError(invariant, message)
