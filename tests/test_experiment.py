"""The main experiment's numbers checked against the truth and independent computations.

One small run (a 15 × 15 m rooms world, a short loop driven with dataset3) is scored by
``run_experiment``; the tests re-simulate the same frames themselves and recompute the
odometry RPE, homing, counts and relations without the evaluation code under test.
"""

from __future__ import annotations

import json
import math
from collections import Counter
from typing import Any

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from albot2d.errors import InputError
from albot2d.evaluation import (
    EvaluationParams,
    HomingParams,
    RunSpec,
    drive_mappers,
    run_experiment,
)
from albot2d.evaluation.run.experiment import evaluation_params_from_report
from albot2d.evaluation.run.report import (
    format_homing_table,
    format_summary_table,
    report_json,
    without_timings,
)
from albot2d.frames import Frame, Scan
from albot2d.geometry import Pose
from albot2d.logs import relations_from_truth
from albot2d.mapping import Albot1, GroundTruthIntegration
from albot2d.seeding import RUN_STREAMS, stream_seed
from albot2d.sim.odometry import noise_preset
from albot2d.sim.simulator import Simulator
from tests.runs import small_run
from worldgen import plan_tour
from worldgen.generate import generate

SPEC = small_run(3, noise="typical")
PARAMS = EvaluationParams(homing=HomingParams(stop_every_m=4.0, min_start_distance_m=1.5))


@pytest.fixture(scope="module")
def result() -> Any:
    return run_experiment(SPEC, PARAMS)


@pytest.fixture(scope="module")
def frames() -> list[Frame]:
    """The run's frames, simulated here as ``albot2d simulate`` seeds them."""
    world = generate("rooms", seed=3, width_m=15.0, height_m=15.0)
    tour = plan_tour(world, "loop", 20.0)
    sim = Simulator(
        world, seed=stream_seed(3, RUN_STREAMS, "simulator"), odometry=noise_preset("typical")
    )
    return list(sim.drive(tour, "dataset3"))


def _rpe_by_hand(frames: list[Frame], poses: list[Pose]) -> tuple[float, float, int]:
    """Mean translational (m) and rotational (deg) error, looping over relations."""
    stamps = np.array([f.timestamp for f in frames])
    truth = np.array([f.true_pose.as_array() for f in frames])
    rel = relations_from_truth(stamps, truth)
    index = {t: k for k, t in enumerate(stamps.tolist())}
    trans, rot = [], []
    for t1, t2, motion in zip(rel.t1.tolist(), rel.t2.tolist(), rel.motion, strict=True):
        est = poses[index[t1]].inverse() @ poses[index[t2]]
        err = Pose.from_array(motion).inverse() @ est
        trans.append(math.hypot(err.x, err.y))
        rot.append(abs(math.degrees(math.atan2(math.sin(err.theta), math.cos(err.theta)))))
    return float(np.mean(trans)), float(np.mean(rot)), len(trans)


def test_report_has_the_documented_shape(result: Any) -> None:
    report = json.loads(report_json(result.report))  # strict JSON: no NaN anywhere
    assert report["command"] == "run" and report["seed"] == 3
    assert report["world"]["kind"] == "rooms" and report["profile"] == "dataset3"
    assert report["params"]["spec"]["noise"] == "typical"
    assert set(report["mappers"]) == {"albot1", "naive", "truth"}
    for m in report["mappers"].values():
        assert {"views", "local_maps", "triangulations", "path_integrations"} <= set(m["counts"])
        assert {
            "trans_m_mean",
            "trans_m_std",
            "rot_deg_mean",
            "rot_deg_std",
            "relations",
            "short",
            "long",
        } <= set(m["rpe"])
        assert {"accuracy_m_mean", "accuracy_m_p95", "completeness"} <= set(m["map"])
        assert m["homing"] and {
            "view",
            "bearing_est_deg",
            "bearing_true_deg",
            "distance_est_m",
            "distance_true_m",
        } <= set(m["homing"][0])
        assert "extraction" in m["timing_ms"] and m["timing_ms"]["total"] > 0
    assert "rpe" in report["odometry"]
    assert "albot1" in format_summary_table(result.scores)
    assert "stop" in format_homing_table(result.scores)


def test_truth_mapper_is_exact(result: Any) -> None:
    truth = result.report["mappers"]["truth"]
    assert truth["rpe"]["trans_m_mean"] < 1e-9 and truth["rpe"]["rot_deg_mean"] < 1e-7
    for stop in truth["homing"]:
        assert stop["bearing_error_deg"] == pytest.approx(0.0, abs=1e-7)
        assert stop["distance_error_m"] == pytest.approx(0.0, abs=1e-9)
    # Its map is the true walls seen with SICK range noise (σ ≈ 1 cm).
    assert truth["map"]["accuracy_m_mean"] < 0.03 and truth["map"]["completeness"] > 0.9


def test_odometry_rpe_matches_an_independent_computation(result: Any, frames: list) -> None:
    assert result.trace.n_frames == len(frames)
    trans, rot, n = _rpe_by_hand(frames, [f.odom_pose for f in frames])
    rpe = result.report["odometry"]["rpe"]
    assert rpe["relations"] == n == result.report["run"]["relations"]
    assert rpe["trans_m_mean"] == pytest.approx(trans, rel=1e-9)
    assert rpe["rot_deg_mean"] == pytest.approx(rot, rel=1e-9, abs=1e-12)
    assert rpe["trans_m_mean"] > 0  # the noise preset really perturbed odometry
    # Naive integration places views by odometry: the same trajectory up to its origin.
    naive = result.report["mappers"]["naive"]["rpe"]
    assert naive["trans_m_mean"] == pytest.approx(trans, rel=1e-9)


def test_counts_match_albot1s_route_map(result: Any, frames: list) -> None:
    albot1 = Albot1()
    for frame in frames:
        albot1.observe(frame)
    counts = result.report["mappers"]["albot1"]["counts"]
    methods = Counter(albot1.route.methods())
    assert counts["views"] == len(frames)
    assert counts["local_maps"] == len(albot1.route) == len(result.trace.mappers["albot1"].route)
    assert counts["triangulations"] == methods["triangulation"]
    assert counts["path_integrations"] == methods["path_integration"]
    rows = [m.frame_index for m in albot1.route]
    assert counts["moves_between_updates_max"] == max(np.diff(rows))
    assert counts["global_map_surfaces"] == len(albot1.global_map().segments)
    # Albot1's RPE equals scoring its trajectory by hand.
    trans, _, _ = _rpe_by_hand(frames, [Pose.from_array(p) for p in albot1.trajectory()])
    rpe = result.report["mappers"]["albot1"]["rpe"]
    assert rpe["trans_m_mean"] == pytest.approx(trans, rel=1e-9)
    snaps = result.report["mappers"]["albot1"]["snapshots"]
    assert snaps[-1]["update"] == len(albot1.route) and snaps[-1]["row"] == len(frames) - 1


def test_homing_truth_is_computed_from_true_poses(result: Any, frames: list) -> None:
    start = frames[0].true_pose
    stops = result.report["mappers"]["albot1"]["homing"]
    assert len(stops) >= 2
    travelled = np.cumsum(
        [0.0] + [math.hypot(f.odom_increment.x, f.odom_increment.y) for f in frames[1:]]
    )
    for stop in stops:
        pose = frames[stop["view"]].true_pose
        dx, dy = start.x - pose.x, start.y - pose.y
        bearing = math.degrees(
            math.atan2(
                math.sin(math.atan2(dy, dx) - pose.theta), math.cos(math.atan2(dy, dx) - pose.theta)
            )
        )
        assert stop["bearing_true_deg"] == pytest.approx(bearing, abs=1e-9)
        assert stop["distance_true_m"] == pytest.approx(math.hypot(dx, dy), abs=1e-12)
        assert stop["distance_true_m"] >= PARAMS.homing.min_start_distance_m
        assert stop["travelled_m"] == pytest.approx(travelled[stop["view"]])
    # Every stop but the last is the first view past a multiple of the spacing.
    every = PARAMS.homing.stop_every_m
    for stop in stops[:-1]:
        k = stop["view"]
        assert travelled[k] // every > travelled[k - 1] // every


def test_same_spec_same_report_and_reproducible_from_it(result: Any) -> None:
    spec = RunSpec.from_report(result.report)
    assert spec == SPEC
    params = evaluation_params_from_report(result.report)
    assert params == PARAMS
    again = run_experiment(spec, params)
    assert without_timings(again.report) == without_timings(result.report)


def test_bad_specs_are_input_errors() -> None:
    for kwargs in (
        {"seed": -1},
        {"tour_length_m": 0.0},
        {"tour_kind": "spiral"},
        {"laser_noise": "loud"},
        {"max_frames": 0},
        {"mappers": ()},
        {"kind": None},
        {"world_file": "w.json"},
    ):
        with pytest.raises(InputError):
            RunSpec(**kwargs)
    with pytest.raises(InputError, match="unknown mapper"):
        run_experiment(RunSpec(mappers=("albot1", "nope")))
    with pytest.raises(InputError, match="command"):
        RunSpec.from_report({"command": "replay"})


def test_max_frames_cuts_the_run(result: Any) -> None:
    spec = RunSpec(**{**SPEC.to_dict(), "max_frames": 30, "mappers": ("naive",)})
    short = run_experiment(spec, PARAMS)
    assert short.trace.n_frames == 30
    assert short.report["mappers"]["naive"]["counts"]["views"] == 30
    np.testing.assert_array_equal(short.trace.odom_poses, result.trace.odom_poses[:30])


def _frame(index: int, step_m: float) -> Frame:
    scan = Scan(np.ones(3), np.array([-0.1, 0.0, 0.1]), np.ones(3, bool), max_range_m=30.0)
    return Frame(
        index,
        float(index),
        scan,
        Pose(0.0, 0.0, 0.0),
        Pose(step_m, 0.0, 0.0),
        true_pose=Pose(0.0, 0.0, 0.0),
    )


@given(
    steps=st.lists(st.floats(0.0, 3.0), min_size=1, max_size=40),
    every=st.floats(0.5, 10.0),
    include_last=st.booleans(),
)
def test_stops_fall_on_each_new_multiple_of_the_spacing(
    steps: list[float], every: float, include_last: bool
) -> None:
    frames = [_frame(k, s) for k, s in enumerate(steps)]
    # Odometer distance is what counts; true poses all at the start would skip every stop,
    # so the minimum start distance is zero here.
    params = HomingParams(stop_every_m=every, min_start_distance_m=0.0, include_last=include_last)
    trace = drive_mappers(frames, {"truth": GroundTruthIntegration()}, homing=params)
    travelled = np.cumsum([0.0, *steps[1:]])
    expected = [
        k for k in range(1, len(steps)) if travelled[k] // every > travelled[k - 1] // every
    ]
    if include_last and (not expected or expected[-1] != len(steps) - 1):
        expected.append(len(steps) - 1)
    assert [s.row for s in trace.stops] == expected
    np.testing.assert_allclose(trace.travelled_m, travelled)
