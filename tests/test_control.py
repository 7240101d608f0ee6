"""The frontier explorer's parts: knowledge grid, reachable floor, grid search, and a short
exploration through ``Simulator.step``."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely

from albot2d.control import (
    ExploreDrive,
    ExplorerParams,
    FrontierExplorer,
    GridSpec,
    KnowledgeGrid,
    reachable_floor,
)
from albot2d.control.exploration import explorer_grid
from albot2d.control.grid_search import dijkstra_to_goal, dilate, nearest_goal_path
from albot2d.geometry import Pose
from albot2d.sim import LaserNoise, Simulator
from worldgen import generate

SMALL = {"width_m": 14.0, "height_m": 10.0}


def _brute_dilate(mask: np.ndarray, r: float) -> np.ndarray:
    ny, nx = mask.shape
    out = np.zeros_like(mask)
    ys, xs = np.nonzero(mask)
    yy, xx = np.mgrid[0:ny, 0:nx]
    for y, x in zip(ys, xs, strict=True):
        out |= (yy - y) ** 2 + (xx - x) ** 2 <= r * r
    return out


@pytest.mark.parametrize("radius", [0.0, 1.0, 1.5, 2.5, 3.7])
def test_dilate_is_a_disc(radius: float) -> None:
    mask = np.random.default_rng(1).random((23, 31)) < 0.03
    assert np.array_equal(dilate(mask, radius), _brute_dilate(mask, radius))


def test_grid_search_finds_the_nearest_goal_around_a_wall() -> None:
    cost = np.ones((20, 20))
    cost[5:15, 10] = np.inf  # a wall with ways round both ends
    goal = np.zeros_like(cost, dtype=bool)
    goal[10, 15] = True
    seeds = np.array([10 * 20 + 5])
    found = nearest_goal_path(cost, goal, seeds, np.zeros(1))
    assert found is not None
    cells, length = found
    assert tuple(cells[0]) == (10, 5) and tuple(cells[-1]) == (10, 15)
    assert np.all(np.isfinite(cost[cells[:, 0], cells[:, 1]]))
    assert length > 10.0  # longer than the straight line through the wall
    # the compiled and the plain search agree cell for cell
    plain = dijkstra_to_goal(cost.reshape(-1), goal.reshape(-1), seeds, np.zeros(1), 20)
    chain = [int(plain[0])]
    while plain[1][chain[-1]] >= 0:
        chain.append(int(plain[1][chain[-1]]))
    assert np.array_equal(np.array(chain[::-1]), cells[:, 0] * 20 + cells[:, 1])
    cost[:, 10] = np.inf  # now the goal is cut off
    assert nearest_goal_path(cost, goal, seeds, np.zeros(1)) is None
    assert plain[0] == 10 * 20 + 15


def test_knowledge_grid_sees_only_free_space_and_walls() -> None:
    world = generate("rooms", seed=3, **SMALL)
    sim = Simulator(world, seed=0, laser_noise=LaserNoise.zero())  # no mixed pixels
    obs = sim.reset()
    spec = explorer_grid(world, 0.1)
    grid = KnowledgeGrid(spec, sensing_range_m=10.0)
    new = grid.integrate(obs.true_pose, obs.scan)
    assert len(new) == grid.seen.sum() > 100
    xs, ys = spec.centres()
    # Every seen cell centre lies in free space (grown by a cell for the walls' own cells).
    inside = shapely.contains_xy(world.free_space.buffer(0.1), xs[grid.seen], ys[grid.seen])
    assert inside.all()
    # Returns make cells occupied; they lie on or next to the walls and clutter.
    occ = grid.occupied
    assert occ.any()
    d = shapely.distance(
        shapely.MultiLineString(list(world.obstacle_segments.reshape(-1, 2, 2))),
        shapely.points(xs[occ], ys[occ]),
    )
    assert np.all(d < 0.15)
    assert len(grid.integrate(obs.true_pose, obs.scan)) == 0  # nothing new the second time


def test_reachable_floor_is_the_disc_swept_free_space() -> None:
    world = generate("rooms", seed=3, **SMALL)
    spec = explorer_grid(world, 0.1)
    floor = reachable_floor(world, spec)
    assert 0.5 * world.free_space.area < floor.area_m2 <= world.free_space.area + 1e-6
    assert floor.cells * spec.cell_area_m2 == pytest.approx(floor.area_m2, rel=0.05)
    iy, ix = spec.cell_of(world.start.x, world.start.y)
    assert floor.mask[iy, ix]
    # a bigger robot reaches less
    assert reachable_floor(world, spec, radius_m=0.4).area_m2 < floor.area_m2


def test_grid_spec_cells() -> None:
    spec = GridSpec.covering(0.0, 0.0, 1.0, 0.5, 0.1)
    assert spec.shape == (5, 10)
    assert spec.cell_of(0.05, 0.45) == (4, 0)
    assert spec.cell_of(-3.0, 9.0) == (4, 0)  # clipped


def test_exploration_covers_a_small_world_without_collisions() -> None:
    world = generate("rooms", seed=3, **SMALL)
    drive = ExploreDrive(Simulator(world, seed=1), "dataset3", max_time_s=240.0)
    frames = list(drive.frames())
    result = drive.result
    assert result.collisions == 0
    assert result.final_coverage > 0.8, result.to_dict()
    assert np.all(np.diff(result.coverage) >= 0.0)
    assert result.reason in ("explored", "time")
    # views as the profile says: 1 m or 10° of odometry between them (a turn view may
    # come at the first scan after 10°)
    inc = np.array([[f.odom_increment.x, f.odom_increment.y, f.odom_increment.theta]
                    for f in frames[1:]])  # fmt: skip
    moved, turned = np.hypot(inc[:, 0], inc[:, 1]), np.abs(inc[:, 2])
    assert np.all((moved >= 1.0 - 1e-6) | (turned >= math.radians(10.0) - 0.2))
    report = result.to_dict()
    assert report["time_to_coverage_s"]["0.50"] is not None
    assert report["coverage_every_60s"][0]["time_s"] == 0.0


def test_explorer_rejects_bad_params() -> None:
    from albot2d.errors import InputError

    with pytest.raises(InputError, match="speed_mps"):
        ExplorerParams(speed_mps=-1.0)
    with pytest.raises(InputError, match="max_time_s"):
        ExploreDrive(Simulator(generate("rooms", seed=3, **SMALL), seed=0), max_time_s=math.nan)


def test_start_pose_is_used() -> None:
    world = generate("rooms", seed=3, **SMALL)
    drive = ExploreDrive(Simulator(world, seed=0), max_time_s=1.0, start=world.start)
    first = next(iter(drive.frames()))
    assert first.true_pose == Pose(world.start.x, world.start.y, world.start.theta)


def _walled_room(stray: bool) -> tuple[FrontierExplorer, np.ndarray]:
    """A seen room (x 0.2–3 m) and corridor (x 3–5.8 m) with a 1 m doorway in the wall
    between them at x = 3 m, the unknown beyond the corridor's open east end; with
    ``stray``, one occupied cell in the doorway (a mixed pixel at a jamb that no fan of the
    laser has cleared)."""
    spec = GridSpec.covering(0.0, 0.0, 7.0, 3.0, 0.1)
    explorer = FrontierExplorer(spec, 0.25, ExplorerParams(initial_spin=False))
    k = explorer.knowledge
    xs, ys = spec.centres()
    inside = (xs > 0.2) & (xs < 5.8) & (ys > 0.2) & (ys < 2.8)
    wall = inside & ((ys < 0.3) | (ys > 2.7) | (xs < 0.3))
    wall |= inside & (np.abs(xs - 3.0) < 0.06) & ~((ys > 1.0) & (ys < 2.0))
    k.known[inside] = True
    k.seen[inside & ~wall] = True
    k.evidence[inside] = -2.0
    k.evidence[wall] = 3.5
    cell = np.zeros_like(wall)
    if stray:
        iy, ix = spec.cell_of(3.0, 1.5)
        cell[iy, ix] = True
        k.evidence[cell] = 0.9
    return explorer, wall | cell


def test_explorer_walled_in_by_a_stray_return_forgets_obstacles_and_goes_on() -> None:
    pose = Pose(1.5, 1.5, 0.0)
    open_door, _ = _walled_room(stray=False)
    assert open_door.command(pose, 0.0) is not None and open_door.clears == 0
    explorer, obstacles = _walled_room(stray=True)
    command = explorer.command(pose, 0.0)
    assert command is not None and not explorer.finished and explorer.clears == 1
    assert explorer._path is not None and explorer._path[-1, 0] > 4.5  # through the door
    assert not explorer.knowledge.occupied.any()  # forgotten; the next scans bring walls back
    # The next scan sees the same stray return and nothing new: walled in again right after
    # a clear, it is finished (it clears again only once it has seen something new).
    explorer.knowledge.evidence[obstacles] = 3.5
    explorer._replan = True
    assert explorer.command(pose, 1.0) is None and explorer.finished and explorer.clears == 1
