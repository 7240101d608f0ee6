"""The one setup path (``evaluation.setup``) and the typed scores (``evaluation.results``)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from albot2d.errors import InputError
from albot2d.evaluation.metrics.homing import HomingResult
from albot2d.evaluation.run.results import HomingStop, HomingSummary, ProcessCounts
from albot2d.evaluation.run.setup import RunSpec, build_run, check_spec
from albot2d.seeding import RUN_STREAMS, stream_seed
from albot2d.sim.laser import LASER_NOISE_PRESETS, LaserNoise, laser_noise_preset
from albot2d.sim.odometry import noise_preset
from albot2d.sim.simulator import Simulator
from tests.runs import small_run
from worldgen import generate, plan_tour
from worldgen.io import world_to_json

SPEC = small_run(4, mappers=("albot1", "naive"))


def test_build_run_is_world_tour_and_simulator_made_by_hand() -> None:
    setup = build_run(SPEC)
    world = generate("rooms", seed=4, width_m=15.0, height_m=15.0)
    assert world_to_json(setup.world) == world_to_json(world)
    tour = plan_tour(world, "loop", 20.0)
    assert np.array_equal(setup.tour.waypoints, tour.waypoints)
    assert list(setup.mapper_factories) == ["albot1", "naive"]
    sim = Simulator(
        world,
        seed=stream_seed(4, RUN_STREAMS, "simulator"),
        odometry=noise_preset("typical"),
        laser_noise=LaserNoise.sick_lms200(),
    )
    ours = itertools.islice(setup.simulator.drive(setup.tour, setup.profile), 30)
    theirs = itertools.islice(sim.drive(tour, "dataset3"), 30)
    for a, b in zip(ours, theirs, strict=True):
        assert a.odom_pose == b.odom_pose and np.array_equal(a.scan.ranges, b.scan.ranges)
    assert "rooms seed 4" in repr(setup)


def test_names_are_resolved_once_with_the_valid_ones_listed() -> None:
    assert set(LASER_NOISE_PRESETS) == {"sick_lms200", "zero", "sick_lms200_any_jump"}
    assert laser_noise_preset("sick_lms200_any_jump").mixed_pixel_edges == "any_jump"
    assert laser_noise_preset("zero").is_zero
    with pytest.raises(InputError, match="unknown laser noise 'loud'; valid: sick_lms200, zero"):
        RunSpec(laser_noise="loud")
    with pytest.raises(InputError, match="unknown tour kind 'spiral'"):
        RunSpec(tour_kind="spiral")
    with pytest.raises(InputError, match="no such world file"):
        check_spec(RunSpec(kind=None, world_file="/nonexistent/world.json"))
    with pytest.raises(InputError, match="unknown odometry noise preset 'wild'"):
        build_run(RunSpec(noise="wild"))


def test_typed_scores_are_the_report_sections() -> None:
    counts = ProcessCounts(
        views=10,
        local_maps=2,
        triangulations=1,
        path_integrations=0,
        global_map_surfaces=7,
        moves_between_updates_mean=5.0,
    )
    assert "loop_closures" not in counts.to_dict()
    with_slam = ProcessCounts(1, 1, 0, 0, 0, None, loop_closures={"keyframes": 3})
    assert with_slam.to_dict()["loop_closures"] == {"keyframes": 3}
    known = HomingStop(HomingResult(5, 10.0, -350.0, 3.0, 2.5), 20.0)
    unknown = HomingStop(HomingResult(9, 4.0, None, 1.0, None), 40.0)
    assert known.to_dict()["bearing_error_deg"] == pytest.approx(0.0, abs=1e-9)
    assert known.to_dict()["distance_error_m"] == pytest.approx(0.5)
    assert unknown.to_dict()["bearing_error_deg"] is None
    summary = HomingSummary.of((known, unknown))  # only stops with the truth count
    assert summary.stops == 2 and summary.distance_abs_max_m == pytest.approx(0.5)
    assert HomingSummary.of((unknown,)).to_dict() == {
        "stops": 1,
        "bearing_abs_max_deg": None,
        "bearing_abs_mean_deg": None,
        "distance_abs_max_m": None,
        "distance_abs_mean_m": None,
    }


def test_the_help_texts_read_the_registries_and_the_dataclasses_defaults(capsys) -> None:
    """--help lists every name a registry accepts and the defaults RunSpec and CampaignParams
    really have: both are read from them, so adding a preset or a kind needs no CLI edit."""
    from albot2d.cli import main
    from albot2d.sim.driving import PROFILES
    from albot2d.sim.laser import LASER_NOISE_PRESETS
    from albot2d.sim.odometry import NOISE_PRESETS
    from worldgen.kinds import world_kinds
    from worldgen.tours import TOUR_KINDS

    for command in ("run", "simulate", "fuzz"):
        assert main([command, "--help"]) == 0
        text = " ".join(capsys.readouterr().out.split())
        for names in (world_kinds(), PROFILES, NOISE_PRESETS, LASER_NOISE_PRESETS, TOUR_KINDS):
            for name in names:
                assert name in text, (command, name)
    spec = RunSpec()
    assert main(["run", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert f"(default {spec.profile})" in text and f"(default {spec.noise})" in text
    assert f"(default {spec.tour_length_m:g})" in text
