"""Tours: start at the start, long enough, every straight leg safe for the robot's disc."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import shapely
from hypothesis import given
from hypothesis import strategies as st

from albot2d.errors import InputError
from albot2d.seeding import make_rng, spawn_rngs
from worldgen import TOUR_KINDS, generate, make_tour, make_world, plan_tour
from worldgen.strategies import worlds


def assert_legs_safe(world, tour):
    legs = shapely.linestrings(tour.legs.reshape(-1, 2, 2))
    assert shapely.covers(world.free_space, legs).all()
    gap = shapely.distance(legs, world.free_space.boundary)
    assert gap.min() >= world.robot_radius_m - 1e-9


def reversals(waypoints: np.ndarray) -> int:
    d = np.diff(waypoints, axis=0)
    d /= np.hypot(*d.T)[:, None]
    return int((np.einsum("ij,ij->i", d[:-1], d[1:]) < -0.95).sum())


@given(
    world=worlds(max_size_m=35.0),
    kind=st.sampled_from(TOUR_KINDS),
    length=st.sampled_from([0.0, 30.0, 120.0]),
    seed=st.integers(0, 1000),
)
def test_every_tour_leg_is_collision_free(world, kind, length, seed):
    tour = make_tour(world, make_rng(seed), kind=kind, min_length_m=length)
    assert tour.kind == kind
    assert np.array_equal(tour.waypoints[0], [world.start.x, world.start.y])
    assert tour.length_m >= length
    assert len(tour.waypoints) >= 2
    assert (np.hypot(*np.diff(tour.waypoints, axis=0).T) > 0).all()  # no zero-length legs
    assert_legs_safe(world, tour)
    if kind in ("loop", "out_and_back", "circuit"):
        assert np.array_equal(tour.waypoints[-1], tour.waypoints[0])
    if kind == "out_and_back":
        assert tour.node_ids == tour.node_ids[::-1]  # back exactly the way it came


@given(seed=st.integers(0, 2**32 - 1), kind=st.sampled_from(["rooms", "office", "corridors"]))
def test_backtracking_turns_back_and_revisits(seed, kind):
    world = generate(kind, seed=seed, width_m=30.0, height_m=30.0)
    tour = make_tour(world, make_rng(seed), kind="backtracking", min_length_m=120.0)
    assert reversals(tour.waypoints) >= 2
    ids = np.asarray(tour.node_ids)
    assert len(np.unique(ids)) < len(ids)  # some places are visited again


def test_loop_visits_far_apart_places_around_the_office():
    world = generate("office", seed=5)
    tour = make_tour(world, make_rng(0), kind="loop", min_length_m=100.0)
    wp = tour.waypoints
    # it goes round: the route spans most of the building in both directions
    assert np.ptp(wp[:, 0]) > 0.5 * world.width_m and np.ptp(wp[:, 1]) > 0.5 * world.height_m


def test_short_roadmaps_repeat_to_reach_the_length():
    world = generate("rooms", seed=3, width_m=7.0, height_m=7.0)
    for kind in TOUR_KINDS:
        tour = make_tour(world, make_rng(1), kind=kind, min_length_m=150.0)
        assert tour.length_m >= 150.0
        assert_legs_safe(world, tour)


def test_same_rng_seed_same_tour():
    world = generate("mixed", seed=2)
    for kind in TOUR_KINDS:
        a = make_tour(world, make_rng(9), kind=kind, min_length_m=80.0)
        b = make_tour(world, make_rng(9), kind=kind, min_length_m=80.0)
        assert a.waypoints.tobytes() == b.waypoints.tobytes()


def test_tour_errors():
    world = generate("rooms", seed=1, width_m=10.0, height_m=10.0)
    with pytest.raises(InputError, match=r"unknown tour kind 'spiral'.*loop, out_and_back"):
        make_tour(world, make_rng(0), kind="spiral")
    with pytest.raises(InputError, match="min_length_m"):
        make_tour(world, make_rng(0), min_length_m=float("nan"))
    with pytest.raises(InputError, match="min_length_m"):
        make_tour(world, make_rng(0), min_length_m=-1.0)
    tiny = make_world(shapely.box(0, 0, 1.0, 1.0))  # room for one node only
    with pytest.raises(InputError, match="roadmap too small for a tour: 1 nodes"):
        make_tour(tiny, make_rng(0))


def dead_end_visits(tour, graph) -> int:
    """Times the tour enters a node off the roadmap's cycles and later comes back."""
    import networkx as nx

    core = set(nx.k_core(graph, 2).nodes)
    return sum(1 for v in tour.node_ids if v not in core)


@pytest.mark.parametrize("seed", [0, 2])
def test_circuit_follows_the_corridors_without_stubs(seed):
    world = generate("office", seed=seed)
    loop = plan_tour(world, kind="loop", length_m=100.0)
    circuit = plan_tour(world, kind="circuit", length_m=100.0)
    assert circuit.kind == "circuit" and circuit.length_m >= 100.0
    assert np.array_equal(circuit.waypoints[-1], circuit.waypoints[0])
    assert_legs_safe(world, circuit)
    # Only the way from the start to the nearest cycle (and back) leaves the cycles,
    # and no U-turn happens anywhere else.
    graph = world.roadmap.graph
    assert dead_end_visits(circuit, graph) < dead_end_visits(loop, graph)
    assert reversals(circuit.waypoints) < reversals(loop.waypoints)
    assert reversals(circuit.waypoints) <= 1


def test_circuit_on_a_tree_roadmap_is_an_out_and_back():
    from worldgen.world import Roadmap

    world = generate("office", seed=0)
    nodes = np.array(
        [
            [world.start.x, world.start.y],
            [world.start.x + 1.0, world.start.y],
            [world.start.x + 2.0, world.start.y],
        ]
    )
    tree = dataclasses.replace(world, roadmap=Roadmap(nodes, np.array([[0, 1], [1, 2]])))
    tour = make_tour(tree, 0, kind="circuit", min_length_m=4.0)
    assert tour.length_m >= 4.0
    assert tour.node_ids[:5] == (0, 1, 2, 1, 0)


@pytest.mark.parametrize("kind", TOUR_KINDS)
def test_zero_length_edge_at_the_start_is_refused(kind):
    from worldgen.world import Roadmap

    world = generate("office", seed=0)
    s = [world.start.x, world.start.y]
    far = [[world.start.x + 5.0, world.start.y + 5.0], [world.start.x + 9.0, world.start.y + 5.0]]
    # the start's only edge has length 0; the rest of the roadmap is cut off from it
    roadmap = Roadmap(np.array([s, s, *far]), np.array([[0, 1], [2, 3]]))
    broken = dataclasses.replace(world, roadmap=roadmap)
    with pytest.raises(InputError, match=r"reaches only 0\.00 m"):
        make_tour(broken, 0, kind=kind, min_length_m=50.0)


def test_plan_tour_is_the_cli_tour_and_int_seeds_work():
    world = generate("rooms", seed=3, width_m=25.0, height_m=20.0)
    cli = make_tour(world, spawn_rngs(3, 2)[1], kind="loop", length_m=60.0)
    public = plan_tour(world, kind="loop", length_m=60.0)
    assert np.array_equal(public.waypoints, cli.waypoints)
    assert np.array_equal(plan_tour(world, length_m=60.0, seed=3).waypoints, cli.waypoints)
    at_least = make_tour(world, spawn_rngs(3, 2)[1], kind="loop", min_length_m=60.0)
    assert np.array_equal(plan_tour(world, "loop", 60.0, at_least=True).waypoints,
                          at_least.waypoints)  # fmt: skip
    by_int = make_tour(world, 1, kind="loop", min_length_m=60.0)
    by_rng = make_tour(world, make_rng(1), min_length_m=60.0)
    assert np.array_equal(by_int.waypoints, by_rng.waypoints)


@given(
    world=worlds(max_size_m=35.0),
    kind=st.sampled_from(TOUR_KINDS),
    length=st.sampled_from([5.0, 30.0, 120.0]),
    seed=st.integers(0, 1000),
)
def test_a_tour_length_is_met_within_the_tolerance(world, kind, length, seed):
    from worldgen.tours import TOUR_LENGTH_TOLERANCE

    tour = make_tour(world, make_rng(seed), kind=kind, length_m=length)
    assert length - 1e-9 <= tour.length_m <= (1.0 + TOUR_LENGTH_TOLERANCE) * length + 1e-9
    assert np.array_equal(tour.waypoints[0], [world.start.x, world.start.y])
    assert (np.hypot(*np.diff(tour.waypoints, axis=0).T) > 0).all()
    assert_legs_safe(world, tour)
    if kind in ("loop", "out_and_back", "circuit"):
        assert np.array_equal(tour.waypoints[-1], tour.waypoints[0])


@pytest.mark.parametrize("kind", TOUR_KINDS)
@pytest.mark.parametrize("world_kind", ["office", "mixed", "corridors"])
def test_the_command_lines_tour_length_is_the_length(kind, world_kind):
    world = generate(world_kind, seed=0)
    for length in (20.0, 100.0, 250.0):
        tour = plan_tour(world, kind, length)
        assert length <= tour.length_m <= 1.3 * length, (length, tour.length_m)
        assert plan_tour(world, kind, length, at_least=True).length_m >= length


def test_the_default_run_drives_about_100_m_not_three_times_that():
    world = generate("office", seed=0)
    assert 100.0 <= plan_tour(world).length_m <= 130.0
    assert plan_tour(world, at_least=True).length_m > 200.0  # the minimum's old meaning


def test_length_and_minimum_are_exclusive():
    world = generate("rooms", seed=1, width_m=10.0, height_m=10.0)
    with pytest.raises(InputError, match="not both"):
        make_tour(world, make_rng(0), length_m=10.0, min_length_m=10.0)
    with pytest.raises(InputError, match="length_m must be positive"):
        make_tour(world, make_rng(0), length_m=0.0)
