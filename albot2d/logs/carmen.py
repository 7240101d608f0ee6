"""CARMEN log records and a streaming reader (plain or gzip); the writer is ``carmen_writer``.

Formats are those of ``shared/data/SOURCES.md`` §1.1. :class:`CarmenReader` yields one frozen
record per data line, lazily; ``FLASER``/``RLASER`` (any beam count), ``ROBOTLASER1``, ``ODOM``,
``PARAM`` and ``NEFF`` are understood, ``#`` lines are comments, and any other message type is
skipped and counted in :attr:`CarmenReader.stats`. A malformed line raises
:class:`~albot2d.errors.InputError` as ``file:line: <message> <what is wrong>``.

Limits (``albot2d.limits``, each refused as ``file:line``): a line of at most
``MAX_LINE_BYTES``, ``MAX_TEXT_BYTES`` after decompression, ``MAX_LOG_SCANS`` laser lines
and ``MAX_LOG_READINGS`` readings in all (counted as the lines stream by); pose numbers
(headings too) within
±``COORDINATE_LIMIT_M`` (1e6), timestamps within ±:data:`TIMESTAMP_LIMIT_S`,
at most :data:`MAX_BEAMS` readings per line, ``ROBOTLASER1`` angles within a turn and its
max range within the coordinate limit. Ranges may be anything a laser writes (NaN, inf,
negative); ``albot2d.logs.anomalies`` counts those.

Pose fields keep CARMEN's meaning: ``LaserRecord.pose`` is the first pose of the line (the laser
pose; in raw logs identical to odometry) and ``odom_pose`` the second (the robot's odometry).
"""

from __future__ import annotations

import math
import os
from collections import Counter
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import TypeAlias

import numpy as np
from numpy.typing import NDArray

from albot2d.arrays import readonly
from albot2d.errors import InputError
from albot2d.geometry import Pose
from albot2d.limits import MAX_BEAMS, MAX_LOG_READINGS, MAX_LOG_SCANS
from albot2d.logs.textio import open_text
from albot2d.validation import COORDINATE_LIMIT_M

__all__ = [
    "ANGLE_LIMIT_RAD",
    "MAX_BEAMS",
    "TIMESTAMP_LIMIT_S",
    "CarmenReader",
    "CarmenStats",
    "CommentRecord",
    "LaserRecord",
    "NeffRecord",
    "OdomRecord",
    "ParamRecord",
    "Record",
    "read_carmen",
]

FloatArray = NDArray[np.float64]

#: Largest timestamp magnitude in seconds (year ~5100 in Unix time).
TIMESTAMP_LIMIT_S = 1e11
#: Largest heading or laser angle magnitude in radians (just over one turn).
ANGLE_LIMIT_RAD = 2.0 * math.pi + 1e-6

# Distinct unknown message types counted one by one in the stats.
_MAX_SKIPPED_TYPES = 256

_POSE_NAMES = ("x", "y", "theta", "odom_x", "odom_y", "odom_theta")
_STAMP_NAMES = ("ipc_timestamp", "ipc_hostname", "logger_timestamp")
_FLASER_TAIL = (*_POSE_NAMES, *_STAMP_NAMES)
_ODOM_NAMES = ("x", "y", "theta", "tv", "rv", "accel", *_STAMP_NAMES)
_ROBOTLASER_HEAD = (
    "laser_type", "start_angle", "fov", "angular_res", "max_range", "accuracy", "remission_mode",
)  # fmt: skip
_ROBOTLASER_TAIL = (
    "laser_x", "laser_y", "laser_theta", "robot_x", "robot_y", "robot_theta", "tv", "rv",
    "forward_safety_dist", "side_safety_dist", "turn_axis", *_STAMP_NAMES,
)  # fmt: skip


@dataclass(frozen=True, eq=False, slots=True)
class LaserRecord:
    """An ``FLASER``/``RLASER`` (old format) or ``ROBOTLASER1`` line.

    The ``ROBOTLASER1``-only fields are ``None`` for the old format, which records no angles.
    """

    message: str
    ranges: FloatArray
    pose: Pose
    odom_pose: Pose
    ipc_timestamp: float
    hostname: str
    logger_timestamp: float
    line_number: int = 0
    laser_type: int | None = None
    start_angle_rad: float | None = None
    fov_rad: float | None = None
    angular_resolution_rad: float | None = None
    max_range_m: float | None = None
    accuracy_m: float | None = None
    remission_mode: int | None = None
    remissions: FloatArray | None = None
    tv_mps: float | None = None
    rv_radps: float | None = None
    forward_safety_dist_m: float | None = None
    side_safety_dist_m: float | None = None
    turn_axis: float | None = None

    @property
    def n_beams(self) -> int:
        return len(self.ranges)


@dataclass(frozen=True, slots=True)
class OdomRecord:
    """An ``ODOM`` line: odometry pose and velocities."""

    pose: Pose
    tv_mps: float
    rv_radps: float
    accel_mps2: float
    ipc_timestamp: float
    hostname: str
    logger_timestamp: float
    line_number: int = 0


@dataclass(frozen=True, slots=True)
class ParamRecord:
    """A ``PARAM name value [ipc_timestamp host logger_timestamp]`` line; ``value`` is text."""

    name: str
    value: str
    ipc_timestamp: float | None = None
    hostname: str | None = None
    logger_timestamp: float | None = None
    line_number: int = 0


@dataclass(frozen=True, slots=True)
class NeffRecord:
    """A ``NEFF value`` line (gmapping's effective sample size after the previous scan)."""

    value: float
    line_number: int = 0


@dataclass(frozen=True, slots=True)
class CommentRecord:
    """A ``#`` line, text without the leading ``#``; yielded only with ``include_comments``."""

    text: str
    line_number: int = 0


Record: TypeAlias = LaserRecord | OdomRecord | ParamRecord | NeffRecord | CommentRecord


@dataclass(frozen=True)
class CarmenStats:
    """What a reader has seen so far: records per message type and skipped unknown types."""

    counts: dict[str, int] = field(default_factory=dict)
    skipped: dict[str, int] = field(default_factory=dict)
    n_lines: int = 0
    n_comments: int = 0
    n_blank: int = 0

    @property
    def n_skipped(self) -> int:
        return sum(self.skipped.values())


class _LineError(Exception):
    """A reason a line is malformed; the reader adds ``file:line``."""


_Layout = list[str | tuple[str, int]]  # field names after the type; (label, k) = k repeats


def _names(layout: _Layout, start: int, limit: int) -> list[str]:
    """Up to ``limit`` field names from position ``start`` (0 = first field after the type)."""
    names: list[str] = []
    position = 0
    for part in layout:
        label, count = (part, 1) if isinstance(part, str) else part
        first = max(start - position, 0)
        for k in range(first, min(count, first + limit - len(names))):
            names.append(label if isinstance(part, str) else f"{label} {k}")
        position += count
        if len(names) >= limit:
            break
    return names


def _count_error(context: str, tokens: list[str], expected: int, layout: _Layout) -> _LineError:
    """Field-count error naming the first missing fields, or how many are extra.

    The reader prefixes the message type; ``context`` adds e.g. the declared beam count.
    """
    got = len(tokens)
    message = f"{context} has" if context else "has"
    if got < expected:
        missing = _names(layout, got - 1, min(expected - got, 4))
        shown = ", ".join(missing) + (", ..." if expected - got > 4 else "")
        return _LineError(
            f"{message} {got} fields, expected {expected} (ends where {shown} should be)"
        )
    return _LineError(f"{message} {got} fields, expected {expected} ({got - expected} extra)")


def _cut(text: str, limit: int = 40) -> str:
    """``text`` cut to ``limit`` characters for a message (a field may be megabytes)."""
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _shown(token: str) -> str:
    return repr(_cut(token))


def _float(
    tokens: list[str], index: int, name: str, *, finite: bool = True, limit: float = math.inf
) -> float:
    try:
        value = float(tokens[index])
    except ValueError:
        raise _LineError(
            f"{name} {_shown(tokens[index])} (field {index}) is not a number"
        ) from None
    if finite and not math.isfinite(value):
        raise _LineError(f"{name} {_shown(tokens[index])} (field {index}) is not finite")
    if abs(value) > limit:
        raise _LineError(
            f"{name} {_shown(tokens[index])} (field {index}) is outside the limit of ±{limit:g}"
        )
    return value


def _stamp(tokens: list[str], index: int, name: str) -> float:
    return _float(tokens, index, name, limit=TIMESTAMP_LIMIT_S)


def _int(tokens: list[str], index: int, name: str) -> int:
    try:
        value = int(tokens[index])
    except ValueError:
        raise _LineError(
            f"{name} {_shown(tokens[index])} (field {index}) is not an integer"
        ) from None
    if value < 0:
        raise _LineError(f"{name} must be >= 0, got {value} (field {index})")
    return value


def _count(tokens: list[str], index: int, name: str) -> int:
    value = _int(tokens, index, name)
    if value > MAX_BEAMS:
        raise _LineError(f"{name} {value} (field {index}) is more than the limit of {MAX_BEAMS}")
    return value


def _floats(tokens: list[str], start: int, count: int, name: str) -> FloatArray:
    """``count`` numbers from ``start``; non-finite values are allowed (they mark no-returns)."""
    chunk = tokens[start : start + count]
    try:
        return readonly(np.array(chunk, dtype=np.float64), copy=False)
    except ValueError:
        for k, text in enumerate(chunk):
            try:
                float(text)
            except ValueError:
                raise _LineError(
                    f"{name} {k} {_shown(text)} (field {start + k}) is not a number"
                ) from None
        raise


def _pose(tokens: list[str], start: int, names: tuple[str, ...]) -> Pose:
    return Pose(*(_float(tokens, start + k, names[k], limit=COORDINATE_LIMIT_M) for k in range(3)))


def _beam_count(tokens: list[str], index: int = 1, name: str = "n") -> int:
    if len(tokens) <= index:
        raise _LineError(f"has no {name} (number of readings)")
    return _count(tokens, index, name)


def _parse_flaser(tokens: list[str], line_number: int) -> LaserRecord:
    message = tokens[0]
    n = _beam_count(tokens)
    expected = 2 + n + len(_FLASER_TAIL)
    if len(tokens) != expected:
        layout: _Layout = ["n", ("range", n), *_FLASER_TAIL]
        raise _count_error(f"with n={n}", tokens, expected, layout)
    ranges = _floats(tokens, 2, n, "range")
    tail = 2 + n
    return LaserRecord(
        message=message,
        ranges=ranges,
        pose=_pose(tokens, tail, _FLASER_TAIL[:3]),
        odom_pose=_pose(tokens, tail + 3, _FLASER_TAIL[3:6]),
        ipc_timestamp=_stamp(tokens, tail + 6, "ipc_timestamp"),
        hostname=tokens[tail + 7],
        logger_timestamp=_stamp(tokens, tail + 8, "logger_timestamp"),
        line_number=line_number,
    )


def _parse_robotlaser(tokens: list[str], line_number: int) -> LaserRecord:
    message = tokens[0]
    head = 1 + len(_ROBOTLASER_HEAD)
    n = _beam_count(tokens, head, "num_readings")
    rem_index = head + 1 + n
    if len(tokens) <= rem_index:
        layout: _Layout = [*_ROBOTLASER_HEAD, "num_readings", ("range", n), "num_remissions"]
        raise _count_error(f"with n={n}", tokens, rem_index + 1, layout)
    n_rem = _count(tokens, rem_index, "num_remissions")
    expected = rem_index + 1 + n_rem + len(_ROBOTLASER_TAIL)
    if len(tokens) != expected:
        layout = [
            *_ROBOTLASER_HEAD, "num_readings", ("range", n), "num_remissions",
            ("remission", n_rem), *_ROBOTLASER_TAIL,
        ]  # fmt: skip
        raise _count_error(f"with n={n}, n_rem={n_rem}", tokens, expected, layout)
    tail = rem_index + 1 + n_rem
    values = [_float(tokens, tail + k, _ROBOTLASER_TAIL[k]) for k in range(11)]
    for k in range(6):  # laser and robot poses
        _float(tokens, tail + k, _ROBOTLASER_TAIL[k], limit=COORDINATE_LIMIT_M)
    return LaserRecord(
        message=message,
        ranges=_floats(tokens, head + 1, n, "range"),
        pose=Pose(*values[0:3]),
        odom_pose=Pose(*values[3:6]),
        ipc_timestamp=_stamp(tokens, tail + 11, "ipc_timestamp"),
        hostname=tokens[tail + 12],
        logger_timestamp=_stamp(tokens, tail + 13, "logger_timestamp"),
        line_number=line_number,
        laser_type=_int(tokens, 1, "laser_type"),
        start_angle_rad=_float(tokens, 2, "start_angle", limit=ANGLE_LIMIT_RAD),
        fov_rad=_float(tokens, 3, "fov", limit=ANGLE_LIMIT_RAD),
        angular_resolution_rad=_float(tokens, 4, "angular_res", limit=ANGLE_LIMIT_RAD),
        max_range_m=_float(tokens, 5, "max_range", limit=COORDINATE_LIMIT_M),
        accuracy_m=_float(tokens, 6, "accuracy"),
        remission_mode=_int(tokens, 7, "remission_mode"),
        remissions=_floats(tokens, rem_index + 1, n_rem, "remission"),
        tv_mps=values[6],
        rv_radps=values[7],
        forward_safety_dist_m=values[8],
        side_safety_dist_m=values[9],
        turn_axis=values[10],
    )


def _parse_odom(tokens: list[str], line_number: int) -> OdomRecord:
    expected = 1 + len(_ODOM_NAMES)
    if len(tokens) != expected:
        raise _count_error("", tokens, expected, list(_ODOM_NAMES))
    values = [_float(tokens, 1 + k, _ODOM_NAMES[k]) for k in range(7)]
    for k in range(3):
        _float(tokens, 1 + k, _ODOM_NAMES[k], limit=COORDINATE_LIMIT_M)
    _stamp(tokens, 7, "ipc_timestamp")
    return OdomRecord(
        pose=Pose(*values[0:3]),
        tv_mps=values[3],
        rv_radps=values[4],
        accel_mps2=values[5],
        ipc_timestamp=values[6],
        hostname=tokens[8],
        logger_timestamp=_stamp(tokens, 9, "logger_timestamp"),
        line_number=line_number,
    )


def _parse_param(tokens: list[str], line_number: int) -> ParamRecord:
    if len(tokens) < 3:
        raise _LineError(f"needs a name and a value, got {len(tokens) - 1} field(s)")
    if len(tokens) == 6:
        return ParamRecord(
            name=tokens[1],
            value=tokens[2],
            ipc_timestamp=_float(tokens, 3, "ipc_timestamp"),
            hostname=tokens[4],
            logger_timestamp=_float(tokens, 5, "logger_timestamp"),
            line_number=line_number,
        )
    # Hand-written logs drop some or all of the stamp fields; the value is still tokens[2].
    return ParamRecord(name=tokens[1], value=tokens[2], line_number=line_number)


def _parse_neff(tokens: list[str], line_number: int) -> NeffRecord:
    if len(tokens) not in (2, 5):
        raise _LineError(f"has {len(tokens)} fields, expected 2 (or 5 with stamps)")
    return NeffRecord(value=_float(tokens, 1, "value"), line_number=line_number)


_PARSERS: dict[str, Callable[[list[str], int], Record]] = {
    "FLASER": _parse_flaser,
    "RLASER": _parse_flaser,
    "ROBOTLASER1": _parse_robotlaser,
    "ODOM": _parse_odom,
    "PARAM": _parse_param,
    "NEFF": _parse_neff,
}


class CarmenReader:
    """Stream the records of a CARMEN log (plain text or gzip, detected by magic bytes).

    Iterate it to get records lazily; :attr:`stats` describes the lines seen by the latest
    iteration (complete once the iteration has finished).
    """

    def __init__(self, path: str | os.PathLike[str], *, include_comments: bool = False) -> None:
        self.path = os.fspath(path)
        self.include_comments = include_comments
        self._counts: Counter[str] = Counter()
        self._skipped: Counter[str] = Counter()
        self._lines = self._comments = self._blank = 0

    @property
    def stats(self) -> CarmenStats:
        return CarmenStats(
            counts=dict(self._counts),
            skipped=dict(self._skipped),
            n_lines=self._lines,
            n_comments=self._comments,
            n_blank=self._blank,
        )

    def __iter__(self) -> Iterator[Record]:
        self._counts, self._skipped = Counter(), Counter()
        self._lines = self._comments = self._blank = 0
        scans = readings = 0
        with open_text(self.path) as handle:
            for line_number, line in enumerate(handle, start=1):
                self._lines = line_number
                record = self._parse_line(line, line_number)
                if record is None:
                    continue
                if isinstance(record, LaserRecord):
                    scans += 1
                    readings += record.n_beams + (
                        0 if record.remissions is None else len(record.remissions)
                    )
                    if scans > MAX_LOG_SCANS:
                        raise InputError(
                            f"{self.path}:{line_number}: more than {MAX_LOG_SCANS} laser "
                            "scans, the limit (MAX_LOG_SCANS)"
                        )
                    if readings > MAX_LOG_READINGS:
                        raise InputError(
                            f"{self.path}:{line_number}: more than {MAX_LOG_READINGS} laser "
                            "readings in all, the limit (MAX_LOG_READINGS)"
                        )
                yield record

    def _parse_line(self, line: str, line_number: int) -> Record | None:
        stripped = line.strip()
        if not stripped:
            self._blank += 1
            return None
        if stripped.startswith("#"):
            self._comments += 1
            return (
                CommentRecord(stripped[1:].strip(), line_number) if self.include_comments else None
            )
        tokens = stripped.split()
        parser = _PARSERS.get(tokens[0])
        if parser is None:
            # Counted by type; past a few hundred distinct names (no real log has them)
            # the rest are counted together, so the stats stay small.
            name = tokens[0] if len(self._skipped) < _MAX_SKIPPED_TYPES else "(other)"
            self._skipped[name[:40]] += 1
            return None
        try:
            record = parser(tokens, line_number)
        except _LineError as exc:
            raise InputError(f"{self.path}:{line_number}: {tokens[0]} {exc}") from None
        except (IndexError, ValueError, OverflowError) as exc:  # a case the checks missed
            raise InputError(
                f"{self.path}:{line_number}: {tokens[0]} malformed ({type(exc).__name__}: "
                f"{_cut(str(exc))})"
            ) from None
        self._counts[tokens[0]] += 1
        return record


def read_carmen(
    path: str | os.PathLike[str], *, include_comments: bool = False
) -> Iterator[Record]:
    """Iterate the records of a CARMEN log; use :class:`CarmenReader` to get the stats too."""
    return iter(CarmenReader(path, include_comments=include_comments))
