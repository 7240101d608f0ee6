"""Simulated run directories: the files a simulation leaves behind, and reading them back.

A run directory holds

- ``log.clf``: the raw CARMEN log (what a real robot would have recorded);
- ``truth.txt``: one line per scan, ``ipc_timestamp x y theta`` of the true pose;
- ``log.relations``: Kümmerle relations computed from the truth (see ``relations.py``);
- ``run.json``: format, parameters, counts, file names, and the frames that collided.

All four are written through temporary files and renamed into place only after every one of
them was written, so a failed run leaves no partial files. Timestamps use the log's precision in
all three text files, so relation and truth stamps equal the log's ``ipc_timestamp`` exactly.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import os
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from albot2d import __version__
from albot2d.atomic import atomic_paths
from albot2d.errors import InputError
from albot2d.frames import Frame
from albot2d.geometry import Pose
from albot2d.inputfiles import read_json_file
from albot2d.logs.carmen_writer import LOG_PRECISION, FloatFormat, format_float
from albot2d.logs.log_frames import read_frames, write_carmen
from albot2d.logs.relations import (
    Relations,
    RelationsOptions,
    read_relations,
    relations_from_truth,
    write_relations,
)
from albot2d.logs.textio import atomic_text_output, read_number_table
from albot2d.plainjson import to_plain

__all__ = [
    "LOG_NAME",
    "MANIFEST_NAME",
    "RELATIONS_NAME",
    "RUN_FORMAT",
    "TRUTH_NAME",
    "Run",
    "read_run",
    "read_truth",
    "write_run",
    "write_truth",
]

LOG_NAME = "log.clf"
TRUTH_NAME = "truth.txt"
RELATIONS_NAME = "log.relations"
MANIFEST_NAME = "run.json"
RUN_FORMAT = "albot2d-run"
RUN_FORMAT_VERSION = 1
_TIMESTAMP_MATCH_S = 1e-6

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class Run:
    """A run read back: frames with ``true_pose`` and ``collided`` filled in, and its metadata."""

    directory: Path
    frames: tuple[Frame, ...]
    relations: Relations
    params: dict[str, Any]
    manifest: dict[str, Any]


def write_truth(
    path: str | os.PathLike[str],
    timestamps: ArrayLike,
    poses: ArrayLike,
    *,
    timestamp_decimals: int | None = None,
) -> None:
    """Write ``truth.txt``: poses exactly (``repr``), timestamps at ``timestamp_decimals``."""
    t = np.asarray(timestamps, dtype=np.float64)
    p = np.asarray(poses, dtype=np.float64).reshape(-1, 3)
    if t.shape != (len(p),):
        raise InputError(f"truth needs timestamps (N,) and poses (N, 3), got {t.shape}, {p.shape}")
    with atomic_text_output(path) as out:
        out.write("# albot2d ground truth: one line per laser scan of log.clf\n")
        out.write("# ipc_timestamp x y theta  (true pose, world frame, metres / radians)\n")
        for stamp, (x, y, theta) in zip(t.tolist(), p.tolist(), strict=True):
            out.write(f"{format_float(stamp, timestamp_decimals)} {x!r} {y!r} {theta!r}\n")


def read_truth(path: str | os.PathLike[str]) -> tuple[FloatArray, FloatArray]:
    """Read ``truth.txt`` → ``(timestamps (N,), poses (N, 3))``."""
    table = read_number_table(path, ("ipc_timestamp", "x", "y", "theta"), "truth line")
    return table[:, 0].copy(), table[:, 1:].copy()


def write_run(
    out_dir: str | os.PathLike[str],
    frames: Iterable[Frame],
    *,
    params: Mapping[str, Any] | None = None,
    relations_options: RelationsOptions | None = None,
    float_format: FloatFormat = LOG_PRECISION,
) -> dict[str, Any]:
    """Write a run directory for ``frames`` (streamed once; each needs a ``true_pose``).

    ``params`` (the simulation's settings) go to ``run.json`` and, flattened, to the log's
    PARAMs. Returns the manifest written to ``run.json``.
    """
    directory = Path(out_dir)
    created = not directory.exists()
    directory.mkdir(parents=True, exist_ok=True)
    options = relations_options or RelationsOptions()
    plain_params = to_plain(dict(params or {}), where="params", into="run.json")
    stamps: list[float] = []
    truth: list[tuple[float, float, float]] = []
    collided: list[int] = []

    def recorded() -> Iterator[Frame]:
        for frame in frames:
            if frame.true_pose is None:
                raise InputError(f"frame {frame.index} has no true_pose; a run needs the truth")
            stamps.append(frame.timestamp)
            truth.append((frame.true_pose.x, frame.true_pose.y, frame.true_pose.theta))
            if frame.collided:
                collided.append(len(stamps) - 1)
            yield frame

    try:
        names = (MANIFEST_NAME, LOG_NAME, TRUTH_NAME, RELATIONS_NAME)
        # Given first, renamed last: run.json appears only when everything else is there.
        with atomic_paths(directory / name for name in names) as temps:
            manifest_tmp, log_tmp, truth_tmp, relations_tmp = temps.values()
            n_frames = write_carmen(log_tmp, recorded(), params=params, float_format=float_format)
            t = _rounded(stamps, float_format.timestamp_decimals)
            poses = np.array(truth, dtype=np.float64).reshape(-1, 3)
            write_truth(truth_tmp, t, poses, timestamp_decimals=float_format.timestamp_decimals)
            relations = relations_from_truth(t, poses, options=options)
            write_relations(
                relations_tmp,
                relations,
                timestamp_decimals=float_format.timestamp_decimals,
                header=["albot2d: relations computed from the simulator's true poses"],
            )
            manifest = {
                "format": RUN_FORMAT,
                "format_version": RUN_FORMAT_VERSION,
                "albot2d_version": __version__,
                "files": {"log": LOG_NAME, "truth": TRUTH_NAME, "relations": RELATIONS_NAME},
                "counts": {
                    "frames": n_frames,
                    "relations": len(relations),
                    "collided_frames": len(collided),
                },
                "time_span_s": [float(t[0]), float(t[-1])] if len(t) else None,
                "float_format": dataclasses.asdict(float_format),
                "relations_options": dataclasses.asdict(options),
                "collided_indices": collided,
                "params": plain_params,
            }
            manifest_tmp.write_text(json.dumps(manifest, indent=2) + "\n", encoding="utf-8")
    except BaseException:
        if created:
            with contextlib.suppress(OSError):
                directory.rmdir()  # only succeeds when nothing else was put there
        raise
    return manifest


def _rounded(stamps: list[float], decimals: int | None) -> FloatArray:
    """Timestamps as they read back from the log (so relations refer to the logged values)."""
    return np.array([float(format_float(s, decimals)) for s in stamps], dtype=np.float64)


def read_run(run_dir: str | os.PathLike[str]) -> Run:
    """Read a run directory written by :func:`write_run`."""
    directory = Path(run_dir)
    manifest_path = directory / MANIFEST_NAME
    manifest = read_json_file(manifest_path, "run manifest")
    if not isinstance(manifest, dict) or manifest.get("format") != RUN_FORMAT:
        raise InputError(f"{manifest_path}: not an albot2d run manifest (format != {RUN_FORMAT!r})")
    files = {"log": LOG_NAME, "truth": TRUTH_NAME, "relations": RELATIONS_NAME}
    given = manifest.get("files", {})
    if not isinstance(given, dict) or set(given) - set(files):
        raise InputError(f"{manifest_path}: files must map log, truth, relations to file names")
    for key, name in given.items():
        # Plain names inside the run directory: a manifest may not point elsewhere.
        if not isinstance(name, str) or not name or Path(name).name != name or name in (".", ".."):
            raise InputError(
                f"{manifest_path}: files.{key} must be a file name in the run directory, "
                f"got {str(name)[:60]!r}"
            )
    files |= given
    collided_indices = manifest.get("collided_indices", [])
    if not isinstance(collided_indices, list) or not all(type(k) is int for k in collided_indices):
        raise InputError(f"{manifest_path}: collided_indices must be a list of integers")
    params = manifest.get("params", {})
    if not isinstance(params, dict):
        raise InputError(f"{manifest_path}: params must be an object")
    frames = list(read_frames(directory / files["log"]))
    truth_path = directory / files["truth"]
    t, poses = read_truth(truth_path)
    if len(t) != len(frames):
        raise InputError(f"{truth_path}: {len(t)} poses for {len(frames)} scans in the log")
    collided = set(collided_indices)
    out = []
    for k, frame in enumerate(frames):
        if abs(frame.timestamp - t[k]) > _TIMESTAMP_MATCH_S:
            raise InputError(
                f"{truth_path}: pose {k} has timestamp {float(t[k])!r}, "
                f"but log scan {k} has {frame.timestamp!r}"
            )
        true_pose = Pose.from_array(poses[k])
        out.append(dataclasses.replace(frame, true_pose=true_pose, collided=k in collided))
    return Run(
        directory=directory,
        frames=tuple(out),
        relations=read_relations(directory / files["relations"]),
        params=params,
        manifest=manifest,
    )
