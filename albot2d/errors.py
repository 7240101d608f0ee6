"""Error types for bad user input. The CLI turns these into one line and exit code 2."""

from __future__ import annotations

__all__ = ["InputError"]


class InputError(ValueError):
    """Bad user input: names the file and line, or the parameter, and the offending value."""
