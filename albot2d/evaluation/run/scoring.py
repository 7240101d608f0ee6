"""Score a :class:`~albot2d.evaluation.trace.Trace` into typed results (``results.RunScores``).

``score_run`` scores raw odometry and every mapper; report.json's ``odometry``/``mappers``
sections are ``RunScores``'s ``to_dict`` views. For each mapper: process counts, homing at
the trace's stops, relative pose error against the relations, absolute pose error after
SE(2) alignment (``alignment.ape_result``), map quality against the true walls, end-pose
error, per-stage timings, (for view-based mappers with a route map) the moments at which
its map history is shown, and (simulated runs) the updates by region kind. Sections that
need the truth (simulation) hold ``None`` on real logs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from albot2d.errors import InputError
from albot2d.evaluation.metrics.alignment import ape_result
from albot2d.evaluation.metrics.egocentric import EgocentricQuality, egocentric_quality
from albot2d.evaluation.metrics.homing import homing_to_start
from albot2d.evaluation.metrics.map_quality import MapQuality, MapQualityParams, map_quality
from albot2d.evaluation.metrics.rpe import RPEResult, relative_pose_error
from albot2d.evaluation.run.results import (
    EndPoseError,
    HomingStop,
    HomingSummary,
    MapperScores,
    MapScore,
    OdometryScores,
    ProcessCounts,
    RevisitEvent,
    Revisits,
    RunScores,
    Snapshot,
)
from albot2d.evaluation.run.trace import HomingParams, Stop, Trace
from albot2d.geometry import Pose, between_arrays, wrap_angle
from albot2d.logs.relations import Relations, RelationsOptions
from albot2d.mapping.albot1.route_map import RouteMap
from albot2d.mapping.protocol import LoopClosingMapper, Mapper, ViewBasedMapper
from albot2d.validation import check_positive, check_positive_int

if TYPE_CHECKING:
    from worldgen.world import World

__all__ = [
    "MAX_SNAPSHOTS",
    "EvaluationParams",
    "end_pose_error",
    "homing_section",
    "odometry_scores",
    "route_of",
    "rpe_section",
    "score_mappers",
    "score_run",
    "snapshot_rows",
]

FloatArray = NDArray[np.float64]
# A view touching a map this many local maps back counts as a revisit (the authors' code
# splits deletion groups at gaps of 20 views; a revisit is what crosses such a gap).
REVISIT_GAP_MAPS = 20


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
    return mapper.route_map() if isinstance(mapper, ViewBasedMapper) else None


def revisits_section(mapper: Mapper, min_gap_maps: int) -> Revisits | None:
    """Transience on revisits (paper Fig. 10): updates whose view touched a map more than
    ``min_gap_maps`` maps back in the route, and how many surfaces each deleted."""
    if not isinstance(mapper, ViewBasedMapper):
        return None
    log = mapper.update_log
    return Revisits(min_gap_maps, tuple(
        RevisitEvent(u.map_id, u.frame_index, u.oldest_affected,
                     u.deleted_current + u.deleted_older)
        for u in log if u.oldest_affected >= 0 and u.map_id - u.oldest_affected > min_gap_maps
    ))  # fmt: skip


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
) -> RPEResult | None:
    """Kümmerle RPE of ``poses`` (one per trace row) against ``relations``; None without any."""
    if relations is None:
        return None
    return relative_pose_error(
        trace.timestamps, poses, relations.t1, relations.t2, relations.motion, split_s=split_s
    )


def end_pose_error(trace: Trace, poses: FloatArray) -> EndPoseError | None:
    """Error of the estimated motion from the first to the last view (needs the truth)."""
    if trace.true_poses is None:
        return None
    truth = between_arrays(trace.true_poses[0], trace.true_poses[-1])
    est = between_arrays(poses[0], poses[-1])
    err = between_arrays(truth, est)
    return EndPoseError(
        trans_m=float(math.hypot(err[0], err[1])),
        rot_deg=abs(math.degrees(float(wrap_angle(err[2])))),
    )


def homing_section(
    trace: Trace, name: str, world_segments: FloatArray | None = None
) -> tuple[HomingStop, ...]:
    """Bearing (deg, + = turn left) and distance (m) to the start at each stop, with the
    egocentric map quality there when the world is known."""
    out = []
    for stop in trace.stops:
        pose, start = stop.estimates[name]
        view = int(trace.frame_indices[stop.row])
        truth = trace.true_poses
        result = (
            homing_to_start(view, pose, start)
            if truth is None
            else homing_to_start(view, pose, start, truth[stop.row], truth[0])
        )
        ego = egocentric_at(trace, stop, name, world_segments)
        out.append(HomingStop(result, stop.travelled_m, ego))
    return tuple(out)


def homing_summary(stops: tuple[HomingStop, ...]) -> HomingSummary:
    """Worst and mean absolute homing errors (None without truth or stops)."""
    return HomingSummary.of(stops)


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


def counts_section(trace: Trace, mapper: Mapper) -> ProcessCounts:
    counts = mapper.counts()
    moves_mean = counts.views / counts.local_maps if counts.local_maps else None
    moves_max = metres_mean = loop_closures = None
    if isinstance(mapper, LoopClosingMapper):
        # Loop-closing mappers: keyframes, closure candidates accepted/rejected, optimisations.
        loop_closures = dict(mapper.slam_stats())
    route = route_of(mapper)
    if route is not None and len(route) > 1:
        rows = _map_rows(trace, route)
        moves = np.diff(rows)
        moves_mean = float(moves.mean())
        moves_max = int(moves.max())
        metres_mean = float(np.diff(trace.travelled_m[rows]).mean())
    return ProcessCounts(
        views=counts.views, local_maps=counts.local_maps,
        triangulations=counts.triangulations, path_integrations=counts.path_integrations,
        global_map_surfaces=len(mapper.global_map().segments),
        moves_between_updates_mean=moves_mean, moves_between_updates_max=moves_max,
        metres_between_updates_mean=metres_mean, loop_closures=loop_closures,
    )  # fmt: skip


def snapshots_section(trace: Trace, mapper: Mapper, n: int) -> tuple[Snapshot, ...] | None:
    """The history moments of a view-based mapper: view, update number, surfaces then."""
    if not isinstance(mapper, ViewBasedMapper):
        return None
    map_frames = np.array([m.frame_index for m in mapper.route_map()], dtype=np.int64)
    out = []
    for row in snapshot_rows(trace, n):
        view = int(trace.frame_indices[row])
        update = int(np.count_nonzero(map_frames <= view))
        surfaces = len(mapper.global_map(at_update=update).segments)
        out.append(Snapshot(view, row, float(trace.travelled_m[row]), update, surfaces))
    return tuple(out)


def egocentric_at(
    trace: Trace, stop: Stop | None, name: str, world_segments: FloatArray | None
) -> EgocentricQuality | None:
    """Egocentric map quality of mapper ``name`` at a captured stop (None without truth).

    A stop scored while driving (``drive_mappers(walls=...)``) has it already: those walls
    are the world's, which ``world_segments`` must then be too."""
    if stop is None or world_segments is None or trace.true_poses is None:
        return None
    if name in stop.egocentric:
        return stop.egocentric[name]
    if stop.seen is None or name not in stop.maps:
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
) -> MapScore:
    """Map accuracy and completeness against the true walls (None fields on real logs),
    anchored at the start, and egocentric (from the robot's place at the end)."""
    segments = mapper.global_map().segments
    ego = egocentric_at(trace, trace.final, name or mapper.name, world_segments)
    if world_segments is None or trace.true_poses is None:
        return MapScore(MapQuality(None, None, None, None, len(segments)), ego)
    quality = map_quality(
        segments, world_segments, start_pose=Pose.from_array(trace.true_poses[0]),
        seen_points=trace.seen_points, params=params,
    )  # fmt: skip
    return MapScore(quality, ego)


def odometry_scores(
    trace: Trace, relations: Relations | None, params: EvaluationParams
) -> OdometryScores:
    """Raw odometry scored like a mapper (its trajectory is the odometry poses)."""
    return OdometryScores(
        rpe=rpe_section(trace, trace.odom_poses, relations, params.rpe_split_s),
        end_pose_error=end_pose_error(trace, trace.odom_poses),
        ape=ape_result(trace.timestamps, trace.odom_poses, trace.true_poses),
    )


def score_mappers(
    trace: Trace,
    relations: Relations | None,
    world_segments: FloatArray | None,
    params: EvaluationParams,
    world: World | None = None,
) -> dict[str, MapperScores]:
    """Every mapper's scores, in the order the mappers were given. With the ``world``
    (a simulated run), the global-map updates are also counted by region kind (Fig. 14)."""
    from albot2d.evaluation.metrics.updates import updates_section

    out: dict[str, MapperScores] = {}
    for name, mapper in trace.mappers.items():
        poses = trajectory_of(name, mapper, trace.n_frames)
        stops = homing_section(trace, name, world_segments)
        timing = dict(mapper.timings_ms())
        timing["total"] = trace.wall_ms.get(name, 0.0) / max(trace.n_frames, 1)
        out[name] = MapperScores(
            counts=counts_section(trace, mapper),
            homing=stops,
            homing_summary=homing_summary(stops),
            rpe=rpe_section(trace, poses, relations, params.rpe_split_s),
            end_pose_error=end_pose_error(trace, poses),
            ape=ape_result(trace.timestamps, poses, trace.true_poses),
            map=map_section(trace, mapper, world_segments, params.map_quality, name),
            snapshots=snapshots_section(trace, mapper, params.snapshots),
            revisits=revisits_section(mapper, REVISIT_GAP_MAPS),
            timing_ms=timing,
            updates_by_region=None if world is None else updates_section(world, trace, mapper),
            regions_scored=world is not None,
        )
    return out


def score_run(
    trace: Trace,
    relations: Relations | None,
    params: EvaluationParams,
    world: World | None = None,
) -> RunScores:
    """Raw odometry and every mapper scored; ``world`` for a simulated run (None: a log)."""
    segments = None if world is None else world.obstacle_segments
    return RunScores(
        odometry_scores(trace, relations, params),
        score_mappers(trace, relations, segments, params, world),
    )
