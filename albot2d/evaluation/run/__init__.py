"""The run pipeline: a run description → world, tour and simulator → every mapper → scores.

- ``setup``: ``RunSpec`` and ``build_run`` — the one path from a run description to its
  world, tour and simulator;
- ``trace``: drive every mapper over one frame stream, keeping what metrics and figures
  need;
- ``scoring`` and ``results``: the trace scored into typed, frozen results;
- ``experiment``: ``run_experiment(RunSpec)``, the whole of ``albot2d run``;
- ``replay``: the same on a recorded log and its relations;
- ``report``: report.json (a view of the results) and the printed tables;
- ``export``: files the field's tools read (TUM trajectories, CSV maps);
- ``map_exports``: ``--export occupancy`` (ROS map_server grids) and ``--export g2o``.

May import: everything below evaluation and ``albot2d.evaluation.metrics``.
"""

from albot2d.evaluation.run.experiment import ExperimentResult, run_experiment
from albot2d.evaluation.run.replay import DEFAULT_REPLAY_MAPPERS, find_relations, replay_log
from albot2d.evaluation.run.results import MapperScores, OdometryScores, RunScores
from albot2d.evaluation.run.scoring import EvaluationParams, score_mappers, score_run
from albot2d.evaluation.run.setup import DEFAULT_MAPPERS, RunSetup, RunSpec, build_run
from albot2d.evaluation.run.trace import HomingParams, StepTimes, Trace, drive_mappers

__all__ = [
    "DEFAULT_MAPPERS",
    "DEFAULT_REPLAY_MAPPERS",
    "EvaluationParams",
    "ExperimentResult",
    "HomingParams",
    "MapperScores",
    "OdometryScores",
    "RunScores",
    "RunSetup",
    "RunSpec",
    "StepTimes",
    "Trace",
    "build_run",
    "drive_mappers",
    "find_relations",
    "replay_log",
    "run_experiment",
    "score_mappers",
    "score_run",
]
