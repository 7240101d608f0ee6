"""Evaluation: run the mappers on simulated or recorded runs, score them, check them, fuzz them.

- ``run``: the run pipeline (``RunSpec`` → world, tour, simulator → every mapper → typed
  scores → report.json), ``run_experiment`` and ``replay_log``;
- ``metrics``: relative pose error, APE after alignment, homing, map quality;
- ``checks``: invariants of a run and its mapper, for the tests and the fuzzer;
- ``fuzz``: campaigns of random episodes, their records and summaries;
- ``paper``: the paper's experiments regenerated beside its numbers.

Inside, ``metrics`` and ``checks`` import nothing of the others; ``run`` imports
``metrics``; ``fuzz`` imports ``run``, ``metrics`` and ``checks``; ``paper`` imports all.
This package re-exports the entry points a user of the library needs.
"""

from albot2d.evaluation.metrics.alignment import (
    AbsolutePoseError,
    absolute_pose_error,
    in_world_frame,
    map_in_world_frame,
)
from albot2d.evaluation.metrics.homing import HomingResult, homing, homing_to_start
from albot2d.evaluation.metrics.map_quality import MapQuality, MapQualityParams, map_quality
from albot2d.evaluation.metrics.rpe import RPEResult, RPEStats, relative_pose_error
from albot2d.evaluation.run.experiment import (
    DEFAULT_MAPPERS,
    ExperimentResult,
    RunSpec,
    evaluation_params_from_report,
    run_experiment,
)
from albot2d.evaluation.run.replay import DEFAULT_REPLAY_MAPPERS, find_relations, replay_log
from albot2d.evaluation.run.report import (
    REPORT_NAME,
    format_homing_table,
    format_summary_table,
    read_report,
    write_report,
)
from albot2d.evaluation.run.results import MapperScores, OdometryScores, RunScores
from albot2d.evaluation.run.scoring import EvaluationParams, score_mappers, score_run
from albot2d.evaluation.run.trace import HomingParams, StepTimes, Trace, drive_mappers

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
