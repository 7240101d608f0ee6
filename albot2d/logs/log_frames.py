"""CARMEN records ↔ albot2d ``Frame`` streams: reading real logs and writing simulated ones.

Reading (:func:`read_frames`): every ``FLASER`` or ``ROBOTLASER1`` line becomes one ``Frame``;
``RLASER``, ``ODOM`` and ``NEFF`` lines are not turned into frames (the laser line carries the
odometry pose already). Each laser quantity comes from, in order: the keyword argument, the
log's ``PARAM`` lines seen so far, then the defaults below.

- Beam angles: ``ROBOTLASER1`` gives start angle and resolution. ``FLASER`` beams start at
  ``-fov/2`` (``fov`` from ``laser_front_laser_fov`` in degrees, default 180°) and step by
  ``laser_front_laser_resolution`` (degrees) when that PARAM is present; otherwise by
  ``fov/(n-1)`` for odd ``n`` (181, 361: −90°…+90° inclusive) and, for even ``n``, by
  ``even_beam_convention``: ``"fov_over_n"`` (default; 180 → 1°, −90°…+89°) or
  ``"fov_over_n_minus_1"``.
- Validity: a beam is valid when finite, > 0 and below both the no-return threshold and
  ``max_range_m``. The threshold defaults to ``ROBOTLASER1``'s max range, else
  ``robot_front_laser_max``, else :data:`DEFAULT_NO_RETURN_THRESHOLD_M` = 30 m: below every
  no-return code seen in real logs (32.767, 50.0, 51.1–51.25, 81.83, 81.91) and the SICK LMS's
  rated range for dark (10 %) targets, beyond which returns are sparse and unreliable.
- Mount: ``robot_frontlaser_offset`` / ``_sideoffset`` / ``_angular_offset``; for
  ``ROBOTLASER1`` the robot→laser transform of its two poses.

Writing (:func:`write_carmen`) produces what a raw log has: laser PARAMs, then per frame an
``ODOM`` and an ``FLASER`` line with the odometry pose in both pose fields. Invalid beams are
written as ``max_range_m``, so they read back invalid; a *valid* beam reads back valid when
``0 < range < max_range_m`` after rounding to the written precision (:class:`FloatFormat`).
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
from collections.abc import Iterable, Iterator, Mapping
from itertools import chain
from typing import Any, Literal

import numpy as np

from albot2d import __version__
from albot2d.errors import InputError
from albot2d.frames import Frame, Scan
from albot2d.geometry import Pose
from albot2d.logs.carmen import CarmenReader, LaserRecord, OdomRecord, ParamRecord, Record
from albot2d.logs.carmen_writer import LOG_PRECISION, FloatFormat, format_float, write_records
from albot2d.plainjson import to_plain
from albot2d.validation import COORDINATE_LIMIT_M

__all__ = [
    "DEFAULT_EVEN_BEAM_CONVENTION",
    "DEFAULT_FOV_DEG",
    "DEFAULT_NO_RETURN_THRESHOLD_M",
    "HOSTNAME",
    "EvenBeamConvention",
    "frames_to_records",
    "read_frames",
    "records_to_frames",
    "write_carmen",
]

EvenBeamConvention = Literal["fov_over_n", "fov_over_n_minus_1"]
DEFAULT_FOV_DEG = 180.0
DEFAULT_EVEN_BEAM_CONVENTION: EvenBeamConvention = "fov_over_n"
DEFAULT_NO_RETURN_THRESHOLD_M = 30.0
HOSTNAME = "albot2d"

PARAM_FOV_DEG = "laser_front_laser_fov"
PARAM_RESOLUTION_DEG = "laser_front_laser_resolution"
PARAM_MAX_RANGE_M = "robot_front_laser_max"
PARAM_OFFSET_M = "robot_frontlaser_offset"
PARAM_SIDE_OFFSET_M = "robot_frontlaser_sideoffset"
PARAM_ANGULAR_OFFSET_RAD = "robot_frontlaser_angular_offset"
PARAM_VERSION = "albot2d_version"
_USER_PARAM_PREFIX = "albot2d_"
_FRAME_MESSAGES = ("FLASER", "ROBOTLASER1")
_GEOMETRY_PARAMS = frozenset(
    (PARAM_FOV_DEG, PARAM_RESOLUTION_DEG, PARAM_MAX_RANGE_M, PARAM_OFFSET_M, PARAM_SIDE_OFFSET_M,
     PARAM_ANGULAR_OFFSET_RAD)
)  # fmt: skip
_POSITIVE_PARAMS = frozenset((PARAM_FOV_DEG, PARAM_RESOLUTION_DEG, PARAM_MAX_RANGE_M))
# The largest value each laser PARAM may have: angles in degrees up to one turn, lengths
# within the coordinate limit, the mount's angle in radians up to one turn.
_PARAM_LIMITS = {
    PARAM_FOV_DEG: 360.0,
    PARAM_RESOLUTION_DEG: 360.0,
    PARAM_MAX_RANGE_M: COORDINATE_LIMIT_M,
    PARAM_OFFSET_M: COORDINATE_LIMIT_M,
    PARAM_SIDE_OFFSET_M: COORDINATE_LIMIT_M,
    PARAM_ANGULAR_OFFSET_RAD: 2.0 * math.pi,
}
_UNIFORM_TOLERANCE_RAD = 1e-9


def read_frames(
    path: str | os.PathLike[str],
    *,
    fov_deg: float | None = None,
    no_return_threshold_m: float | None = None,
    even_beam_convention: EvenBeamConvention | None = None,
    max_range_m: float | None = None,
) -> Iterator[Frame]:
    """Stream the laser frames of a CARMEN log (see the module docstring for the rules)."""
    return records_to_frames(
        CarmenReader(path),
        source=os.fspath(path),
        fov_deg=fov_deg,
        no_return_threshold_m=no_return_threshold_m,
        even_beam_convention=even_beam_convention,
        max_range_m=max_range_m,
    )


def records_to_frames(
    records: Iterable[Record],
    *,
    source: str = "<records>",
    fov_deg: float | None = None,
    no_return_threshold_m: float | None = None,
    even_beam_convention: EvenBeamConvention | None = None,
    max_range_m: float | None = None,
) -> Iterator[Frame]:
    """Turn a record stream into ``Frame``s; ``source`` names the file in error messages.

    Options are checked now; records are consumed lazily as the frames are iterated.
    """
    if even_beam_convention not in (None, "fov_over_n", "fov_over_n_minus_1"):
        raise InputError(
            f"even_beam_convention must be 'fov_over_n' or 'fov_over_n_minus_1', "
            f"got {even_beam_convention!r}"
        )
    for name, value, limit in (
        ("fov_deg", fov_deg, 360.0),
        ("no_return_threshold_m", no_return_threshold_m, COORDINATE_LIMIT_M),
        ("max_range_m", max_range_m, COORDINATE_LIMIT_M),
    ):
        if value is not None and not (math.isfinite(value) and 0 < value <= limit):
            raise InputError(f"{name} must be a number in (0, {limit:g}], got {value!r}")
    return _frames(
        records, source, fov_deg, no_return_threshold_m, even_beam_convention, max_range_m
    )


def _frames(
    records: Iterable[Record],
    source: str,
    fov_deg: float | None,
    no_return_threshold_m: float | None,
    even_beam_convention: EvenBeamConvention | None,
    max_range_m: float | None,
) -> Iterator[Frame]:
    params: dict[str, float] = {}
    angle_cache: dict[tuple[int, float, float], np.ndarray] = {}
    prev_odom: Pose | None = None
    index = 0
    for record in records:
        if isinstance(record, ParamRecord):
            if record.name in _GEOMETRY_PARAMS:
                params[record.name] = _geometry_param(record, source)
            continue
        if not isinstance(record, LaserRecord) or record.message not in _FRAME_MESSAGES:
            continue
        if record.message == "ROBOTLASER1":
            angles = _robotlaser_angles(record, angle_cache)
            mount = record.odom_pose.between(record.pose)
            record_max = record.max_range_m if record.max_range_m else None
        else:
            fov_used = (
                fov_deg if fov_deg is not None else params.get(PARAM_FOV_DEG, DEFAULT_FOV_DEG)
            )
            fov = math.radians(fov_used)
            angles = _flaser_angles(
                record.n_beams, fov, params.get(PARAM_RESOLUTION_DEG), even_beam_convention,
                angle_cache,
            )  # fmt: skip
            mount = Pose(
                params.get(PARAM_OFFSET_M, 0.0),
                params.get(PARAM_SIDE_OFFSET_M, 0.0),
                params.get(PARAM_ANGULAR_OFFSET_RAD, 0.0),
            )
            record_max = params.get(PARAM_MAX_RANGE_M)
        threshold = no_return_threshold_m or record_max or DEFAULT_NO_RETURN_THRESHOLD_M
        if not (math.isfinite(threshold) and threshold > 0):
            raise InputError(
                f"{source}:{record.line_number}: laser max range {threshold!r} must be > 0"
            )
        usable = max_range_m or threshold
        ranges = record.ranges
        with np.errstate(invalid="ignore"):
            valid = np.isfinite(ranges) & (ranges > 0) & (ranges < min(threshold, usable))
        scan = Scan(ranges, angles, valid, usable, record.ipc_timestamp, mount)
        odom = record.odom_pose
        increment = Pose() if prev_odom is None else prev_odom.between(odom)
        yield Frame(index, record.ipc_timestamp, scan, odom, increment)
        prev_odom = odom
        index += 1


def _geometry_param(record: ParamRecord, source: str) -> float:
    try:
        value = float(record.value)
    except ValueError:
        value = math.nan
    limit = _PARAM_LIMITS[record.name]
    positive = record.name in _POSITIVE_PARAMS
    if not (abs(value) <= limit) or (positive and value <= 0):
        kind = f"a number in (0, {limit:g}]" if positive else f"a number within ±{limit:g}"
        raise InputError(
            f"{source}:{record.line_number}: PARAM {record.name} value {record.value!r} "
            f"is not {kind}"
        )
    return value


def _flaser_angles(
    n: int,
    fov_rad: float,
    resolution_deg: float | None,
    convention: EvenBeamConvention | None,
    cache: dict[tuple[int, float, float], np.ndarray],
) -> np.ndarray:
    if convention is None and resolution_deg is not None:
        step = math.radians(resolution_deg)
    elif n < 2:
        step = 0.0
    elif n % 2 == 1 or (convention or DEFAULT_EVEN_BEAM_CONVENTION) == "fov_over_n_minus_1":
        step = fov_rad / (n - 1)
    else:
        step = fov_rad / n
    return _angles(n, -0.5 * fov_rad if n > 1 else 0.0, step, cache)


def _robotlaser_angles(
    record: LaserRecord, cache: dict[tuple[int, float, float], np.ndarray]
) -> np.ndarray:
    start = record.start_angle_rad or 0.0
    return _angles(record.n_beams, start, record.angular_resolution_rad or 0.0, cache)


def _angles(
    n: int, start: float, step: float, cache: dict[tuple[int, float, float], np.ndarray]
) -> np.ndarray:
    key = (n, start, step)
    if key not in cache:
        cache[key] = start + step * np.arange(n, dtype=np.float64)
    return cache[key]


@dataclasses.dataclass(frozen=True)
class _LaserGeometry:
    """What FLASER + PARAMs can record about a scan: a centred uniform sweep."""

    n_beams: int
    fov_rad: float
    step_rad: float
    max_range_m: float
    mount: Pose
    angles: np.ndarray

    @classmethod
    def of(cls, scan: Scan, index: int) -> _LaserGeometry:
        a, n = scan.angles, scan.n_beams
        if n < 2:
            raise InputError(f"frame {index}: a CARMEN FLASER scan needs >= 2 beams, got {n}")
        step = float(a[-1] - a[0]) / (n - 1)
        uniform = np.max(np.abs(a - (a[0] + step * np.arange(n)))) <= _UNIFORM_TOLERANCE_RAD
        if uniform and step > 0 and abs(a[0] + 0.5 * (n - 1) * step) <= _UNIFORM_TOLERANCE_RAD:
            fov = (n - 1) * step
        elif uniform and step > 0 and abs(a[0] + 0.5 * n * step) <= _UNIFORM_TOLERANCE_RAD:
            fov = n * step
        else:
            raise InputError(
                f"frame {index}: scan angles are not a uniform counter-clockwise sweep starting "
                f"at -fov/2 (all FLASER can record): first {a[0]!r}, last {a[-1]!r}, n {n}"
            )
        return cls(n, fov, step, float(scan.max_range_m), scan.laser_pose, a)

    def check(self, scan: Scan, index: int) -> None:
        same = (
            scan.n_beams == self.n_beams
            and scan.max_range_m == self.max_range_m
            and scan.laser_pose == self.mount
            and np.allclose(scan.angles, self.angles, rtol=0.0, atol=_UNIFORM_TOLERANCE_RAD)
        )
        if not same:
            raise InputError(
                f"frame {index}: laser geometry (beams, angles, max range or mount) differs from "
                "frame 0; a CARMEN log records one laser configuration in its PARAMs"
            )

    def params(self) -> dict[str, float]:
        return {
            PARAM_FOV_DEG: math.degrees(self.fov_rad),
            PARAM_RESOLUTION_DEG: math.degrees(self.step_rad),
            PARAM_MAX_RANGE_M: self.max_range_m,
            PARAM_OFFSET_M: self.mount.x,
            PARAM_SIDE_OFFSET_M: self.mount.y,
            PARAM_ANGULAR_OFFSET_RAD: self.mount.theta,
        }


def frames_to_records(
    frames: Iterable[Frame],
    *,
    params: Mapping[str, Any] | None = None,
    hostname: str = HOSTNAME,
    float_format: FloatFormat = LOG_PRECISION,
) -> Iterator[Record]:
    """Records of a raw CARMEN log for ``frames``: PARAMs, then ODOM + FLASER per frame.

    ``params`` (e.g. the simulator's settings) are written as ``PARAM albot2d_<key> <value>``
    (nested keys joined with "."); the laser PARAMs are derived from the frames themselves.
    ``ODOM`` velocities are the odometry increment over the time since the previous frame.
    Invalid beams get the max range, rounded up to ``float_format``'s range precision.
    """
    stream = iter(frames)
    first = next(stream, None)
    t0 = first.timestamp if first is not None else 0.0
    geometry = _LaserGeometry.of(first.scan, first.index) if first is not None else None
    laser: dict[str, float | str] = dict(geometry.params()) if geometry is not None else {}
    entries = laser | _flatten_params(params or {}) | {PARAM_VERSION: __version__}
    for name, value in entries.items():
        text = value if isinstance(value, str) else repr(float(value))
        yield ParamRecord(name, text, t0, hostname, 0.0)
    if first is None or geometry is None:
        return
    no_return = _no_return_value(geometry.max_range_m, float_format.range_decimals)
    prev: Frame | None = None
    for frame in chain([first], stream):
        geometry.check(frame.scan, frame.index)
        tv = rv = 0.0
        if prev is not None and frame.timestamp > prev.timestamp:
            dt = frame.timestamp - prev.timestamp
            inc = prev.odom_pose.between(frame.odom_pose)
            tv, rv = inc.x / dt, inc.theta / dt
        stamp, logger = frame.timestamp, frame.timestamp - t0
        odom = frame.odom_pose
        yield OdomRecord(odom, tv, rv, 0.0, stamp, hostname, logger)
        ranges = np.where(frame.scan.valid, frame.scan.ranges, no_return)
        yield LaserRecord("FLASER", ranges, odom, odom, stamp, hostname, logger)
        prev = frame


def _no_return_value(max_range_m: float, decimals: int | None) -> float:
    """The smallest value at ``decimals`` places that reads back >= ``max_range_m``."""
    if decimals is None:
        return max_range_m
    unit = 10.0**-decimals
    value = math.ceil(max_range_m / unit) * unit
    while float(format_float(value, decimals)) < max_range_m:
        value += unit
    return value


def write_carmen(
    path: str | os.PathLike[str],
    frames: Iterable[Frame],
    *,
    params: Mapping[str, Any] | None = None,
    float_format: FloatFormat = LOG_PRECISION,
) -> int:
    """Write ``frames`` as a raw CARMEN log (atomic; gzip if ``path`` ends in .gz).

    Streams the frames (any iterable, consumed once). Returns the number of frames written.
    """
    count = 0

    def counted() -> Iterator[Record]:
        nonlocal count
        for record in frames_to_records(frames, params=params, float_format=float_format):
            count += isinstance(record, LaserRecord)
            yield record

    write_records(path, counted(), float_format)
    return count


def _flatten_params(params: Mapping[str, Any], prefix: str = "") -> dict[str, str]:
    """``{"laser": {"noise_m": 0.01}}`` → ``{"albot2d_laser.noise_m": "0.01"}``.

    A PARAM value is one token: plain strings stay as they are; other values become compact
    JSON, and so do strings that are empty or hold whitespace, with the whitespace written as
    ``\\uXXXX`` escapes (still valid JSON). Whitespace in names becomes "_".
    """
    out: dict[str, str] = {}
    for key, value in params.items():
        name = "".join("_" if ch.isspace() else ch for ch in f"{prefix}{key}")
        if dataclasses.is_dataclass(value) and not isinstance(value, type):
            value = dataclasses.asdict(value)
        if isinstance(value, Mapping):
            out |= _flatten_params(value, f"{name}.")
            continue
        if isinstance(value, str) and value and not any(ch.isspace() for ch in value):
            text = value
        else:
            try:
                text = json.dumps(to_plain(value), separators=(",", ":"), allow_nan=True)
            except (TypeError, InputError):
                raise InputError(f"params[{name!r}]: cannot write {type(value).__name__}") from None
        # Compact JSON has whitespace only inside strings, where a \\u escape means the same.
        text = "".join(f"\\u{ord(ch):04x}" if ch.isspace() else ch for ch in text)
        out[f"{_USER_PARAM_PREFIX}{name}"] = text
    return out
