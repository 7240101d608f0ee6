"""The error every invariant check raises, shared by ``invariants``, ``deletion_invariant``
and ``sim_invariants``."""

from __future__ import annotations

__all__ = ["InvariantError", "fail"]


class InvariantError(AssertionError):
    """An invariant failed: ``invariant`` is its name (one of ``INVARIANTS``)."""

    def __init__(self, invariant: str, message: str) -> None:
        super().__init__(f"{invariant}: {message}")
        self.invariant = invariant
        self.message = message


def fail(invariant: str, message: str) -> None:
    """Raise the InvariantError of ``invariant``."""
    raise InvariantError(invariant, message)
