"""Drive every mapper over one frame stream and keep what the metrics and figures need.

``drive_mappers`` feeds each frame to every mapper in turn (so a long run is streamed once,
never held in memory) and records a :class:`Trace`: per-frame timestamps, odometry and (in
simulation) true poses, distance travelled, the laser hits of the last K views, wall time
per mapper, per-view stage times (:class:`StepTimes`, ``steps.csv``) and the *homing stops*.

Perceive once: each frame's surfaces are extracted once per distinct ``ExtractionParams``
and passed to every ``PerceivingMapper`` that wants them (``observe_perceived``; see
``takes_perceived_views``); other mappers get the raw frame (``observe``). A mapper's
``timing_ms`` and wall time still include the extraction it used, as if it had extracted
alone (so the sum over mappers counts a shared extraction more than once).

Homing stops are chosen online, as a robot that stops to point home would: every
``stop_every_m`` metres of odometer distance (what the robot itself measures, as in the
paper), plus the last view; a stop closer than ``min_start_distance_m`` to the start (true
distance in simulation, odometry on real logs) is skipped because the bearing to a point
that near is ill-defined. At each stop every mapper is asked, there and then, for its pose
and for where its map puts the start (its trajectory's first pose).

Egocentric map quality at the stops (simulation): given the true ``walls``,
``drive_mappers`` scores each mapper's map there and then and keeps only the scores, so
memory follows the map, not stops × map (a 1,200 m tour kept 2.8 GB of map copies).
Without ``walls`` a stop keeps what the scores are computed from (the seen window and
each mapper's map near the robot), for a caller to score later against any walls.
"""

from __future__ import annotations

import contextlib
import io
import math
import time
from array import array
from collections import deque
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from albot2d.errors import InputError
from albot2d.evaluation.metrics.egocentric import (
    EgocentricParams,
    EgocentricQuality,
    egocentric_qualities,
    in_robot_frame,
    seen_window_local,
)
from albot2d.frames import Frame, Scan
from albot2d.mapping.baselines import IntegratedMap, ViewIntegrator
from albot2d.mapping.protocol import Mapper, StageTimer, takes_perceived_views
from albot2d.perception import ExtractionParams, Surfaces, extract_surfaces
from albot2d.validation import check_non_negative, check_positive

__all__ = ["HomingParams", "StepTimes", "Stop", "Trace", "drive_mappers"]

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
    """A homing stop: trace row, odometer distance, and each mapper's (pose, start) then.

    In simulation it also has each mapper's egocentric map quality there
    (``albot2d.evaluation.metrics.egocentric``): ``egocentric``, scored while driving when the
    driver had the true walls; else what it is computed from: ``seen``, the laser hits of
    the last window of travel relative to the true pose, and ``maps``, each mapper's
    global-map surfaces near the robot relative to its own pose estimate, with its total
    surface count.
    """

    row: int
    travelled_m: float
    estimates: dict[str, tuple[FloatArray, FloatArray]]
    seen: FloatArray | None = None
    maps: dict[str, tuple[FloatArray, int]] = field(default_factory=dict)
    egocentric: dict[str, EgocentricQuality] = field(default_factory=dict)


class StepTimes:
    """Per-view columns of ``steps.csv``: stage times (ms) and a few counters per view.

    Columns: ``view`` (frame index), ``simulation_ms`` (waiting for the frame: the
    simulator step, or reading a log), ``extraction_ms`` (the shared extraction, summed
    over distinct settings), then per mapper ``NAME.STAGE_ms`` (its ``StageTimer`` stages,
    when it has one as ``.timer``) and ``NAME.total_ms``, and for mappers that expose them
    ``NAME.tracked`` (surfaces tracked at this view), ``NAME.remembered`` (local maps
    remembered at this view) and ``NAME.map_surfaces`` (surfaces in its global map now).
    A stage a view did not run counts 0. Columns are compact ``array('d')``: 8 bytes a cell.
    """

    def __init__(self) -> None:
        self.columns: dict[str, array[float]] = {}
        self.rows = 0

    def add_row(self, values: dict[str, float]) -> None:
        for name in values:
            if name not in self.columns:  # a new column: zeros for the earlier rows
                self.columns[name] = array("d", bytes(8 * self.rows))
        for name, column in self.columns.items():
            column.append(values.get(name, 0.0))
        self.rows += 1

    def column(self, name: str) -> NDArray[np.float64]:
        return np.frombuffer(self.columns[name], dtype=np.float64).copy()

    def stage_names(self) -> list[str]:
        """The time columns (``*_ms``), in the order they first appeared."""
        return [name for name in self.columns if name.endswith("_ms")]

    def summary_ms(self) -> dict[str, dict[str, float]]:
        """Per time column: mean, p50, p95 and max milliseconds per view."""
        out: dict[str, dict[str, float]] = {}
        for name in self.stage_names():
            v = self.column(name)
            if not len(v):
                continue
            p50, p95 = np.percentile(v, [50, 95])
            out[name.removesuffix("_ms")] = {
                "mean": float(v.mean()), "p50": float(p50), "p95": float(p95),
                "max": float(v.max()),
            }  # fmt: skip
        return out

    def to_csv(self) -> str:
        """The table as CSV text (``view`` and counters as integers, times in ms)."""
        names = list(self.columns)
        data = np.column_stack([self.column(n) for n in names]) if names else np.zeros((0, 0))
        buf = io.StringIO()
        buf.write(",".join(names) + "\n")
        integer = [not n.endswith("_ms") for n in names]
        for row in data:
            cells = (str(int(x)) if whole else f"{x:.4f}"
                     for x, whole in zip(row, integer, strict=True))  # fmt: skip
            buf.write(",".join(cells) + "\n")
        return buf.getvalue()


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
    final: Stop | None = None
    egocentric: EgocentricParams = field(default_factory=EgocentricParams)
    step_times: StepTimes = field(default_factory=StepTimes)

    @property
    def n_frames(self) -> int:
        return len(self.timestamps)

    def __repr__(self) -> str:
        metres = float(self.travelled_m[-1]) if self.n_frames else 0.0
        return (
            f"Trace({self.n_frames} frames, {metres:.1f} m, truth={self.has_truth}, "
            f"{len(self.stops)} stops, mappers={list(self.mappers)})"
        )

    @property
    def has_truth(self) -> bool:
        return self.true_poses is not None


class _Recorder:
    """Accumulates the per-frame rows of a Trace, in flat typed arrays (~70 bytes a frame;
    a list of small arrays and Python numbers per column cost ~400)."""

    def __init__(self, last_k_views: int, window_m: float = 30.0) -> None:
        self.indices = array("q")
        self.stamps = array("d")
        self.odom = array("d")  # x, y, theta per frame
        self.truth = array("d")
        self.collided = array("b")
        self.travelled = array("d")
        self.recent: deque[FloatArray] = deque(maxlen=last_k_views)
        self.window_m = window_m
        self.window: deque[tuple[float, FloatArray]] = deque()
        self.with_truth: bool | None = None
        self.last_truth = np.zeros(3)

    def __len__(self) -> int:
        return len(self.indices)

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
        odom = frame.odom_pose
        self.odom.extend((odom.x, odom.y, odom.theta))
        self.collided.append(bool(frame.collided))
        if frame.true_pose is not None:
            true = frame.true_pose
            self.truth.extend((true.x, true.y, true.theta))
            self.last_truth = true.as_array()
            hits = frame.world_hits()
            self.recent.append(hits)
            self.window.append((self.travelled[-1], hits))
            while self.window and self.window[0][0] < self.travelled[-1] - self.window_m:
                self.window.popleft()

    def seen_window(self, grid_m: float) -> FloatArray | None:
        """The last window's laser hits relative to the true pose now (None without truth)."""
        if not self.with_truth or not self.window:
            return None
        return seen_window_local(np.vstack([h for _, h in self.window]), self.last_truth, grid_m)

    def reference_distance(self) -> float:
        """Straight-line distance from the start now (truth if known, else odometry)."""
        track = self.truth if self.with_truth else self.odom
        return math.hypot(track[-3] - track[0], track[-2] - track[1])

    @staticmethod
    def column(values: array[Any], dtype: type, width: int = 1) -> NDArray[Any]:
        """A recorded column as a fresh numpy array (``(N, width)`` when ``width > 1``)."""
        out: NDArray[Any] = np.zeros(0, dtype)
        if len(values):
            out = np.frombuffer(values, dtype=dtype).copy()
        return out.reshape(-1, width) if width > 1 else out


def _egocentric_map(mapper: Mapper, seen: FloatArray) -> tuple[FloatArray, int]:
    """The mapper's map surfaces near it, relative to its own pose, and its surface count.

    A map that keeps every view (``IntegratedMap``: the naive and truth mappers) is read
    block by block, not copied whole: a copy per stop made the memory of driving follow
    the map's size (the same surfaces, in the same order)."""
    reach = float(np.max(np.hypot(seen[:, 0], seen[:, 1]), initial=0.0)) + 1.0
    pose = mapper.pose().as_array()
    stored = getattr(mapper, "map", None)
    # (only where global_map is ViewIntegrator's: a subclass may answer otherwise)
    plain = isinstance(mapper, ViewIntegrator) and (
        type(mapper).global_map is ViewIntegrator.global_map
    )
    if plain and isinstance(stored, IntegratedMap):
        near = [in_robot_frame(pose, segments, reach) for segments, _ in stored.blocks()]
        return (np.vstack(near) if near else np.zeros((0, 4))), len(stored)
    segments = mapper.global_map().segments
    return in_robot_frame(pose, segments, reach), len(segments)


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
    egocentric: EgocentricParams | None = None,
    walls: FloatArray | None = None,
) -> Trace:
    """Feed ``frames`` (at most ``max_frames``) to every mapper; see the module docstring.

    ``on_frame(frame, travelled_m)`` is called after each frame (e.g. a progress bar);
    ``source`` names the frames' origin in errors; ``egocentric`` sets the window kept for
    the egocentric map quality at each stop and at the end; ``walls`` (``(W, 4)``, world
    frame), the true walls it is scored against while driving.
    """
    params = homing or HomingParams()
    ego = egocentric or EgocentricParams()
    rec = _Recorder(last_k_views, ego.window_m)
    wall_ns = dict.fromkeys(mappers, 0)
    stops: list[Stop] = []
    passed = 0  # multiples of stop_every_m passed so far
    steps = StepTimes()
    perceives = {name: m.perception() for name, m in mappers.items()
                 if takes_perceived_views(m)}  # fmt: skip
    probes = {name: _Probe(m) for name, m in mappers.items()}
    for extraction in set(perceives.values()):
        _warm_up(extraction)

    def capture() -> Stop:
        estimates = {name: _estimate(m) for name, m in mappers.items()}
        row, travelled = len(rec) - 1, rec.travelled[-1]
        seen = rec.seen_window(ego.grid_m)
        if seen is None:
            return Stop(row, travelled, estimates)
        maps = {n: _egocentric_map(m, seen) for n, m in mappers.items()}
        if walls is None:
            return Stop(row, travelled, estimates, seen, maps)
        # Scored now; the window and the map copies are dropped with this frame.
        scores = egocentric_qualities(seen, maps, walls, rec.last_truth, ego)
        return Stop(row, travelled, estimates, egocentric=scores)

    def stop_here() -> None:
        if rec.reference_distance() < params.min_start_distance_m:
            return
        stops.append(capture())

    stream = iter(frames)
    while max_frames is None or len(rec) < max_frames:
        t0 = time.perf_counter_ns()
        frame = next(stream, None)
        if frame is None:
            break
        row: dict[str, float] = {
            "view": frame.index,
            "simulation_ms": (time.perf_counter_ns() - t0) / 1e6,
        }
        rec.add(frame)
        views: dict[ExtractionParams, tuple[Surfaces, int]] = {}
        for extraction in perceives.values():
            if extraction not in views:
                t0 = time.perf_counter_ns()
                view = extract_surfaces(frame.scan, extraction)
                views[extraction] = (view, time.perf_counter_ns() - t0)
        if views:
            row["extraction_ms"] = sum(ns for _, ns in views.values()) / 1e6
        for name, mapper in mappers.items():
            shared_ns = 0
            t0 = time.perf_counter_ns()
            if name in perceives:
                view, shared_ns = views[perceives[name]]
                probes[name].charge_extraction(shared_ns)
                # perceives holds only the mappers takes_perceived_views() accepted.
                mapper.observe_perceived(frame, view)  # type: ignore[attr-defined]
            else:
                mapper.observe(frame)
            elapsed = time.perf_counter_ns() - t0 + shared_ns
            wall_ns[name] += elapsed
            probes[name].record(row, name, elapsed)
        steps.add_row(row)
        # Stop when the odometer enters a new multiple of the spacing (floor division, not
        # a running sum, so the spacing's rounding cannot accumulate).
        multiple = int(rec.travelled[-1] // params.stop_every_m)
        if multiple > passed:
            passed = multiple
            stop_here()
        if on_frame is not None:
            on_frame(frame, rec.travelled[-1])
    if not len(rec):
        raise InputError(f"no frames to map: {source} has no laser scans")
    if params.include_last and (not stops or stops[-1].row != len(rec) - 1):
        stop_here()
    final = stops[-1] if stops and stops[-1].row == len(rec) - 1 else capture()
    truth = rec.column(rec.truth, np.float64, 3) if rec.with_truth else None
    seen = np.vstack(list(rec.recent)) if rec.with_truth and rec.recent else None
    return Trace(
        frame_indices=rec.column(rec.indices, np.int64),
        timestamps=rec.column(rec.stamps, np.float64),
        odom_poses=rec.column(rec.odom, np.float64, 3),
        true_poses=truth,
        collided=rec.column(rec.collided, np.int8).astype(bool),
        travelled_m=rec.column(rec.travelled, np.float64),
        seen_points=seen,
        stops=stops,
        mappers=mappers,
        wall_ms={name: ns / 1e6 for name, ns in wall_ns.items()},
        final=final,
        egocentric=ego,
        step_times=steps,
    )


def _warm_up(params: ExtractionParams) -> None:
    """Extract a tiny synthetic scan once, so loading (or compiling) the compiled
    extraction is not counted as the first view's extraction time."""
    angles = np.linspace(-0.5, 0.5, 2 * params.min_points)
    ranges = np.full(len(angles), 2.0)
    with contextlib.suppress(InputError):  # a lambda narrower than these beams: no matter
        extract_surfaces(Scan(ranges, angles, np.ones(len(angles), bool), 10.0), params)


class _Probe:
    """Reads what one mapper exposes after each view, for its ``steps.csv`` columns.

    Optional, by duck typing: a ``StageTimer`` as ``.timer`` (stage times), a ``.steps``
    list of records with ``.tracked`` (Albot1's ``StepRecord``) and a ``.map`` with a
    length (its global map); ``counts().local_maps`` gives the maps remembered.
    """

    def __init__(self, mapper: Mapper) -> None:
        self.mapper = mapper
        timer = getattr(mapper, "timer", None)
        self.timer = timer if isinstance(timer, StageTimer) else None
        self.has_steps = isinstance(getattr(mapper, "steps", None), list)
        self.has_map = hasattr(getattr(mapper, "map", None), "__len__")
        self.local_maps = 0
        self.shared = False

    def charge_extraction(self, ns: int) -> None:
        """Count a shared extraction to this mapper's stages, as if it had extracted alone."""
        self.shared = True
        if self.timer is not None:
            self.timer.add("extraction", ns)

    def record(self, row: dict[str, Any], name: str, total_ns: int) -> None:
        """Add this view's columns (``total_ns`` includes any shared extraction, which has
        its own column, ``extraction_ms``)."""
        if self.timer is not None:
            for stage, ns in self.timer.take_view().items():
                if not (self.shared and stage == "extraction"):
                    row[f"{name}.{stage}_ms"] = ns / 1e6
        row[f"{name}.total_ms"] = total_ns / 1e6
        # steps and map are not in the Mapper protocol: __init__ checked for them (duck typing).
        steps = self.mapper.steps if self.has_steps else None  # type: ignore[attr-defined]
        if steps:
            row[f"{name}.tracked"] = getattr(steps[-1], "tracked", 0)
        local_maps = self.mapper.counts().local_maps
        row[f"{name}.remembered"] = local_maps - self.local_maps
        self.local_maps = local_maps
        if self.has_map:
            row[f"{name}.map_surfaces"] = len(self.mapper.map)  # type: ignore[attr-defined]  # has_map
