"""Replay a recorded CARMEN log or ROS bag (real or simulated) through the mappers; score them.

A bag (``.bag``, ``.mcap``, ``.db3`` or a ROS 2 bag directory) is read by
``albot2d.logs.rosbag`` from its scan and odometry topics; everything after reading is the
same as for a CARMEN log.

Real logs carry no ground truth, so only what the relations file (Kümmerle et al. 2009) can
judge is measured: relative pose error of every mapper and of raw odometry, overall and
split into short and long relations. Homing gives each mapper's estimates with the true
values ``null``; map quality is ``null``. The ``truth`` mapper cannot run on a log.

Without an explicit relations file one is looked for beside the log: ``NAME.relations``
next to ``NAME.clf[.gz]`` (this is where ``albot2d simulate`` puts it, as ``log.relations``)
or in a sibling ``relations/`` folder (the layout of the shared MIT CSAIL data); a bag in
a simulated run directory (beside its ``run.json``) uses the run's ``log.relations``.

The log's frames are put in time order first (``albot2d.logs.anomalies``: sorted by
timestamp, repeated timestamps dropped) and its anomalies (non-finite and negative ranges,
out-of-order and duplicate timestamps) are counted in the report's ``log.anomalies``;
with ``strict`` any anomaly refuses the log instead.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import numpy as np

from albot2d.errors import InputError
from albot2d.evaluation.run.experiment import ExperimentResult, evaluation_params_dict
from albot2d.evaluation.run.report import make_report
from albot2d.evaluation.run.scoring import EvaluationParams, score_run
from albot2d.evaluation.run.trace import drive_mappers
from albot2d.frames import Frame
from albot2d.logs.anomalies import ordered_frames
from albot2d.logs.log_frames import read_frames
from albot2d.logs.relations import Relations, read_relations
from albot2d.logs.rosbag import DEFAULT_ODOM_TOPIC, DEFAULT_SCAN_TOPIC, is_bag, read_bag
from albot2d.logs.run_files import MANIFEST_NAME, RELATIONS_NAME
from albot2d.mapping.protocol import Mapper
from albot2d.mapping.registry import resolve_mappers

__all__ = ["DEFAULT_REPLAY_MAPPERS", "find_relations", "log_stem", "replay_log"]

DEFAULT_REPLAY_MAPPERS = ("albot1", "naive")
_LOG_SUFFIXES = (".clf.gz", ".log.gz", ".gz", ".clf", ".log", ".bag", ".mcap", ".db3")
_NEEDS_TRUTH = ("truth",)


def log_stem(path: str | os.PathLike[str]) -> str:
    """The log's name without its log/gzip suffix (``mit-csail.clf.gz`` → ``mit-csail``)."""
    name = Path(path).name
    for suffix in _LOG_SUFFIXES:
        if name.endswith(suffix) and len(name) > len(suffix):
            return name[: -len(suffix)]
    return name


def find_relations(log: str | os.PathLike[str]) -> Path | None:
    """A relations file for ``log`` in the usual places (see the module docstring), or None."""
    path = Path(log)
    stem = log_stem(path)
    for candidate in (
        path.parent / f"{stem}.relations",
        path.parent.parent / "relations" / f"{stem}.relations",
    ):
        if candidate.is_file():
            return candidate
    run_relations = path.parent / RELATIONS_NAME
    if (path.parent / MANIFEST_NAME).is_file() and run_relations.is_file():
        return run_relations  # a bag exported into a simulated run directory
    return None


def check_replay_mappers(specs: Sequence[str]) -> None:
    """Refuse mappers that need ground truth, which a log does not have."""
    for spec in specs:
        if spec in _NEEDS_TRUTH:
            raise InputError(
                f"mapper {spec!r} needs the true pose of every frame, which a CARMEN log does "
                "not have; use it with `albot2d run`"
            )


def _check_beam_spacing(log_path: Path, frame: Frame) -> None:
    """Refuse, naming the log, a laser too coarse for the mappers' surface extraction."""
    from albot2d.perception.extraction import ExtractionParams

    angles = frame.scan.angles
    spacing = float(np.degrees(np.abs(np.diff(angles)).max())) if len(angles) > 1 else 0.0
    limit = ExtractionParams().breakpoint_lambda_deg
    if spacing >= limit:
        raise InputError(
            f"{log_path}: the laser's beams are {spacing:.3g} deg apart (its PARAM "
            f"laser_front_laser_fov/resolution or ROBOTLASER1 angles); the mappers need "
            f"them less than {limit:g} deg apart"
        )


def replay_log(
    log: str | os.PathLike[str],
    *,
    relations_path: str | os.PathLike[str] | None = None,
    mappers: Sequence[str] = DEFAULT_REPLAY_MAPPERS,
    params: EvaluationParams | None = None,
    max_frames: int | None = None,
    on_frame: Callable[[Frame, float], None] | None = None,
    on_stage: Callable[[str], None] | None = None,
    strict: bool = False,
    scan_topic: str | None = None,
    odom_topic: str | None = None,
    on_mappers: Callable[[Mapping[str, Mapper]], None] | None = None,
) -> ExperimentResult:
    """Map ``log`` with every mapper and score against ``relations_path`` (found if None).

    ``on_frame(frame, travelled_m)`` is called after each frame and ``on_stage("scoring")``
    after the last one (progress display); ``on_mappers(mappers)`` once the mappers are
    made, before the first frame (e.g. a viewer). ``strict`` turns any log anomaly into an
    ``InputError`` (see the module docstring). ``scan_topic`` and ``odom_topic`` (default
    ``/scan``, ``/odom``) choose a bag's topics.
    """
    params = params or EvaluationParams()
    t0 = time.perf_counter()
    log_path = Path(log)
    bag = is_bag(log_path) and log_path.exists()
    if not (log_path.is_file() or bag):
        raise InputError(f"{log_path}: no such log file")
    if not bag and (scan_topic is not None or odom_topic is not None):
        raise InputError(f"{log_path}: scan and odometry topics apply to ROS bags only")
    check_replay_mappers(mappers)
    factories = resolve_mappers(list(mappers))
    rel_path = Path(relations_path) if relations_path is not None else find_relations(log_path)
    relations: Relations | None = None
    if rel_path is not None:
        if not rel_path.is_file():
            raise InputError(f"{rel_path}: no such relations file")
        relations = read_relations(rel_path)
    if max_frames is not None and (isinstance(max_frames, bool) or max_frames <= 0):
        raise InputError(f"max_frames must be a positive integer, got {max_frames!r}")
    bag_info = None
    if bag:
        bag_frames = read_bag(
            log_path, scan_topic=scan_topic or DEFAULT_SCAN_TOPIC,
            odom_topic=odom_topic or DEFAULT_ODOM_TOPIC,
        )  # fmt: skip
        bag_info = bag_frames.as_dict()
        frames, anomalies = ordered_frames(bag_frames.frames)
    else:
        frames, anomalies = ordered_frames(read_frames(log_path))
    if strict and anomalies.total:
        raise InputError(f"{log_path}: log anomalies (strict): {anomalies.summary()}")
    if frames and any(":" not in spec for spec in mappers):  # built-ins extract surfaces
        _check_beam_spacing(log_path, frames[0])
    instances = {name: factory() for name, factory in factories.items()}
    if on_mappers is not None:
        on_mappers(instances)
    trace = drive_mappers(
        frames, instances, homing=params.homing, last_k_views=params.map_quality.last_k_views,
        max_frames=max_frames, on_frame=on_frame, source=os.fspath(log_path),
    )  # fmt: skip
    if on_stage is not None:
        on_stage("scoring")
    scores = score_run(trace, relations, params)
    rpe = scores.odometry.rpe
    used = 0 if rpe is None else rpe.overall.relations
    log_info = {
        "path": os.fspath(log_path),
        "relations_path": None if rel_path is None else os.fspath(rel_path),
        "frames": trace.n_frames,
        "duration_s": float(trace.timestamps[-1] - trace.timestamps[0]),
        "travelled_m": float(trace.travelled_m[-1]),
        "relations": None if relations is None else len(relations),
        "relations_used": None if relations is None else used,
        "relations_source": None if rel_path is None else "file",
    }
    report = make_report(
        "replay",
        seed=None,
        world=None,
        profile=None,
        params={
            "log": os.fspath(log_path),
            "relations_file": None if rel_path is None else os.fspath(rel_path),
            "mappers": list(mappers),
            "max_frames": max_frames,
            # Relations come from the file, so the options for making them do not apply.
            **{k: v for k, v in evaluation_params_dict(params).items() if k != "relations"},
        },
        run=log_info,
        log={
            "path": os.fspath(log_path),
            "anomalies": anomalies.as_dict(),
            **({"bag": bag_info} if bag_info is not None else {}),
        },
        odometry=scores.odometry.to_dict(),
        mappers=scores.mappers_dict(),
        timing_ms=trace.step_times.summary_ms(),  # per-view stage times (steps.csv)
        figures=[],
        wall_time_s=time.perf_counter() - t0,
    )
    title = f"{log_path.name}  {trace.n_frames} views  {trace.travelled_m[-1]:.0f} m (odometry)"
    return ExperimentResult(report, trace, None, None, relations, title, scores)
