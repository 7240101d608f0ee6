"""The invariant checks (albot2d.evaluation.checks.invariants): each passes on real runs and fails
on a run broken on purpose; property tests of the simulator and of Albot1's heading error
over random worlds; Albot1 against raw odometry on average."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from albot2d.evaluation.checks import heading_bound as hb
from albot2d.evaluation.checks import invariants as inv
from albot2d.evaluation.checks import simulator as sim_inv
from albot2d.evaluation.fuzz.campaign import CampaignParams
from albot2d.evaluation.fuzz.episode import EpisodeSpec, run_episode
from albot2d.frames import Frame, Scan
from albot2d.geometry import Pose, transform_segments
from albot2d.mapping import Albot1, StepRecord, UpdateReport
from albot2d.mapping.albot1.route_map import RouteMap
from albot2d.sim.driving import get_profile
from albot2d.sim.laser import Laser, LaserNoise
from albot2d.sim.odometry import NOISE_PRESETS
from albot2d.sim.robot import RobotParams
from tests.runs import run_albot1, simulate
from worldgen.generate import generate
from worldgen.strategies import worlds

# The ci profile's 25 examples → 5 here; the fuzz profile's 5000 → 1000.
EXAMPLES = max(2, settings().max_examples // 5)
SMALL_WORLDS = worlds(kinds=("rooms", "corridors", "office", "open"), max_size_m=20.0)


@pytest.fixture(scope="module")
def run():  # type: ignore[no-untyped-def]
    world = generate("rooms", seed=4, width_m=14.0, height_m=12.0)
    frames = simulate(world, 4)
    albot = run_albot1(frames)
    truth = np.array([f.true_pose.as_array() for f in frames])
    index = np.array([f.index for f in frames])
    return world, frames, albot.mapper, albot.updates, truth, index, albot.views.views


# -- each check passes on a real run and fails on a broken one ------------------------------
def test_a_real_run_passes_every_check(run) -> None:  # type: ignore[no-untyped-def]
    world, frames, m, recorder, truth, index, views = run
    assert recorder.updates == m.counts().local_maps > 3
    inv.check_local_map_rule(m, views)
    inv.check_route_connected(m.route)
    sim_inv.check_robot_clear(world.obstacle_segments, truth, RobotParams().radius_m)
    checker = sim_inv.FrameChecker(world.obstacle_segments, LaserNoise())
    for f in frames:
        checker(f)
    assert checker.finish() == [] and checker.hits > 100 * len(frames)
    bound = hb.heading_error_bound(
        m.route, index, truth, NOISE_PRESETS["typical"], get_profile("dataset3"), LaserNoise()
    )
    inv.check_heading_error_bound(m.trajectory(), truth, bound)


def test_a_broken_chain_is_caught(run) -> None:  # type: ignore[no-untyped-def]
    m = run[2]
    maps = list(m.route.maps)
    maps[2] = dataclasses.replace(maps[2], pose=maps[2].pose @ Pose(0.01, 0.0, 0.0))
    with pytest.raises(inv.InvariantError, match="route_connected: local map 2"):
        inv.check_route_connected(RouteMap(maps))
    maps = list(m.route.maps)
    maps[1] = dataclasses.replace(maps[1], method="start")
    with pytest.raises(inv.InvariantError, match="no pose in its predecessor"):
        inv.check_route_connected(RouteMap(maps))


def test_a_broken_local_map_rule_is_caught(run) -> None:  # type: ignore[no-untyped-def]
    m, views = run[2], run[6]
    k = next(i for i, s in enumerate(m.steps) if i > 0 and s.tracked >= 4)
    broken = Albot1()
    broken.route = m.route
    broken.steps = list(m.steps)
    s = m.steps[k]
    broken.steps[k] = StepRecord(
        s.frame_index, s.tracked, s.use_vc, (s.frame_index,), ("triangulation",)
    )
    with pytest.raises(inv.InvariantError, match="local_map_rule"):
        inv.check_local_map_rule(broken, views)


def test_the_tracked_counts_are_recounted_not_read_from_the_mapper(run) -> None:  # type: ignore[no-untyped-def]
    """The rule is checked on tracking recounted from the views and the route map: the
    recount agrees with Albot1's records on a real run, and a record that lies about its
    tracked count (the remembering decision left as it was) is caught."""
    m, views = run[2], run[6]
    recount = inv.recount_tracking(views, m.params.tracking, m.params.min_tracked)
    assert [(r.frame_index, r.tracked, r.remembered) for r in recount] == [
        (s.frame_index, s.tracked, s.remembered) for s in m.steps
    ]
    assert any(r.remembered for r in recount[1:]) and any(not r.remembered for r in recount)
    k = next(i for i, s in enumerate(m.steps) if i > 0 and s.tracked < 4)
    lying = Albot1()
    lying.route, lying.steps = m.route, list(m.steps)
    lying.steps[k] = m.steps[k]._replace(tracked=m.params.min_tracked + 3)
    with pytest.raises(inv.InvariantError, match=f"frame {m.steps[k].frame_index}: recorded"):
        inv.check_local_map_rule(lying, views)
    # Fewer views than steps (a view the recount never saw) is caught too.
    with pytest.raises(inv.InvariantError, match="views given"):
        inv.check_local_map_rule(m, views[:-1])


def test_an_update_that_keeps_older_facing_surfaces_is_caught(run) -> None:  # type: ignore[no-untyped-def]
    m = run[2]
    last = m.route[-1]
    view = transform_segments(last.pose.as_array(), last.view.segments)
    # A pretend update that sees the last view again from its own viewpoint, yet deleted
    # nothing: the surfaces it sees (the last map's own) were left behind.
    report = UpdateReport(m.map.n_updates + 1, last.map_id + 2, 0, (), (), 0, 0, shapely.Polygon())
    with pytest.raises(inv.InvariantError, match="update_deletes_facing_overlap"):
        inv.check_update_deleted_facing_overlap(m, report, last.pose, view)
    report = report._replace(map_id=last.map_id + 1)
    with pytest.raises(inv.InvariantError, match="map being left"):
        inv.check_update_deleted_facing_overlap(m, report, last.pose, view)
    # Turned round, the robot has all of it behind: it could see none of it.
    behind = Pose(last.pose.x, last.pose.y, last.pose.theta + np.pi)
    inv.check_update_deleted_facing_overlap(m, report, behind, view)


def test_a_robot_inside_a_wall_is_caught(run) -> None:  # type: ignore[no-untyped-def]
    world = run[0]
    wall = world.obstacle_segments[0]
    on_wall = np.array([[0.5 * (wall[0] + wall[2]), 0.5 * (wall[1] + wall[3]), 0.0]])
    with pytest.raises(inv.InvariantError, match="robot_clear_of_obstacles"):
        sim_inv.check_robot_clear(world.obstacle_segments, on_wall, 0.25)


@pytest.mark.parametrize("laser", [LaserNoise(), LaserNoise.zero()], ids=["sick", "zero"])
def test_hits_seen_from_the_wrong_pose_are_caught(run, laser: LaserNoise) -> None:  # type: ignore[no-untyped-def]
    world, frames = run[0], run[1]
    checker = sim_inv.FrameChecker(world.obstacle_segments, laser)
    f = frames[len(frames) // 2]
    shifted = dataclasses.replace(f, true_pose=f.true_pose @ Pose(0.3, 0.0, 0.05))
    with pytest.raises(inv.InvariantError, match="laser_hits_on_obstacles"):
        checker(shifted)
        checker.finish()


def test_a_heading_that_jumps_is_caught(run) -> None:  # type: ignore[no-untyped-def]
    m, truth, index = run[2], run[4], run[5]
    bound = hb.heading_error_bound(
        m.route, index, truth, NOISE_PRESETS["typical"], get_profile("dataset3"), LaserNoise()
    )
    estimate = m.trajectory().copy()
    # This 32 m tour turns 25 rad: with odometry's random walk (typical: 0.05 rad per
    # sqrt(rad)) the 5-sigma envelope is ~70° half-way and ~110° at the end (the per-read
    # model's was narrower, so 60° used to be enough); a 150° jump is beyond it.
    half = len(estimate) // 2
    assert bound[half] < math.radians(100.0)
    estimate[half:, 2] += math.radians(150.0)
    with pytest.raises(inv.InvariantError, match="heading_error_bound"):
        inv.check_heading_error_bound(estimate, truth, bound)


def test_the_heading_bound_grows_with_odometry_noise(run) -> None:  # type: ignore[no-untyped-def]
    """The same route's bound: path-integration links and the offsets from each local map
    carry odometry's error, so more noise never lowers it; with none, only the laser's
    triangulation error and the floor remain."""
    m, truth, index = run[2], run[4], run[5]
    d1 = get_profile("dataset3")

    def bound(noise: str) -> np.ndarray:
        return hb.heading_error_bound(m.route, index, truth, NOISE_PRESETS[noise], d1, LaserNoise())

    none, typical, high = bound("none"), bound("typical"), bound("high")
    floor = math.radians(hb.HeadingBoundParams().floor_deg)
    assert np.all(none >= floor) and none[-1] > floor  # the laser's error accumulates
    eps = 1e-12  # the same sums in another order
    assert np.all(typical >= none - eps) and np.all(high >= typical - eps)
    assert high.max() > typical.max() > none.max()


def test_a_misplaced_local_map_breaks_zero_noise_localisation(run) -> None:  # type: ignore[no-untyped-def]
    m, truth, index = run[2], run[4], run[5]
    exact = RouteMap()
    rows = {int(i): r for r, i in enumerate(index)}
    for lm in m.route:
        prev = exact.maps[-1] if exact.maps else None
        rel = (
            Pose()
            if prev is None
            else Pose.from_array(truth[rows[prev.frame_index]]).between(
                Pose.from_array(truth[rows[lm.frame_index]])
            )
        )
        exact.append(lm.frame_index, lm.view, rel, lm.method)
    inv.check_zero_noise_localisation(exact, index, truth)
    maps = list(exact.maps)
    maps[3] = dataclasses.replace(
        maps[3], pose_in_previous=maps[3].pose_in_previous @ Pose(0.0, 0.08, 0.0)
    )
    with pytest.raises(inv.InvariantError, match=r"1 of \d+ local maps off; worst map 3"):
        inv.check_zero_noise_localisation(RouteMap(maps), index, truth)


# -- properties over random worlds ----------------------------------------------------------
@settings(max_examples=EXAMPLES)
@given(worlds(max_size_m=20.0), st.integers(0, 2**16), st.sampled_from(["sick", "zero"]))
def test_the_robot_stays_clear_and_every_hit_lies_on_an_obstacle(world, seed, laser) -> None:  # type: ignore[no-untyped-def]
    noise = LaserNoise() if laser == "sick" else LaserNoise.zero()
    frames = simulate(world, seed, laser=noise, length_m=12.0)
    truth = np.array([f.true_pose.as_array() for f in frames])
    sim_inv.check_robot_clear(world.obstacle_segments, truth, RobotParams().radius_m)
    checker = sim_inv.FrameChecker(world.obstacle_segments, noise)
    for f in frames:
        checker(f)
    checker.finish()


@settings(max_examples=EXAMPLES)
@given(SMALL_WORLDS, st.integers(0, 2**16), st.sampled_from(["low", "typical", "high"]))
def test_albot1_heading_error_stays_within_the_noise_bound(world, seed, noise) -> None:  # type: ignore[no-untyped-def]
    frames = simulate(world, seed, noise=noise)
    m = run_albot1(frames).mapper
    truth = np.array([f.true_pose.as_array() for f in frames])
    index = np.array([f.index for f in frames])
    bound = hb.heading_error_bound(
        m.route, index, truth, NOISE_PRESETS[noise], get_profile("dataset3"), LaserNoise()
    )
    inv.check_heading_error_bound(m.trajectory(), truth, bound)


@pytest.mark.slow  # ten full episodes
@pytest.mark.parametrize(
    ("profile", "noise", "episodes", "tour_m"),
    [("dataset3", "high", 8, 25.0), ("dataset2", "none", 2, 8.0)],
)
def test_albot1_beats_raw_odometry_on_average(profile, noise, episodes, tour_m) -> None:  # type: ignore[no-untyped-def]
    """Holds clearly for the high preset and for dataset 2's induced error; with the typical
    and low presets odometry is already good and Albot1 is not better on every run."""
    campaign = CampaignParams(
        episodes=episodes,
        seed=3,
        kinds=("rooms", "corridors", "open"),
        profile=profile,
        noise=noise,
        world_size_min_m=12.0,
        world_size_max_m=16.0,
        tour_length_min_m=tour_m,
        tour_length_max_m=tour_m,
    )
    records = [run_episode(EpisodeSpec.draw(campaign, k)).record for k in range(episodes)]
    assert all(r.status != "crash" for r in records), [r.error for r in records]
    # Every invariant but the heading bound holds. That bound is Albot1's own error model at
    # 4 sigma; with the high preset Albot1 holds it in all eight episodes (largest error /
    # bound 0.90 on the corrected laser; before the line-fit discretisation term one left
    # it: docs/invariants.md), too close to the edge to pin here.
    others = [{k: v for k, v in r.violations.items() if k != "heading_error_bound"}
              for r in records]  # fmt: skip
    assert others == [{}] * episodes, others
    mine = np.mean([r.metric("heading_error_mean_deg") for r in records])
    odometry = np.mean([r.metric("odometry_heading_error_mean_deg") for r in records])
    assert mine < odometry


def test_mixed_pixels_are_exempt_other_hits_off_the_walls_are_not() -> None:
    """Pinned from 1000-episode campaigns (seed 0; episodes 326, 126): two neighbouring
    depth jumps each blending one beam, and a 0.205 m jump split by its blended beam into
    two small steps, had been taken for hits off the walls."""
    walls = np.array([[2.0, -3.0, 2.0, 0.02], [4.0, -10.0, 4.0, 10.0]])  # near panel, far wall
    laser = Laser(walls, noise=LaserNoise.zero())
    exact = laser.true_ranges(Pose())
    edge = int(np.flatnonzero(np.isclose(exact, 2.0 / np.cos(laser.angles), atol=1e-9))[-1])

    def frame(ranges: np.ndarray) -> Frame:
        scan = Scan(ranges, laser.angles, np.isfinite(ranges), 30.0)
        return Frame(0, 0.0, scan, Pose(), Pose(), true_pose=Pose())

    mixed = exact.copy()
    mixed[edge] = 0.5 * (exact[edge] + exact[edge + 1])  # the near beam, blended outwards
    mixed[edge + 1] = exact[edge + 1] - 0.3 * (exact[edge + 1] - exact[edge])  # and the far
    checker = sim_inv.FrameChecker(walls, LaserNoise())
    checker(frame(mixed))
    assert checker.finish() == [] and checker.mixed_pixels == 2
    for noise in (LaserNoise(), LaserNoise.zero()):  # the zero-noise laser never mixes
        wrong = exact.copy()
        wrong[edge + 20] -= 0.5  # a far-wall beam returning 0.5 m short: no jump there
        if noise.mixed_pixel_prob == 0.0:
            wrong = mixed
        checker = sim_inv.FrameChecker(walls, noise)
        with pytest.raises(inv.InvariantError, match="laser_hits_on_obstacles"):
            checker(frame(wrong))
            checker.finish()


def test_a_mixed_pixel_along_one_smooth_wall_is_a_hit_off_the_walls() -> None:
    """The laser's former model blended beams along a wall seen at a grazing angle; the
    check holds a laser that mixes only at occluding edges to that, and accepts the former
    model's blends when told that is the model."""
    wall = np.array([[-1.0, 1.0, 60.0, 1.0]])
    quiet = {"range_sigma_m": 0.0, "range_sigma_per_m": 0.0, "dropout_prob": 0.0,
             "range_resolution_m": 0.0}  # fmt: skip
    former = LaserNoise(**quiet, mixed_pixel_edges="any_jump")
    rng = np.random.default_rng(0)
    blended = [Laser(wall, noise=former).scan(Pose(), rng) for _ in range(5)]

    def frames() -> list[Frame]:
        return [Frame(i, float(i), s, Pose(), Pose(), true_pose=Pose())
                for i, s in enumerate(blended)]  # fmt: skip

    accepting = sim_inv.FrameChecker(wall, former)
    for f in frames():
        accepting(f)
    assert accepting.finish() == [] and accepting.mixed_pixels > 5
    with pytest.raises(inv.InvariantError, match="laser_hits_on_obstacles"):
        checker = sim_inv.FrameChecker(wall, LaserNoise(**quiet))
        for f in frames():
            checker(f)
        checker.finish()
    # The corrected laser's scans of the same wall hold.
    ok = sim_inv.FrameChecker(wall, LaserNoise(**quiet))
    for i in range(5):
        ok(Frame(i, float(i), Laser(wall, noise=LaserNoise(**quiet)).scan(Pose(), rng), Pose(),
                 Pose(), true_pose=Pose()))  # fmt: skip
    assert ok.finish() == [] and ok.mixed_pixels == 0
