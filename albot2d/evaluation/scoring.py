"""Score a :class:`~albot2d.evaluation.trace.Trace`: the per-mapper sections of report.json.

For each mapper: process counts, homing at the trace's stops, relative pose error against
the relations, absolute pose error after SE(2) alignment (``alignment.ape_section``),
map quality against the true walls, end-pose error, per-stage timings, and
(for view-based mappers with a route map) the moments at which its map history is shown.
Sections that need the truth (simulation) hold ``None`` on real logs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from albot2d.errors import InputError
from albot2d.evaluation.alignment import ape_section
from albot2d.evaluation.egocentric import EgocentricQuality, egocentric_quality
from albot2d.evaluation.homing import homing
from albot2d.evaluation.map_quality import MapQualityParams, map_quality
from albot2d.evaluation.rpe import relative_pose_error
from albot2d.evaluation.trace import HomingParams, Stop, Trace
from albot2d.geometry import Pose, between_arrays, wrap_angle
from albot2d.logs.relations import Relations, RelationsOptions
from albot2d.mapping.protocol import Mapper
from albot2d.mapping.route_map import RouteMap
from albot2d.validation import check_positive, check_positive_int

__all__ = [
    "MAX_SNAPSHOTS",
    "EvaluationParams",
    "end_pose_error",
    "homing_section",
    "odometry_section",
    "route_of",
    "rpe_section",
    "score_mappers",
    "snapshot_rows",
]

FloatArray = NDArray[np.float64]
# A view touching a map this many local maps back counts as a revisit (the authors' code
# splits deletion groups at gaps of 20 views; a revisit is what crosses such a gap).
REVISIT_GAP_MAPS = 20
_MAP_FIELDS = ("accuracy_m_mean", "accuracy_m_p95", "accuracy_m_max", "completeness")


#: Most map-history moments a run draws and reports (each is a full map drawn in a figure).
MAX_SNAPSHOTS = 100


@dataclass(frozen=True, slots=True)
class EvaluationParams:
    """How a run is scored.

    - ``rpe_split_s``: relations spanning less than this are "short" (Kümmerle: 2 s).
    - ``snapshots``: moments (evenly spread, the last at the end) at which a view-based
      mapper's global map is shown in the history figure and listed in the report.
    """

    homing: HomingParams = field(default_factory=HomingParams)
    map_quality: MapQualityParams = field(default_factory=MapQualityParams)
    relations: RelationsOptions = field(default_factory=RelationsOptions)
    rpe_split_s: float = 2.0
    snapshots: int = 4

    def __post_init__(self) -> None:
        check_positive(self, "rpe_split_s")
        check_positive_int(self, "snapshots", maximum=MAX_SNAPSHOTS)


def route_of(mapper: Mapper) -> RouteMap | None:
    """The mapper's route map when it is view-based like Albot1, else None."""
    route = getattr(mapper, "route", None)
    return route if isinstance(route, RouteMap) else None


def revisits_section(mapper: Mapper, min_gap_maps: int) -> dict[str, Any] | None:
    """Transience on revisits (paper Fig. 10): updates whose view touched a map more than
    ``min_gap_maps`` maps back in the route, and how many surfaces each deleted."""
    log = getattr(mapper, "update_log", None)
    if not isinstance(log, list):
        return None
    events = [
        {"map_id": u.map_id, "view": u.frame_index, "oldest_map": u.oldest_affected,
         "deleted": u.deleted_current + u.deleted_older}
        for u in log if u.oldest_affected >= 0 and u.map_id - u.oldest_affected > min_gap_maps
    ]  # fmt: skip
    return {
        "min_gap_maps": min_gap_maps,
        "updates": len(events),
        "deleted_surfaces": int(sum(e["deleted"] for e in events)),
        "events": events,
    }


def trajectory_of(name: str, mapper: Mapper, n_frames: int) -> FloatArray:
    """The mapper's ``(F, 3)`` trajectory, checked to have one pose per observed frame."""
    poses = np.asarray(mapper.trajectory(), dtype=np.float64)
    if poses.shape != (n_frames, 3) or not np.all(np.isfinite(poses)):
        raise InputError(
            f"mapper {name!r}: trajectory() gave shape {poses.shape} (finite: "
            f"{bool(np.all(np.isfinite(poses)))}), expected ({n_frames}, 3) finite poses"
        )
    return poses


def rpe_section(
    trace: Trace, poses: FloatArray, relations: Relations | None, split_s: float
) -> dict[str, Any] | None:
    """Kümmerle RPE of ``poses`` (one per trace row) against ``relations``; None without any."""
    if relations is None:
        return None
    result = relative_pose_error(
        trace.timestamps, poses, relations.t1, relations.t2, relations.motion, split_s=split_s
    )
    return result.to_dict()


def end_pose_error(trace: Trace, poses: FloatArray) -> dict[str, float] | None:
    """Error of the estimated motion from the first to the last view (needs the truth)."""
    if trace.true_poses is None:
        return None
    truth = between_arrays(trace.true_poses[0], trace.true_poses[-1])
    est = between_arrays(poses[0], poses[-1])
    err = between_arrays(truth, est)
    return {
        "trans_m": float(math.hypot(err[0], err[1])),
        "rot_deg": abs(math.degrees(float(wrap_angle(err[2])))),
    }


def homing_section(trace: Trace, name: str) -> list[dict[str, Any]]:
    """Bearing (deg, + = turn left) and distance (m) to the start at each stop."""
    out = []
    for stop in trace.stops:
        pose, start = stop.estimates[name]
        bearing_est, distance_est = homing(Pose.from_array(pose), start[:2])
        entry: dict[str, Any] = {
            "view": int(trace.frame_indices[stop.row]),
            "travelled_m": stop.travelled_m,
            "bearing_est_deg": bearing_est,
            "bearing_true_deg": None,
            "distance_est_m": distance_est,
            "distance_true_m": None,
            "bearing_error_deg": None,
            "distance_error_m": None,
        }
        if trace.true_poses is not None:
            bt, dt = homing(Pose.from_array(trace.true_poses[stop.row]), trace.true_poses[0, :2])
            diff = math.degrees(float(wrap_angle(math.radians(bearing_est - bt))))
            entry |= {"bearing_true_deg": bt, "distance_true_m": dt,
                      "bearing_error_deg": diff, "distance_error_m": distance_est - dt}
        out.append(entry)
    return out


def homing_summary(entries: list[dict[str, Any]]) -> dict[str, Any]:
    """Worst and mean absolute homing errors (None without truth or stops)."""
    errors = [(e["bearing_error_deg"], e["distance_error_m"]) for e in entries
              if e["bearing_error_deg"] is not None]
    if not errors:
        return {"stops": len(entries), "bearing_abs_max_deg": None, "bearing_abs_mean_deg": None,
                "distance_abs_max_m": None, "distance_abs_mean_m": None}
    b, d = np.abs(np.array(errors, dtype=np.float64)).T
    return {"stops": len(entries), "bearing_abs_max_deg": float(b.max()),
            "bearing_abs_mean_deg": float(b.mean()), "distance_abs_max_m": float(d.max()),
            "distance_abs_mean_m": float(d.mean())}


def snapshot_rows(trace: Trace, n: int) -> list[int]:
    """``n`` trace rows spread evenly over the run, the last one at its end (ascending)."""
    f = trace.n_frames
    return sorted({max(math.ceil(f * k / n) - 1, 0) for k in range(1, n + 1)})


def _map_rows(trace: Trace, route: RouteMap) -> NDArray[np.int64]:
    """Trace row of each local map's view."""
    frame_indices = np.array([m.frame_index for m in route], dtype=np.int64)
    order = np.argsort(trace.frame_indices, kind="stable")
    pos = np.searchsorted(trace.frame_indices[order], frame_indices)
    return order[np.clip(pos, 0, len(order) - 1)]


def counts_section(trace: Trace, mapper: Mapper) -> dict[str, Any]:
    counts = mapper.counts()
    out: dict[str, Any] = {
        "views": counts.views,
        "local_maps": counts.local_maps,
        "triangulations": counts.triangulations,
        "path_integrations": counts.path_integrations,
        "global_map_surfaces": len(mapper.global_map().segments),
        "moves_between_updates_mean": (
            counts.views / counts.local_maps if counts.local_maps else None
        ),
        "moves_between_updates_max": None,
        "metres_between_updates_mean": None,
    }
    slam_stats = getattr(mapper, "slam_stats", None)
    if callable(slam_stats):
        # Loop-closing mappers: keyframes, closure candidates accepted/rejected, optimisations.
        out["loop_closures"] = dict(slam_stats())
    route = route_of(mapper)
    if route is not None and len(route) > 1:
        rows = _map_rows(trace, route)
        moves = np.diff(rows)
        out["moves_between_updates_mean"] = float(moves.mean())
        out["moves_between_updates_max"] = int(moves.max())
        out["metres_between_updates_mean"] = float(np.diff(trace.travelled_m[rows]).mean())
    return out


def snapshots_section(trace: Trace, mapper: Mapper, n: int) -> list[dict[str, Any]] | None:
    """The history moments of a view-based mapper: view, update number, surfaces then."""
    route = route_of(mapper)
    if route is None:
        return None
    map_frames = np.array([m.frame_index for m in route], dtype=np.int64)
    out = []
    for row in snapshot_rows(trace, n):
        view = int(trace.frame_indices[row])
        update = int(np.count_nonzero(map_frames <= view))
        # at_update (the map's history) is not in the Mapper protocol; route_of() found one.
        surfaces = len(mapper.global_map(at_update=update).segments)  # type: ignore[call-arg]
        out.append({"view": view, "row": row, "travelled_m": float(trace.travelled_m[row]),
                    "update": update, "surfaces": surfaces})
    return out


def egocentric_at(
    trace: Trace, stop: Stop | None, name: str, world_segments: FloatArray | None
) -> EgocentricQuality | None:
    """Egocentric map quality of mapper ``name`` at a captured stop (None without truth)."""
    if (
        stop is None or stop.seen is None or name not in stop.maps
        or world_segments is None or trace.true_poses is None
    ):  # fmt: skip
        return None
    local, surfaces = stop.maps[name]
    return egocentric_quality(
        stop.seen, local, world_segments, trace.true_poses[stop.row], trace.egocentric,
        surfaces=surfaces,
    )  # fmt: skip


def map_section(
    trace: Trace,
    mapper: Mapper,
    world_segments: FloatArray | None,
    params: MapQualityParams,
    name: str | None = None,
) -> dict[str, Any]:
    """Map accuracy and completeness against the true walls (None fields on real logs),
    anchored at the start, and egocentric (from the robot's place at the end)."""
    segments = mapper.global_map().segments
    ego = egocentric_at(trace, trace.final, name or mapper.name, world_segments)
    ego_dict = ego.to_dict() if ego is not None else None
    if world_segments is None or trace.true_poses is None:
        return dict.fromkeys(_MAP_FIELDS) | {"surfaces": len(segments), "egocentric": ego_dict}
    quality = map_quality(
        segments, world_segments, start_pose=Pose.from_array(trace.true_poses[0]),
        seen_points=trace.seen_points, params=params,
    )  # fmt: skip
    return quality.to_dict() | {"egocentric": ego_dict}


def odometry_section(
    trace: Trace, relations: Relations | None, params: EvaluationParams
) -> dict[str, Any]:
    """Raw odometry scored like a mapper (its trajectory is the odometry poses)."""
    return {
        "rpe": rpe_section(trace, trace.odom_poses, relations, params.rpe_split_s),
        "end_pose_error": end_pose_error(trace, trace.odom_poses),
        "ape": ape_section(trace.timestamps, trace.odom_poses, trace.true_poses),
    }


def score_mappers(
    trace: Trace,
    relations: Relations | None,
    world_segments: FloatArray | None,
    params: EvaluationParams,
) -> dict[str, dict[str, Any]]:
    """The ``mappers`` section of report.json, in the order the mappers were given."""
    out: dict[str, dict[str, Any]] = {}
    for name, mapper in trace.mappers.items():
        poses = trajectory_of(name, mapper, trace.n_frames)
        entries = homing_section(trace, name)
        for entry, stop in zip(entries, trace.stops, strict=True):
            ego = egocentric_at(trace, stop, name, world_segments)
            entry["egocentric_completeness"] = None if ego is None else ego.completeness
            entry["egocentric_accuracy_m_p95"] = None if ego is None else ego.accuracy_m_p95
        timing = dict(mapper.timings_ms())
        timing["total"] = trace.wall_ms.get(name, 0.0) / max(trace.n_frames, 1)
        out[name] = {
            "counts": counts_section(trace, mapper),
            "homing": entries,
            "homing_summary": homing_summary(entries),
            "rpe": rpe_section(trace, poses, relations, params.rpe_split_s),
            "end_pose_error": end_pose_error(trace, poses),
            "ape": ape_section(trace.timestamps, poses, trace.true_poses),
            "map": map_section(trace, mapper, world_segments, params.map_quality, name),
            "snapshots": snapshots_section(trace, mapper, params.snapshots),
            "revisits": revisits_section(mapper, REVISIT_GAP_MAPS),
            "timing_ms": timing,
        }
    return out
