"""Text file plumbing for the log formats: plain or gzip input (by magic bytes), atomic output.

Readers open files with :func:`open_text`, which looks at the first two bytes rather than the
suffix, so a gzipped log named ``.clf`` still reads, and streams the lines within the limits
of ``albot2d.limits`` (line length, bytes after decompression). Writers use
:func:`atomic_text_output`, which gzips when the target name ends in ``.gz`` (with a fixed
header timestamp, so the same content always gives the same bytes) and renames into place
only when writing succeeded.
"""

from __future__ import annotations

import array
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
from albot2d.inputfiles import ReadsLines, binary_lines
from albot2d.limits import MAX_TABLE_ROWS

__all__ = ["GZIP_MAGIC", "atomic_text_output", "is_gzip", "open_text", "read_number_table"]

GZIP_MAGIC = b"\x1f\x8b"


def is_gzip(path: str | os.PathLike[str]) -> bool:
    """Whether ``path`` starts with the gzip magic bytes."""
    with open(path, "rb") as handle:
        return handle.read(len(GZIP_MAGIC)) == GZIP_MAGIC


@contextlib.contextmanager
def open_text(path: str | os.PathLike[str]) -> Iterator[Iterator[str]]:
    """The lines of ``path`` as text, decompressing gzip when the magic bytes say so.

    Streamed within a budget (``albot2d.inputfiles.binary_lines``): a line longer than
    ``MAX_LINE_BYTES`` or more than ``MAX_TEXT_BYTES`` after decompression is refused with
    an :class:`InputError` naming the file and the limit, as is corrupt or truncated gzip
    data. Undecodable bytes become U+FFFD (the logs are ASCII; a stray byte then shows up
    as a non-numeric field with a file:line error instead of a decode crash).
    """
    source = os.fspath(path)
    compressed = is_gzip(path)
    raw = open(path, "rb")  # noqa: SIM115 (closed below)
    try:
        binary: ReadsLines = gzip.GzipFile(fileobj=raw, mode="rb") if compressed else raw
        lines = binary_lines(binary, source)
        yield (line.decode("utf-8", errors="replace") for line in lines)
    finally:
        raw.close()


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


def _shown(token: str) -> str:
    """A field for a message, cut short (a field may be megabytes long)."""
    return repr(token if len(token) <= 40 else token[:37] + "...")


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
    rows = array.array("d")  # flat: 8 bytes a number, not a Python float each
    n_rows = 0
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
                        f"{path}:{line_number}: {what} field {name} {_shown(token)} "
                        "is not a finite number"
                    )
                if abs(value) > limit:
                    raise InputError(
                        f"{path}:{line_number}: {what} field {name} {_shown(token)} "
                        f"is outside the limit of ±{limit:g}"
                    )
                row.append(value)
            if n_rows >= MAX_TABLE_ROWS:
                raise InputError(
                    f"{path}:{line_number}: more than {MAX_TABLE_ROWS} {what} rows, the "
                    "limit (MAX_TABLE_ROWS)"
                )
            rows.extend(row)
            n_rows += 1
    return np.array(rows, dtype=np.float64).reshape(-1, len(fields))
