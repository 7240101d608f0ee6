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
from worldgen import generate, plan_tour
from worldgen.io import world_to_json

SPEC = RunSpec(
    kind="rooms",
    seed=4,
    world_params={"width_m": 15.0, "height_m": 15.0},
    profile="dataset3",
    tour_length_m=20.0,
    mappers=("albot1", "naive"),
)


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
    assert set(LASER_NOISE_PRESETS) == {"sick_lms200", "zero"}
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


def test_the_help_texts_defaults_are_the_dataclasses_defaults() -> None:
    """The CLI names RunSpec's/CampaignParams' defaults for --help without importing them."""
    from albot2d.cli import common, fuzz_cmd
    from albot2d.evaluation.fuzz.campaign import CampaignParams

    spec = RunSpec()
    assert spec.kind == common.DEFAULT_KIND and spec.profile == common.DEFAULT_PROFILE
    assert spec.noise == common.DEFAULT_NOISE and spec.laser_noise == common.DEFAULT_LASER_NOISE
    assert spec.tour_kind == common.DEFAULT_TOUR_KIND
    assert spec.tour_length_m == common.DEFAULT_TOUR_LENGTH_M
    campaign = CampaignParams(episodes=1)
    from albot2d.mapping.registry import _ALBOT1_OPTIONS
    from albot2d.sim.driving import PROFILES
    from albot2d.sim.laser import LASER_NOISE_PRESETS
    from albot2d.sim.odometry import NOISE_PRESETS
    from worldgen import KINDS
    from worldgen.tours import TOUR_KINDS

    # The names --help lists are every name the registries accept, in their order.
    assert tuple(KINDS) == common.WORLD_KINDS
    assert tuple(PROFILES) == common.PROFILE_NAMES
    assert tuple(NOISE_PRESETS) == common.NOISE_NAMES
    assert tuple(LASER_NOISE_PRESETS) == common.LASER_NOISE_NAMES
    assert tuple(TOUR_KINDS) == common.TOUR_KIND_NAMES
    assert tuple(_ALBOT1_OPTIONS) == common.ALBOT1_OPTION_KEYS
    for name in ("profile", "noise", "laser_noise", "mapper", "tour_kind"):
        assert fuzz_cmd.DEFAULTS[name] == getattr(campaign, name), name
