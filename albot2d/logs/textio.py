"""Text file plumbing for the log formats: plain or gzip input (by magic bytes), atomic output.

Readers open files with :func:`open_text`, which looks at the first two bytes rather than the
suffix, so a gzipped log named ``.clf`` still reads. Writers use :func:`atomic_text_output`,
which gzips when the target name ends in ``.gz`` (with a fixed header timestamp, so the same
content always gives the same bytes) and renames into place only when writing succeeded.
"""

from __future__ import annotations

import contextlib
import gzip
import io
import math
import os
from collections.abc import Iterator
from pathlib import Path
from typing import TextIO

import numpy as np

from albot2d.atomic import atomic_path
from albot2d.errors import InputError

__all__ = ["GZIP_MAGIC", "atomic_text_output", "is_gzip", "open_text", "read_number_table"]

GZIP_MAGIC = b"\x1f\x8b"


def is_gzip(path: str | os.PathLike[str]) -> bool:
    """Whether ``path`` starts with the gzip magic bytes."""
    with open(path, "rb") as handle:
        return handle.read(len(GZIP_MAGIC)) == GZIP_MAGIC


@contextlib.contextmanager
def open_text(path: str | os.PathLike[str]) -> Iterator[TextIO]:
    """Open ``path`` for reading text, decompressing gzip when the magic bytes say so.

    Undecodable bytes become U+FFFD (the logs are ASCII; a stray byte then shows up as a
    non-numeric field with a file:line error instead of a decode crash). A corrupt or
    truncated gzip stream raises :class:`InputError` naming the file.
    """
    compressed = is_gzip(path)
    if compressed:
        handle: TextIO = gzip.open(path, "rt", encoding="utf-8", errors="replace")  # noqa: SIM115
    else:
        handle = open(path, encoding="utf-8", errors="replace")  # noqa: SIM115
    try:
        yield handle
    except (EOFError, gzip.BadGzipFile, OSError) as exc:
        if compressed and not isinstance(exc, FileNotFoundError):
            raise InputError(f"{path}: corrupt or truncated gzip data ({exc})") from exc
        raise
    finally:
        handle.close()


@contextlib.contextmanager
def atomic_text_output(path: str | os.PathLike[str]) -> Iterator[TextIO]:
    """Write text to ``path`` atomically; gzip-compressed when the name ends in ``.gz``."""
    target = Path(path)
    with atomic_path(target) as tmp, open(tmp, "wb") as raw:
        if target.name.endswith(".gz"):
            # filename="" and mtime=0 keep the gzip header free of run-dependent bytes.
            binary: io.BufferedWriter | gzip.GzipFile = gzip.GzipFile(
                filename="", mode="wb", fileobj=raw, mtime=0
            )
        else:
            binary = raw
        text = io.TextIOWrapper(binary, encoding="utf-8", newline="\n")
        try:
            yield text
            text.flush()
        finally:
            text.detach()
            if binary is not raw:
                binary.close()


def read_number_table(
    path: str | os.PathLike[str],
    fields: tuple[str, ...],
    what: str,
    limits: tuple[float, ...] | None = None,
) -> np.ndarray:
    """Rows of ``len(fields)`` finite numbers from a text table (plain or gzip).

    ``#`` starts a comment; blank lines are skipped. A bad line raises ``InputError``
    naming ``file:line``, the ``what`` (e.g. "relation") and the offending field.
    ``limits`` gives each field's largest magnitude (default: any finite number).
    """
    bounds = limits if limits is not None else (math.inf,) * len(fields)
    rows: list[list[float]] = []
    with open_text(path) as handle:
        for line_number, line in enumerate(handle, start=1):
            text = line.split("#", 1)[0].strip()
            if not text:
                continue
            tokens = text.split()
            if len(tokens) != len(fields):
                raise InputError(
                    f"{path}:{line_number}: {what} has {len(tokens)} fields, expected "
                    f"{len(fields)} ({' '.join(fields)})"
                )
            row = []
            for name, token, limit in zip(fields, tokens, bounds, strict=True):
                try:
                    value = float(token)
                except ValueError:
                    value = math.nan
                if not math.isfinite(value):
                    raise InputError(
                        f"{path}:{line_number}: {what} field {name} {token!r} "
                        "is not a finite number"
                    )
                if abs(value) > limit:
                    raise InputError(
                        f"{path}:{line_number}: {what} field {name} {token!r} "
                        f"is outside the limit of ±{limit:g}"
                    )
                row.append(value)
            rows.append(row)
    return np.array(rows, dtype=np.float64).reshape(-1, len(fields))
