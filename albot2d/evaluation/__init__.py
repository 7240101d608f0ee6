"""Evaluation: relative pose error, homing, map quality, and the experiments that use them.

- ``experiment``: ``run_experiment(RunSpec)`` — world, tour, simulator, every mapper, report;
- ``replay``: ``replay_log(path)`` — the same on a recorded CARMEN log and its relations;
- ``setup``: ``build_run(RunSpec)`` — the one path from a run description to world, tour
  and simulator;
- ``trace`` / ``scoring``: stream frames through the mappers once, then score the trace
  into typed ``results`` (report.json, tables, figures and fuzz metrics are views);
- ``report``: report.json's header, writing, reading and the printed tables;
- ``rpe``, ``homing``, ``map_quality``: the metrics themselves;
- ``alignment``: a mapper's frame → the world frame, APE after SE(2) alignment;
- ``export``: TUM trajectories and CSV maps of a run folder.
"""

from albot2d.evaluation.alignment import (
    AbsolutePoseError,
    absolute_pose_error,
    in_world_frame,
    map_in_world_frame,
)
from albot2d.evaluation.experiment import (
    DEFAULT_MAPPERS,
    ExperimentResult,
    RunSpec,
    evaluation_params_from_report,
    run_experiment,
)
from albot2d.evaluation.homing import HomingResult, homing, homing_to_start
from albot2d.evaluation.map_quality import MapQuality, MapQualityParams, map_quality
from albot2d.evaluation.replay import DEFAULT_REPLAY_MAPPERS, find_relations, replay_log
from albot2d.evaluation.report import (
    REPORT_NAME,
    format_homing_table,
    format_summary_table,
    read_report,
    write_report,
)
from albot2d.evaluation.results import MapperScores, OdometryScores, RunScores
from albot2d.evaluation.rpe import RPEResult, RPEStats, relative_pose_error
from albot2d.evaluation.scoring import EvaluationParams, score_mappers, score_run
from albot2d.evaluation.trace import HomingParams, StepTimes, Trace, drive_mappers

__all__ = [
    "DEFAULT_MAPPERS",
    "DEFAULT_REPLAY_MAPPERS",
    "REPORT_NAME",
    "AbsolutePoseError",
    "EvaluationParams",
    "ExperimentResult",
    "HomingParams",
    "HomingResult",
    "MapQuality",
    "MapQualityParams",
    "MapperScores",
    "OdometryScores",
    "RPEResult",
    "RPEStats",
    "RunScores",
    "RunSpec",
    "StepTimes",
    "Trace",
    "absolute_pose_error",
    "drive_mappers",
    "evaluation_params_from_report",
    "find_relations",
    "format_homing_table",
    "format_summary_table",
    "homing",
    "homing_to_start",
    "in_world_frame",
    "map_in_world_frame",
    "map_quality",
    "read_report",
    "relative_pose_error",
    "replay_log",
    "run_experiment",
    "score_mappers",
    "score_run",
    "write_report",
]
