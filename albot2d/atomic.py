"""Atomic file output: write a temporary sibling, then rename; a failure leaves no partial file."""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterable, Iterator
from pathlib import Path

__all__ = ["atomic_path", "atomic_paths", "atomic_write_bytes", "atomic_write_text"]


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success it is renamed onto ``path``."""
    target = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent or ".")
    # mkstemp makes the file private (0600); give it the permissions open() would (0666 & ~umask).
    os.fchmod(fd, 0o666 & ~_umask())
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        os.replace(tmp_path, target)
    finally:
        if tmp_path.exists():
            tmp_path.unlink()


@contextlib.contextmanager
def atomic_paths(paths: Iterable[str | os.PathLike[str]]) -> Iterator[dict[Path, Path]]:
    """Several files written together: yields ``{target: temporary path}``; on success every
    temporary is renamed onto its target, the first target last (so a manifest or report
    given first appears only when the rest is in place); on failure none appears.

    A temporary that cannot be created raises OSError naming the requested file.
    """
    with contextlib.ExitStack() as stack:
        temps: dict[Path, Path] = {}
        for path in paths:
            target = Path(path)
            try:
                temps[target] = stack.enter_context(atomic_path(target))
            except OSError as exc:  # name the requested file, not the temporary one
                raise OSError(exc.errno, exc.strerror, str(target)) from exc
        # ExitStack exits in reverse order: the first target is renamed last.
        yield temps


def atomic_write_bytes(path: str | os.PathLike[str], data: bytes) -> None:
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)


def atomic_write_text(path: str | os.PathLike[str], text: str) -> None:
    atomic_write_bytes(path, text.encode("utf-8"))
