"""Reading files from outside the process within a budget: bounded bytes, bounded lines.

Every reader of albot2d goes through here rather than ``Path.read_bytes`` or iterating a
file object, so that no input (``/dev/zero``, a gzip bomb, a single 1 GB line) is read
whole before it is refused:

- :func:`read_limited` reads at most ``limit`` bytes of a file (a larger file or an endless
  device is refused after ``limit + 1`` bytes);
- :func:`read_json_file` does that, checks UTF-8 and parses the JSON with
  :func:`albot2d.validation.parse_json` (depth, huge integers);
- :func:`binary_lines` yields the lines of a binary stream (a plain file or a
  ``gzip.GzipFile``), refusing a line or a total past its limit, and turns corrupt
  compressed data (``zlib.error``, ``EOFError``, ``gzip.BadGzipFile``) into
  :class:`~albot2d.errors.InputError`.

Limits come from :mod:`albot2d.limits`; the messages name the file and the limit.
"""

from __future__ import annotations

import gzip
import os
import zlib
from collections.abc import Callable, Iterator
from typing import Any, Protocol

from albot2d.errors import InputError
from albot2d.limits import MAX_JSON_FILE_BYTES, MAX_LINE_BYTES, MAX_TEXT_BYTES
from albot2d.validation import parse_json

__all__ = [
    "CORRUPT_DATA_ERRORS",
    "ReadsLines",
    "binary_lines",
    "format_bytes",
    "read_json_file",
    "read_limited",
]

#: What a decompressor raises on corrupt or truncated data.
CORRUPT_DATA_ERRORS: tuple[type[BaseException], ...] = (
    zlib.error,
    EOFError,
    gzip.BadGzipFile,
)


class ReadsLines(Protocol):
    """A binary stream with ``readline(size)``: a file opened ``rb``, a ``gzip.GzipFile``."""

    def readline(self, size: int = -1, /) -> bytes: ...


def format_bytes(n: int) -> str:
    """``n`` bytes for a message: ``64 MiB`` for whole mebibytes, else the number."""
    return f"{n // (1024 * 1024)} MiB" if n % (1024 * 1024) == 0 and n else f"{n} bytes"


def read_limited(path: str | os.PathLike[str], limit: int, what: str, name: str) -> bytes:
    """The bytes of ``path``, at most ``limit`` of them; more is an ``InputError`` naming the
    file, ``what`` it is and the limit's ``name`` (a constant of ``albot2d.limits``)."""
    with open(path, "rb") as handle:
        data = handle.read(limit + 1)
    if len(data) > limit:
        raise InputError(
            f"{os.fspath(path)}: {what} larger than the limit of {format_bytes(limit)} ({name})"
        )
    return data


def read_json_file(
    path: str | os.PathLike[str],
    what: str,
    *,
    limit: int = MAX_JSON_FILE_BYTES,
    name: str = "MAX_JSON_FILE_BYTES",
    object_pairs_hook: Callable[[list[tuple[str, Any]]], Any] | None = None,
) -> Any:
    """The JSON document in ``path`` (at most ``limit`` bytes of UTF-8); every failure is one
    ``InputError`` naming the file."""
    source = os.fspath(path)
    data = read_limited(path, limit, what, name)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise InputError(f"{source}: not UTF-8 text (byte {exc.start})") from None
    return parse_json(text, source, object_pairs_hook=object_pairs_hook)


def binary_lines(
    stream: ReadsLines,
    source: str,
    *,
    max_line_bytes: int = MAX_LINE_BYTES,
    max_total_bytes: int = MAX_TEXT_BYTES,
    line_limit_name: str = "MAX_LINE_BYTES",
    total_limit_name: str = "MAX_TEXT_BYTES",
) -> Iterator[bytes]:
    """The lines of ``stream`` (with their newline), never more than ``max_line_bytes`` of
    one line or ``max_total_bytes`` in all held or read; either is an ``InputError`` naming
    ``source`` (and the line) and the limit. Corrupt compressed data is an ``InputError``."""
    total = 0
    number = 0
    while True:
        try:
            line = stream.readline(max_line_bytes + 1)
        except CORRUPT_DATA_ERRORS as exc:
            raise InputError(f"{source}: corrupt or truncated gzip data ({exc})") from None
        if not line:
            return
        number += 1
        total += len(line)
        if total > max_total_bytes:
            raise InputError(
                f"{source}: more than {format_bytes(max_total_bytes)} of text (after "
                f"decompression), the limit ({total_limit_name})"
            )
        if len(line) > max_line_bytes and not (
            len(line) == max_line_bytes + 1 and line.endswith(b"\n")
        ):
            raise InputError(
                f"{source}:{number}: line longer than the limit of "
                f"{format_bytes(max_line_bytes)} ({line_limit_name})"
            )
        yield line
