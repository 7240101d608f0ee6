"""Run-folder exports that the field's tools read: TUM trajectories and CSV maps.

For a finished run or replay (an ``ExperimentResult``), ``export_files`` gives the bytes
of, per mapper ``NAME``, ``traj_NAME.tum`` (its pose at every view) and ``map_NAME.csv``
(its final global map), plus ``odometry.tum`` (raw odometry) and, in simulation,
``groundtruth.tum``. TUM lines are ``timestamp x y z qx qy qz qw`` (z = 0, rotation about
z), the format ``evo`` reads: ``evo_ape tum groundtruth.tum traj_albot1.tum --align``
gives the APE that report.json lists. CSV rows are ``x1,y1,x2,y2,map_id``.

Frames: with the truth, every trajectory and map is expressed in the world frame, anchored
at the first true pose (``alignment.in_world_frame``), so all files overlay the world;
on a real log they stay in each mapper's own frame (first view = origin) and odometry in
the log's odometry frame.
"""

from __future__ import annotations

import io
import re
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from albot2d.evaluation.metrics.alignment import in_world_frame, map_in_world_frame
from albot2d.geometry import between_arrays

__all__ = ["GROUNDTRUTH_NAME", "ODOMETRY_NAME", "export_files", "segments_csv", "tum_text"]

GROUNDTRUTH_NAME = "groundtruth.tum"
ODOMETRY_NAME = "odometry.tum"
_UNSAFE = re.compile(r"[^A-Za-z0-9_.-]+")
_CSV_BLOCK_ROWS = 4096


def tum_text(timestamps: ArrayLike, poses: ArrayLike) -> str:
    """``(F,)`` timestamps and ``(F, 3)`` planar poses as a TUM trajectory file."""
    t = np.asarray(timestamps, dtype=np.float64).reshape(-1)
    p = np.asarray(poses, dtype=np.float64).reshape(-1, 3)
    half = p[:, 2] / 2.0
    zeros = np.zeros(len(p))
    rows = np.column_stack([t, p[:, 0], p[:, 1], zeros, zeros, zeros, np.sin(half), np.cos(half)])
    out = io.StringIO()
    out.write("# timestamp x y z qx qy qz qw\n")
    np.savetxt(out, rows, fmt="%.6f %.9f %.9f %.1f %.1f %.1f %.12f %.12f")
    return out.getvalue()


def segments_csv(segments: ArrayLike, map_ids: ArrayLike) -> str:
    """``(M, 4)`` segments and their ``(M,)`` local-map ids as CSV with a header."""
    s = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
    ids = np.asarray(map_ids, dtype=np.int64).reshape(-1)
    if len(s) != len(ids):
        raise ValueError(f"segments_csv: {len(s)} segments but {len(ids)} map ids")
    # Row blocks, each joined at once: a long map's rows as Python floats, or as one string
    # object per row (what StringIO keeps until getvalue), cost ~190 / ~100 bytes a row.
    blocks = ["x1,y1,x2,y2,map_id\n"]
    for lo in range(0, len(s), _CSV_BLOCK_ROWS):
        hi = lo + _CSV_BLOCK_ROWS
        rows = zip(s[lo:hi].tolist(), ids[lo:hi].tolist(), strict=True)
        blocks.append("".join(f"{x1:.6f},{y1:.6f},{x2:.6f},{y2:.6f},{k}\n"
                              for (x1, y1, x2, y2), k in rows))  # fmt: skip
    return "".join(blocks)


def file_stem(name: str) -> str:
    """A mapper's report name made safe as part of a file name."""
    return _UNSAFE.sub("_", name) or "mapper"


def export_files(result: Any) -> dict[str, bytes]:
    """The TUM and CSV files of a run or replay (see the module docstring)."""
    trace = result.trace
    truth = trace.true_poses
    start = truth[0] if truth is not None else None
    files: dict[str, bytes] = {}  # encoded as made: never every file twice
    odometry = trace.odom_poses
    if start is not None:
        files[GROUNDTRUTH_NAME] = tum_text(trace.timestamps, truth).encode("utf-8")
        odometry = in_world_frame(between_arrays(odometry[0], odometry), start)
    files[ODOMETRY_NAME] = tum_text(trace.timestamps, odometry).encode("utf-8")
    for name, mapper in trace.mappers.items():
        poses = np.asarray(mapper.trajectory(), dtype=np.float64).reshape(-1, 3)
        snapshot = mapper.global_map()
        segments = np.asarray(snapshot.segments, dtype=np.float64).reshape(-1, 4)
        if start is not None:
            poses = in_world_frame(poses, start)
            segments = map_in_world_frame(segments, start)
        stem = file_stem(name)
        files[f"traj_{stem}.tum"] = tum_text(trace.timestamps, poses).encode("utf-8")
        files[f"map_{stem}.csv"] = segments_csv(segments, snapshot.map_ids).encode("utf-8")
    return files
