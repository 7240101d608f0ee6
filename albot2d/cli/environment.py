"""What the command line takes from its surroundings: environment variables and signals.

:func:`check_environment` reads the environment variables albot2d acts on before a command
starts, so a bad value is one line naming the variable (exit 2) instead of a traceback
from deep inside a library: ``MPLBACKEND`` (matplotlib refuses an unknown backend when it
is imported, which the figures do), ``ALBOT2D_PLUGINS`` (plugin folders handed to worker
processes, ``albot2d.plugins``) and ``ALBOT2D_DATA`` (``replay``'s data folder).

:func:`sigterm_as_interrupt` makes SIGTERM (``kill``, a job scheduler, ``docker stop``)
behave like Ctrl-C: ``KeyboardInterrupt`` runs every clean-up a Ctrl-C runs (temporary
files removed, a campaign's lock released, worker pools shut down), where the default
action would end the process on the spot.
"""

from __future__ import annotations

import contextlib
import os
import signal
import threading
from collections.abc import Iterator
from pathlib import Path
from types import FrameType

from albot2d.errors import InputError

__all__ = ["check_environment", "sigterm_as_interrupt"]

_DATA_ENV = "ALBOT2D_DATA"


def _check_mplbackend() -> None:
    value = os.environ.get("MPLBACKEND")
    if not value:
        return
    try:
        import matplotlib  # noqa: F401  (validates MPLBACKEND as it is imported)
    except ImportError:
        return  # no matplotlib: no figures, the backend is never used
    except ValueError as exc:
        raise InputError(
            f"environment variable MPLBACKEND={value[:60]!r} is not a matplotlib backend "
            "(unset it, or set it to e.g. agg)"
        ) from exc


def _check_data_folder() -> None:
    value = os.environ.get(_DATA_ENV)
    if value and not Path(value).expanduser().is_dir():
        raise InputError(f"environment variable {_DATA_ENV}={value[:200]!r} is not a folder")


def check_environment(command: str) -> None:
    """Check the environment variables ``command`` may act on (see the module docstring)."""
    from albot2d.plugins import plugin_locations

    plugin_locations()
    _check_mplbackend()
    if command == "replay":
        _check_data_folder()


def _raise_interrupt(signum: int, frame: FrameType | None) -> None:
    raise KeyboardInterrupt


@contextlib.contextmanager
def sigterm_as_interrupt() -> Iterator[None]:
    """Within the block (main thread only), SIGTERM raises ``KeyboardInterrupt``."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGTERM, _raise_interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)
