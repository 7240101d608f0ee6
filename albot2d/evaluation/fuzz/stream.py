"""A campaign's episode stream, ``episodes.jsonl``: one JSON record per line, each on disk
before the next episode's (``EpisodeLog``); reading it back (``read_episodes``) leaves out
a tail cut off by a killed writer and names the line of any other damage."""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from albot2d.errors import InputError

__all__ = ["STATUSES", "EpisodeLog", "read_episodes", "scan_episodes"]

#: An episode record's ``status``.
STATUSES = ("ok", "violation", "crash")


def scan_episodes(path: Path) -> tuple[list[tuple[int, dict[str, Any]]], int, int]:
    """(line number, record) of every whole line, the byte length of the whole part and the
    number of bytes after it (a damaged tail: a line cut off by a killed writer, or the
    zero bytes a crash can leave at the end of a file). Anything else that is not an
    episode record, or an episode twice, is an error naming the line."""
    data = path.read_bytes()
    # Whole lines end with a newline; a writer that was killed leaves at most a cut-off
    # last line. Lines of zero bytes at the end are left by a crash of the machine.
    keep = data.rfind(b"\n") + 1
    while keep > 0:
        previous = data.rfind(b"\n", 0, keep - 1) + 1
        if data[previous:keep].strip(b"\x00\n"):
            break
        keep = previous
    records: list[tuple[int, dict[str, Any]]] = []
    lines_of: dict[int, int] = {}
    for number, line in enumerate(data[:keep].split(b"\n")[:-1], start=1):
        if not line.strip():
            continue
        try:
            record = json.loads(line)
        except ValueError:
            record = None
        index = record.get("episode") if isinstance(record, dict) else None
        if (
            not isinstance(index, int)
            or isinstance(index, bool)
            or index < 0
            or record.get("status") not in STATUSES
        ):
            raise InputError(
                f"{path}:{number}: not an episode record; the file is damaged "
                "(move it away to start afresh)"
            )
        if index in lines_of:
            raise InputError(
                f"{path}:{number}: episode {index} again (first on line "
                f"{lines_of[index]}); the file is damaged (two writers?)"
            )
        lines_of[index] = number
        records.append((number, record))
    return records, keep, len(data) - keep


def read_episodes(path: str | os.PathLike[str]) -> tuple[dict[int, dict[str, Any]], int]:
    """The episode records in an ``episodes.jsonl`` and the byte length of its whole part.

    A damaged tail (a last line cut off by a killed writer) is left out, to be redone; a
    broken line anywhere else, or an episode twice, is an error naming the line.
    """
    p = Path(path)
    if not p.exists():
        return {}, 0
    records, keep, _ = scan_episodes(p)
    return {r["episode"]: r for _, r in records}, keep


class EpisodeLog:
    """Appends one line per episode to episodes.jsonl, on disk before the next."""

    def __init__(self, path: Path, keep_bytes: int) -> None:
        self._file = open(path, "ab")  # noqa: SIM115 (closed in close())
        self._file.truncate(keep_bytes)  # drop a line cut off by an interruption
        self._file.seek(keep_bytes)

    def write(self, record: Mapping[str, Any]) -> None:
        line = json.dumps(record, allow_nan=False, separators=(",", ":")) + "\n"
        self._file.write(line.encode("utf-8"))
        self._file.flush()
        os.fsync(self._file.fileno())

    def close(self) -> None:
        self._file.close()
