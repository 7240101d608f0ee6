"""A campaign's episode stream, ``episodes.jsonl``: one JSON record per line, each on disk
before the next episode's (``EpisodeLog``); reading it back (``read_episodes``) leaves out
a tail cut off by a killed writer and names the line of any other damage."""

from __future__ import annotations

import json
import os
from pathlib import Path

from albot2d.errors import InputError
from albot2d.evaluation.fuzz.files import check_episode_record
from albot2d.evaluation.fuzz.record import STATUSES, EpisodeRecord
from albot2d.inputfiles import binary_lines
from albot2d.limits import MAX_CAMPAIGN_EPISODES, MAX_EPISODE_RECORD_BYTES
from albot2d.validation import parse_json

__all__ = ["STATUSES", "EpisodeLog", "read_episodes", "scan_episodes"]


def scan_episodes(path: Path) -> tuple[list[tuple[int, EpisodeRecord]], int, int]:
    """(line number, record) of every whole line, the byte length of the whole part and the
    number of bytes after it (a damaged tail: a line cut off by a killed writer, or the
    zero bytes a crash can leave at the end of a file). Anything else that is not an
    episode record (``files.check_episode_record``), an episode twice, a line
    longer than ``MAX_EPISODE_RECORD_BYTES`` or more than ``MAX_CAMPAIGN_EPISODES`` lines
    is an error naming the line. Streamed: the file is never read whole."""
    records: list[tuple[int, EpisodeRecord]] = []
    lines_of: dict[int, int] = {}
    keep = offset = 0
    zero_lines: list[int] = []  # lines of zero bytes not (yet) known to be at the end
    source = str(path)
    with open(path, "rb") as handle:
        lines = binary_lines(
            handle,
            source,
            max_line_bytes=MAX_EPISODE_RECORD_BYTES,
            max_total_bytes=(MAX_CAMPAIGN_EPISODES + 1) * MAX_EPISODE_RECORD_BYTES,
            line_limit_name="MAX_EPISODE_RECORD_BYTES",
            total_limit_name="MAX_CAMPAIGN_EPISODES lines of MAX_EPISODE_RECORD_BYTES",
        )
        for number, line in enumerate(lines, start=1):
            offset += len(line)
            if not line.endswith(b"\n"):
                break  # a last line cut off by a killed writer: the damaged tail
            if not line.strip():
                continue  # a blank line
            if not line.strip(b"\x00 \t\r\n"):
                zero_lines.append(number)
                continue
            if zero_lines:  # zero bytes followed by a record: damage, not a tail
                number = zero_lines[0]
                raise InputError(
                    f"{path}:{number}: not an episode record; the file is damaged "
                    "(move it away to start afresh)"
                )
            keep = offset
            if len(records) >= MAX_CAMPAIGN_EPISODES:
                raise InputError(
                    f"{path}:{number}: more than {MAX_CAMPAIGN_EPISODES} episode records, the "
                    "limit (MAX_CAMPAIGN_EPISODES)"
                )
            where = f"{path}:{number}"
            try:
                data = check_episode_record(parse_json(line.decode("utf-8"), where), where)
                record = EpisodeRecord.from_json(data, where)
            except (InputError, UnicodeDecodeError) as exc:
                raise InputError(
                    f"{where}: not an episode record ({str(exc).removeprefix(where + ': ')}); "
                    "the file is damaged (move it away to start afresh)"
                ) from None
            index = record.episode
            if index in lines_of:
                raise InputError(
                    f"{path}:{number}: episode {index} again (first on line "
                    f"{lines_of[index]}); the file is damaged (two writers?)"
                )
            lines_of[index] = number
            records.append((number, record))
    size = path.stat().st_size
    return records, keep, max(size - keep, 0)


def read_episodes(path: str | os.PathLike[str]) -> tuple[dict[int, EpisodeRecord], int]:
    """The episode records in an ``episodes.jsonl`` and the byte length of its whole part.

    A damaged tail (a last line cut off by a killed writer) is left out, to be redone; a
    broken line anywhere else, or an episode twice, is an error naming the line.
    """
    p = Path(path)
    if not p.exists():
        return {}, 0
    records, keep, _ = scan_episodes(p)
    return {r.episode: r for _, r in records}, keep


class EpisodeLog:
    """Appends one line per episode to episodes.jsonl, on disk before the next."""

    def __init__(self, path: Path, keep_bytes: int) -> None:
        self._file = open(path, "ab")  # noqa: SIM115 (closed in close())
        self._file.truncate(keep_bytes)  # drop a line cut off by an interruption
        self._file.seek(keep_bytes)

    def write(self, record: EpisodeRecord) -> None:
        line = json.dumps(record.to_json(), allow_nan=False, separators=(",", ":")) + "\n"
        self._file.write(line.encode("utf-8"))
        self._file.flush()
        os.fsync(self._file.fileno())

    def close(self) -> None:
        self._file.close()
