"""Drive every mapper over one frame stream and keep what the metrics and figures need.

``drive_mappers`` feeds each frame to every mapper in turn (so a long run is streamed once,
never held in memory) and records a :class:`Trace`: per-frame timestamps, odometry and (in
simulation) true poses, distance travelled, the laser hits of the last K views, wall time
per mapper, and the *homing stops*.

Homing stops are chosen online, as a robot that stops to point home would: every
``stop_every_m`` metres of odometer distance (what the robot itself measures, as in the
paper), plus the last view; a stop closer than ``min_start_distance_m`` to the start (true
distance in simulation, odometry on real logs) is skipped because the bearing to a point
that near is ill-defined. At each stop every mapper is asked, there and then, for its pose
and for where its map puts the start (its trajectory's first pose).
"""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from albot2d.errors import InputError
from albot2d.frames import Frame
from albot2d.geometry import transform_points
from albot2d.mapping.protocol import Mapper
from albot2d.validation import check_non_negative, check_positive

__all__ = ["HomingParams", "Stop", "Trace", "drive_mappers"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class HomingParams:
    """Where the robot stops to orient back to its start (paper Table 1).

    - ``stop_every_m``: a stop each time the odometer passes a multiple of this distance.
    - ``min_start_distance_m``: stops nearer than this to the start are skipped.
    - ``include_last``: the last view is a stop too (if far enough from the start).
    """

    stop_every_m: float = 20.0
    min_start_distance_m: float = 3.0
    include_last: bool = True

    def __post_init__(self) -> None:
        check_positive(self, "stop_every_m")
        check_non_negative(self, "min_start_distance_m")
        if not isinstance(self.include_last, bool):
            raise InputError(
                f"HomingParams.include_last must be true or false, got {self.include_last!r}"
            )


@dataclass(frozen=True, slots=True)
class Stop:
    """A homing stop: trace row, odometer distance, and each mapper's (pose, start) then."""

    row: int
    travelled_m: float
    estimates: dict[str, tuple[FloatArray, FloatArray]]


@dataclass(eq=False)
class Trace:
    """What a run left behind (rows are frames in the order observed)."""

    frame_indices: NDArray[np.int64]
    timestamps: FloatArray
    odom_poses: FloatArray
    true_poses: FloatArray | None
    collided: NDArray[np.bool_]
    travelled_m: FloatArray
    seen_points: FloatArray | None
    stops: list[Stop]
    mappers: dict[str, Mapper]
    wall_ms: dict[str, float] = field(default_factory=dict)

    @property
    def n_frames(self) -> int:
        return len(self.timestamps)

    def __repr__(self) -> str:
        metres = float(self.travelled_m[-1]) if self.n_frames else 0.0
        return (f"Trace({self.n_frames} frames, {metres:.1f} m, truth={self.has_truth}, "
                f"{len(self.stops)} stops, mappers={list(self.mappers)})")

    @property
    def has_truth(self) -> bool:
        return self.true_poses is not None


class _Recorder:
    """Accumulates the per-frame rows of a Trace."""

    def __init__(self, last_k_views: int) -> None:
        self.indices: list[int] = []
        self.stamps: list[float] = []
        self.odom: list[FloatArray] = []
        self.truth: list[FloatArray] = []
        self.collided: list[bool] = []
        self.travelled: list[float] = []
        self.recent: deque[FloatArray] = deque(maxlen=last_k_views)
        self.with_truth: bool | None = None

    def add(self, frame: Frame) -> None:
        has_truth = frame.true_pose is not None
        if self.with_truth is None:
            self.with_truth = has_truth
        elif has_truth != self.with_truth:
            raise InputError(
                f"frame {frame.index} {'has' if has_truth else 'lacks'} a true pose, "
                "unlike the first frame; a run has truth for every frame or for none"
            )
        inc = frame.odom_increment
        step = math.hypot(inc.x, inc.y) if self.indices else 0.0
        self.travelled.append((self.travelled[-1] if self.travelled else 0.0) + step)
        self.indices.append(frame.index)
        self.stamps.append(frame.timestamp)
        self.odom.append(frame.odom_pose.as_array())
        self.collided.append(bool(frame.collided))
        if frame.true_pose is not None:
            pose = frame.true_pose.as_array()
            self.truth.append(pose)
            self.recent.append(transform_points(pose, frame.scan.points()))

    def reference_distance(self) -> float:
        """Straight-line distance from the start now (truth if known, else odometry)."""
        track = self.truth if self.with_truth else self.odom
        return float(math.hypot(*(track[-1][:2] - track[0][:2])))


def _estimate(mapper: Mapper) -> tuple[FloatArray, FloatArray]:
    """The mapper's current pose and its start (its trajectory's first pose), as arrays."""
    trajectory = np.asarray(mapper.trajectory(), dtype=np.float64).reshape(-1, 3)
    start = trajectory[0].copy() if len(trajectory) else np.zeros(3)
    return mapper.pose().as_array(), start


def drive_mappers(
    frames: Iterable[Frame],
    mappers: dict[str, Mapper],
    *,
    homing: HomingParams | None = None,
    last_k_views: int = 10,
    max_frames: int | None = None,
    on_frame: Callable[[Frame, float], None] | None = None,
    source: str = "the run",
) -> Trace:
    """Feed ``frames`` (at most ``max_frames``) to every mapper; see the module docstring.

    ``on_frame(frame, travelled_m)`` is called after each frame (e.g. a progress bar);
    ``source`` names the frames' origin in errors.
    """
    params = homing or HomingParams()
    rec = _Recorder(last_k_views)
    wall_ns = dict.fromkeys(mappers, 0)
    stops: list[Stop] = []
    passed = 0  # multiples of stop_every_m passed so far

    def stop_here() -> None:
        if rec.reference_distance() < params.min_start_distance_m:
            return
        estimates = {name: _estimate(m) for name, m in mappers.items()}
        stops.append(Stop(len(rec.stamps) - 1, rec.travelled[-1], estimates))

    for frame in frames:
        if max_frames is not None and len(rec.stamps) >= max_frames:
            break
        rec.add(frame)
        for name, mapper in mappers.items():
            t0 = time.perf_counter_ns()
            mapper.observe(frame)
            wall_ns[name] += time.perf_counter_ns() - t0
        # Stop when the odometer enters a new multiple of the spacing (floor division, not
        # a running sum, so the spacing's rounding cannot accumulate).
        multiple = int(rec.travelled[-1] // params.stop_every_m)
        if multiple > passed:
            passed = multiple
            stop_here()
        if on_frame is not None:
            on_frame(frame, rec.travelled[-1])
    if not rec.stamps:
        raise InputError(f"no frames to map: {source} has no laser scans")
    if params.include_last and (not stops or stops[-1].row != len(rec.stamps) - 1):
        stop_here()
    n = len(rec.stamps)
    truth = np.asarray(rec.truth, dtype=np.float64).reshape(n, 3) if rec.with_truth else None
    seen = np.vstack(list(rec.recent)) if rec.with_truth and rec.recent else None
    return Trace(
        frame_indices=np.asarray(rec.indices, dtype=np.int64),
        timestamps=np.asarray(rec.stamps, dtype=np.float64),
        odom_poses=np.asarray(rec.odom, dtype=np.float64).reshape(n, 3),
        true_poses=truth,
        collided=np.asarray(rec.collided, dtype=bool),
        travelled_m=np.asarray(rec.travelled, dtype=np.float64),
        seen_points=seen,
        stops=stops,
        mappers=mappers,
        wall_ms={name: ns / 1e6 for name, ns in wall_ns.items()},
    )
