"""A fuzzing episode's metrics, scored for what the campaign reads and nothing more.

A campaign's ``episodes.jsonl`` keeps a handful of numbers per episode (counts, homing
maxima, RPE, end-pose error, map accuracy and completeness). ``albot2d run`` scores much
more (absolute pose error after alignment, egocentric map quality at every homing stop
and at the end, updates by region kind, map-history snapshots), which cost an episode
more than driving and mapping it. ``episode_metrics`` computes only the campaign's numbers
from the run's trace, with the very functions ``score_run`` uses, so they are equal bit
for bit to the ones read off a fully scored run (``tests/test_campaign_speed.py`` checks
it).

A failing episode's reproducer is a full report.json (``albot2d run --reproduce`` compares
the re-run with it), so ``complete_scores`` scores a run made with ``score=False``
completely, as ``run_experiment`` would have: only failing episodes pay for it.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from albot2d.evaluation.fuzz.record import EpisodeMetrics, finite_or_none
from albot2d.evaluation.metrics.map_quality import map_quality
from albot2d.evaluation.run.experiment import ExperimentResult
from albot2d.evaluation.run.results import HomingSummary
from albot2d.evaluation.run.scoring import (
    EvaluationParams,
    end_pose_error,
    homing_section,
    rpe_section,
    score_run,
    trajectory_of,
)
from albot2d.geometry import Pose
from albot2d.logs.relations import relations_from_truth

__all__ = ["complete_scores", "episode_metrics"]


def episode_metrics(result: ExperimentResult, params: EvaluationParams) -> EpisodeMetrics:
    """The metrics of an episode's record: its (only) mapper's and raw odometry's scores,
    computed from the trace of ``result`` (a simulated run, scored or not)."""
    trace = result.trace
    assert trace.true_poses is not None and result.world is not None  # a simulated run
    ((name, mapper),) = trace.mappers.items()
    relations = result.relations or relations_from_truth(
        trace.timestamps, trace.true_poses, options=params.relations
    )
    poses = trajectory_of(name, mapper, trace.n_frames)
    # Homing at the stops without the egocentric map quality there (the record has none).
    home = HomingSummary.of(homing_section(trace, name, None))
    rpe = rpe_section(trace, poses, relations, params.rpe_split_s)
    odo_rpe = rpe_section(trace, trace.odom_poses, relations, params.rpe_split_s)
    end, odo_end = end_pose_error(trace, poses), end_pose_error(trace, trace.odom_poses)
    counts = mapper.counts()
    segments = mapper.global_map().segments
    quality = map_quality(
        segments, result.world.obstacle_segments, start_pose=Pose.from_array(trace.true_poses[0]),
        seen_points=trace.seen_points, params=params.map_quality,
    )  # fmt: skip
    f = finite_or_none
    return EpisodeMetrics(
        frames=int(trace.n_frames), travelled_m=float(trace.travelled_m[-1]),
        collided_frames=int(np.asarray(trace.collided).sum()),
        local_maps=int(counts.local_maps), triangulations=int(counts.triangulations),
        path_integrations=int(counts.path_integrations), global_map_surfaces=len(segments),
        homing_stops=int(home.stops),
        homing_bearing_error_max_deg=f(home.bearing_abs_max_deg),
        homing_distance_error_max_m=f(home.distance_abs_max_m),
        rpe_trans_m=None if rpe is None else f(rpe.overall.trans_m_mean),
        rpe_rot_deg=None if rpe is None else f(rpe.overall.rot_deg_mean),
        odometry_rpe_trans_m=None if odo_rpe is None else f(odo_rpe.overall.trans_m_mean),
        odometry_rpe_rot_deg=None if odo_rpe is None else f(odo_rpe.overall.rot_deg_mean),
        end_trans_m=None if end is None else f(end.trans_m),
        end_rot_deg=None if end is None else f(end.rot_deg),
        odometry_end_trans_m=None if odo_end is None else f(odo_end.trans_m),
        odometry_end_rot_deg=None if odo_end is None else f(odo_end.rot_deg),
        map_accuracy_m=f(quality.accuracy_m_mean),
        map_accuracy_p95_m=f(quality.accuracy_m_p95),
        map_completeness=f(quality.completeness),
    )  # fmt: skip


def complete_scores(result: ExperimentResult, params: EvaluationParams) -> ExperimentResult:
    """``result`` (``run_experiment(..., score=False)`` of a simulated run) scored in full:
    the relations, the typed scores and the report's ``odometry``, ``mappers`` and
    ``run.relations`` sections, as ``run_experiment`` makes them when it scores."""
    if result.relations is not None:  # already scored
        return result
    trace = result.trace
    assert trace.true_poses is not None  # a simulated run
    relations = relations_from_truth(trace.timestamps, trace.true_poses, options=params.relations)
    scores = score_run(trace, relations, params, result.world)
    report = dict(result.report)
    report["run"] = dict(report["run"]) | {"relations": len(relations), "relations_source": "truth"}
    report["odometry"] = scores.odometry.to_dict()
    report["mappers"] = scores.mappers_dict()
    from albot2d.evaluation.run.report import plain

    return dataclasses.replace(result, report=plain(report), relations=relations, scores=scores)
