"""The fig6 kind: the paper's Fig. 6 building, its named waypoints and routes."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from albot2d.errors import InputError
from worldgen import generate
from worldgen.kinds.fig6 import FIG6_ROUTES
from worldgen.regions import region_kind_at
from worldgen.routes import route_start, route_tour, waypoint_arclength_m


@pytest.fixture(scope="module")
def worlds():
    return [generate("fig6", seed=s) for s in range(3)]


def test_every_seed_is_a_different_building_of_the_same_shape(worlds):
    digests = {w.walls.tobytes() for w in worlds}
    assert len(digests) == 3
    for w in worlds:
        f = w.features
        assert set(f["waypoints"]) == {"S", "X", "RD", "R", *(f"E{k}" for k in range(1, 9))}
        assert f["waypoints"]["S"] == f["waypoints"]["X"]
        ring = np.array(f["corridor_ring"])
        xl, xr = ring[:, 0].min(), ring[:, 0].max()
        yb, yt = ring[:, 1].min(), ring[:, 1].max()
        p = f["waypoints"]
        # S on the left corridor, E1..E3 ring corners, E5/E6 the cross corridor's ends
        assert p["S"][0] == xl and yb < p["S"][1] < yt
        assert p["E1"] == [xl, yb] and p["E2"] == [xr, yb] and p["E3"] == [xr, yt]
        assert p["E5"][0] == p["E6"][0] and xl < p["E5"][0] < p["E4"][0] < xr
        # the open area is at the top, above the top corridor, and reads as a hall
        hall = np.array(f["open_areas"][0])
        assert hall[3] > yt + 5.0
        mid = [[0.5 * (hall[0] + hall[2]), yt + 0.5 * (hall[3] - yt)]]
        assert region_kind_at(w, mid)[0] == "hall"


def test_routes_are_clear_and_of_the_papers_length(worlds):
    for w in worlds:
        clear = w.free_space.buffer(-w.robot_radius_m)
        for name in FIG6_ROUTES:
            assert name in w.features["routes"], name
            tour = route_tour(w, name)
            assert clear.covers(shapely.LineString(tour.waypoints)), name
        length = route_tour(w, "fig6").length_m
        assert 125.0 <= length <= 150.0  # the paper: ~136 m
        along = waypoint_arclength_m(w, "fig6")
        assert 65.0 <= along["E5"][0] <= 100.0  # the paper: ~100 m by odometer
        assert len(along["E1"]) == 3  # passed again after the first lap and on the way home
        for name in ("fig8_anticlockwise", "fig8_clockwise"):
            tour = route_tour(w, name)
            assert np.array_equal(tour.waypoints[0], tour.waypoints[-1])
            assert tour.length_m == pytest.approx(w.features["ring_length_m"])


def test_route_start_faces_the_first_leg(worlds):
    w = worlds[0]
    start = route_start(w, "fig6")
    assert (start.x, start.y) == tuple(w.features["waypoints"]["S"])
    assert start.theta == pytest.approx(-np.pi / 2)  # S -> E1 goes down the left corridor
    assert route_start(w, "fig8_clockwise").theta == pytest.approx(np.pi / 2)


def test_unknown_route_is_an_input_error(worlds):
    with pytest.raises(InputError, match="unknown route 'nope'"):
        route_tour(worlds[0], "nope")
    with pytest.raises(InputError, match="names no routes"):
        route_tour(generate("rooms", seed=0, width_m=12, height_m=12), "fig6")


def test_too_small_for_the_shape_is_an_input_error():
    with pytest.raises(InputError, match=r"Fig6Params\.width_m"):
        generate("fig6", seed=0, width_m=25.0)


def test_runspec_route_starts_at_s_and_drives_the_route():
    from albot2d.evaluation.run.experiment import RunSpec, run_experiment

    spec = RunSpec(kind="fig6", seed=2, route="fig8_clockwise", profile="start_stop",
                   mappers=("truth",), max_frames=4)  # fmt: skip
    result = run_experiment(spec)
    world = generate("fig6", seed=2)
    s = world.features["waypoints"]["S"]
    assert result.trace.true_poses[0, :2] == pytest.approx(s, abs=1e-9)
    assert result.trace.true_poses[0, 2] == pytest.approx(np.pi / 2)  # up towards E7
    assert result.tour.kind == "route:fig8_clockwise"
    assert result.report["params"]["tour"]["length_m"] == pytest.approx(
        world.features["ring_length_m"]
    )
    assert result.report["params"]["spec"]["route"] == "fig8_clockwise"


def test_fig15_route_goes_into_a_room_and_out_again(worlds):
    for w in worlds:
        p = w.features["waypoints"]
        route = w.features["routes"]["fig15"]
        assert route[:4] == ["S", "RD", "R", "RD"] and route[4] in ("E1", "E7")
        # RD on the left corridor's centre line, R off it (through a door, in a room)
        assert p["RD"][0] == p["S"][0] and p["R"][1] == p["RD"][1]
        assert abs(p["R"][0] - p["RD"][0]) > 2.0
        assert not any(shapely.box(*c).contains(shapely.Point(p["R"]))
                       for c in _corridor_cells(w))  # fmt: skip
        rooms = [shapely.Polygon(r) for r in _room_polygons(w)]
        assert rooms and any(r.contains(shapely.Point(p["R"])) for r in rooms)
        # the whole route, door included, is clear for the robot
        clear = w.free_space.buffer(-w.robot_radius_m)
        assert clear.covers(shapely.LineString(route_tour(w, "fig15").waypoints))


def _corridor_cells(w):
    ring = np.array(w.features["corridor_ring"])
    half = 0.5 * w.features["corridor_width_m"]
    xl, xr = ring[:, 0].min(), ring[:, 0].max()
    yb, yt = ring[:, 1].min(), ring[:, 1].max()
    return [(xl - half, yb - half, xl + half, yt + half),
            (xr - half, yb - half, xr + half, yt + half),
            (xl - half, yb - half, xr + half, yb + half),
            (xl - half, yt - half, xr + half, yt + half)]  # fmt: skip


def _room_polygons(w):
    """The free-space pieces left when the corridor cells are cut away: rooms and hall."""
    rest = w.free_space.difference(shapely.union_all([shapely.box(*c).buffer(0.3)
                                                      for c in _corridor_cells(w)]))  # fmt: skip
    parts = getattr(rest, "geoms", [rest])
    return [np.asarray(g.exterior.coords) for g in parts if g.area > 4.0]
