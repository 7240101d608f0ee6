"""Scoring's fast paths beside the paths they replaced, on a real simulated run (issue 12).

Run: ``python -m pytest benchmarks/test_scoring.py --benchmark-only
--benchmark-group-by=group``. Each pair gives the same numbers bit for bit (tests:
``tests/test_alignment_evo.py``, ``tests/test_metrics.py``, ``tests/test_updates_regions.py``):

- APE: evo's per-pose ``metrics.APE`` loop (one scipy rotation per pose) against
  ``evo_pose_errors`` (all poses at once);
- isovists (region kinds): one point at a time against ``isovist_ranges_many``;
- map quality: every candidate wall of a surface measured against the candidates that
  may be nearest (``_may_be_nearest``).
"""

from __future__ import annotations

import importlib
from typing import Any

import numpy as np
import pytest

from albot2d.evaluation import RunSpec, run_experiment
from albot2d.evaluation.metrics.alignment import _evo_trajectory, evo_pose_errors
from albot2d.geometry import transform_segments
from worldgen.regions import isovist_ranges, isovist_ranges_many

SPEC = RunSpec(kind="office", seed=0, tour_length_m=60.0, max_frames=1500)


@pytest.fixture(scope="module")
def run() -> Any:
    return run_experiment(SPEC, score=False)


def _aligned(run: Any) -> tuple[Any, Any]:
    trace = run.trace
    est = _evo_trajectory(trace.timestamps, trace.odom_poses)
    ref = _evo_trajectory(trace.timestamps, trace.true_poses)
    est.align(ref, correct_scale=False)
    return est, ref


def _evo_loop(est: Any, ref: Any) -> tuple[np.ndarray, np.ndarray]:
    from evo.core import metrics

    errors = []
    for relation in (
        metrics.PoseRelation.translation_part,
        metrics.PoseRelation.rotation_angle_deg,
    ):
        ape = metrics.APE(relation)
        ape.process_data((ref, est))
        errors.append(ape.error)
    return errors[0], errors[1]


@pytest.mark.benchmark(group="APE per-pose errors (1,500 poses)")
@pytest.mark.parametrize("how", ["batched", "evo loop"])
def test_ape_errors(benchmark: Any, run: Any, how: str) -> None:
    pytest.importorskip("evo")
    est, ref = _aligned(run)
    fn = evo_pose_errors if how == "batched" else _evo_loop
    trans, angle = benchmark(fn, est, ref)
    assert len(trans) == len(angle) == run.trace.n_frames


@pytest.mark.benchmark(group="isovists (400 true positions, 72 rays)")
@pytest.mark.parametrize("how", ["many", "one at a time"])
def test_isovists(benchmark: Any, run: Any, how: str) -> None:
    walls, pts = run.world.walls, run.trace.true_poses[::4, :2][:400]

    def one_at_a_time() -> np.ndarray:
        return np.array([isovist_ranges(walls, p, 72, 30.0) for p in pts])

    def many() -> np.ndarray:
        return isovist_ranges_many(walls, pts, 72, 30.0)

    assert benchmark(many if how == "many" else one_at_a_time).shape == (len(pts), 72)


@pytest.mark.benchmark(group="map-quality sample distances (naive map)")
@pytest.mark.parametrize("how", ["pruned", "every candidate"])
def test_map_sample_distances(
    benchmark: Any, run: Any, how: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    module = importlib.import_module("albot2d.evaluation.metrics.map_quality")
    if how == "every candidate":
        monkeypatch.setattr(module, "_may_be_nearest", lambda s, w, c: np.ones(len(w), bool))
    trace = run.trace
    segs = transform_segments(trace.true_poses[0], trace.mappers["naive"].global_map().segments)
    d = benchmark(module._sample_distances, segs, 0.05, run.world.obstacle_segments)
    assert len(d) > len(segs)
