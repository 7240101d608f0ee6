"""Occupancy grids: exact segment rasterisation, ROS map_server files read by a generic
reader (PyYAML + Pillow), the true world's grid against its walls, mappers' grids."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import shapely
from hypothesis import given
from hypothesis import strategies as st

from albot2d.cli import main
from albot2d.errors import InputError
from albot2d.geometry.grid import (
    FREE,
    OCCUPIED,
    UNKNOWN,
    OccupancyGrid,
    grid_for_segments,
    rasterise_segments,
    supercover_cells,
)
from albot2d.logs.map_server import map_server_files, read_map_server
from worldgen.generate import generate

yaml = pytest.importorskip("yaml", reason="the [maps] extra (PyYAML) is not installed")
Image = pytest.importorskip("PIL.Image", reason="the [maps] extra (Pillow) is not installed")

coordinate = st.floats(-20.0, 20.0, allow_nan=False)


def load_map(yaml_path: Path) -> tuple[np.ndarray, dict]:
    """A map_server map as map_server reads it (trinary): cells[row, col], row 0 = lowest
    y, and the YAML document — PyYAML and Pillow only, none of albot2d's code."""
    doc = yaml.safe_load(yaml_path.read_text())
    pixels = np.asarray(Image.open(yaml_path.parent / doc["image"]), dtype=np.float64)
    p = (255.0 - pixels) / 255.0 if not doc["negate"] else pixels / 255.0
    cells = np.full(p.shape, -1, dtype=np.int8)
    cells[p > doc["occupied_thresh"]] = 100
    cells[p < doc["free_thresh"]] = 0
    return cells[::-1], doc


def cell_of(points: np.ndarray, doc: dict) -> tuple[np.ndarray, np.ndarray]:
    ox, oy, yaw = doc["origin"]
    assert yaw == 0.0
    res = doc["resolution"]
    return (np.floor((points[:, 1] - oy) / res).astype(int),
            np.floor((points[:, 0] - ox) / res).astype(int))  # fmt: skip


def along(segments: np.ndarray, step: float) -> np.ndarray:
    """Points every ``step`` metres along each segment (so equal weight per metre)."""
    out = []
    for x1, y1, x2, y2 in segments:
        n = max(int(np.hypot(x2 - x1, y2 - y1) / step), 1)
        t = (np.arange(n) + 0.5) / n
        out.append(np.column_stack([x1 + t * (x2 - x1), y1 + t * (y2 - y1)]))
    return np.vstack(out)


@given(st.lists(st.tuples(coordinate, coordinate, coordinate, coordinate), min_size=1,
                max_size=6))  # fmt: skip
def test_supercover_is_every_cell_a_segment_passes_through(segs: list) -> None:
    s = np.array(segs, dtype=np.float64)
    owner, col, row = supercover_cells(s)
    got = set(zip(owner.tolist(), col.tolist(), row.tolist(), strict=True))
    # Dense samples (away from the ends, where a segment may only touch a cell's edge) all
    # fall in a reported cell; every reported cell holds a sample or is a 1-D touch.
    t = np.linspace(0.0, 1.0, 20001)
    for k, (x1, y1, x2, y2) in enumerate(s):
        px, py = x1 + t * (x2 - x1), y1 + t * (y2 - y1)
        sampled = set(zip(np.floor(px).astype(int).tolist(), np.floor(py).astype(int).tolist(),
                          strict=True))  # fmt: skip
        mine = {(c, r) for o, c, r in got if o == k}
        length = np.hypot(x2 - x1, y2 - y1)
        missing = sampled - mine
        # a sample lands in an unreported cell only on a grid line it runs along or at an end
        for c, r in missing:
            on_line = np.isclose(px, c) | np.isclose(py, r) | np.isclose(px, c + 1) | np.isclose(
                py, r + 1)  # fmt: skip
            inside = (np.floor(px) == c) & (np.floor(py) == r)
            assert np.all(on_line[inside]), (k, c, r)
        assert len(mine) <= len(sampled) + 2 or length < 1e-6


def test_rasterise_marks_exact_cells_and_free_space() -> None:
    grid = OccupancyGrid(np.full((4, 6), UNKNOWN, np.int8), 0.5, origin_x_m=-1.0, origin_y_m=0.0)
    # a horizontal wall at y = 0.75 from x = -0.9 to x = 0.4: row 1, columns 0..2
    out = rasterise_segments(grid, [[-0.9, 0.75, 0.4, 0.75]])
    assert sorted(zip(*np.nonzero(out.cells == OCCUPIED), strict=True)) == [(1, 0), (1, 1), (1, 2)]
    assert out.counts()["unknown"] == 21 and grid.counts()["unknown"] == 24  # grid unchanged
    room = shapely.box(-1.0, 0.0, 0.0, 1.0)  # centres of the 2×2 cells at the lower left
    out = rasterise_segments(grid, [[-0.9, 0.75, 0.4, 0.75]], free_space=room)
    assert out.counts() == {"occupied": 3, "free": 2, "unknown": 19}
    assert out.lookup([[-0.8, 0.1], [0.3, 0.8], [5.0, 5.0]]).tolist() == [FREE, OCCUPIED, UNKNOWN]
    with pytest.raises(InputError, match="resolution_m"):
        OccupancyGrid(np.zeros((2, 2), np.int8), 0.0)
    with pytest.raises(InputError, match="too large"):
        grid_for_segments([[0.0, 0.0, 1e5, 1e5]], 0.01)


def test_map_server_files_round_trip_and_read_as_map_server_does(tmp_path: Path) -> None:
    cells = np.array([[100, 0, -1], [0, 0, 100]], dtype=np.int8)  # row 0 = lowest y
    grid = OccupancyGrid(cells, 0.1, origin_x_m=-2.5, origin_y_m=1.25, origin_yaw_rad=0.0)
    for name, data in map_server_files(grid, "m").items():
        (tmp_path / name).write_bytes(data)
    pixels = np.asarray(Image.open(tmp_path / "m.pgm"))
    assert pixels.tolist() == [[254, 254, 0], [0, 254, 205]]  # top row = highest y
    loaded, doc = load_map(tmp_path / "m.yaml")
    assert np.array_equal(loaded, cells)
    assert doc["origin"] == [-2.5, 1.25, 0.0] and doc["resolution"] == 0.1
    assert doc["mode"] == "trinary" and doc["image"] == "m.pgm"
    back = read_map_server(tmp_path / "m.yaml")
    assert np.array_equal(back.cells, cells) and back.origin_x_m == -2.5
    # scale mode and negate, as map_server interprets them
    Image.fromarray(np.array([[0, 128, 255]], dtype=np.uint8)).save(tmp_path / "s.png")
    (tmp_path / "s.yaml").write_text("image: s.png\nresolution: 1\norigin: [0, 0, 0]\n"
                                     "negate: 1\noccupied_thresh: 0.65\nfree_thresh: 0.2\n"
                                     "mode: scale\n")  # fmt: skip
    assert read_map_server(tmp_path / "s.yaml").cells.tolist() == [[0, 66, 100]]
    (tmp_path / "bad.yaml").write_text("image: s.png\nresolution: fine\norigin: [0, 0, 0]\n")
    with pytest.raises(InputError, match=r"bad\.yaml: resolution must be a number"):
        read_map_server(tmp_path / "bad.yaml")


@pytest.fixture(scope="module")
def office_world_map(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("sim")
    assert main(["simulate", "--out", str(out), "--max-frames", "5", "--no-png",
                 "--export", "occupancy"]) == 0  # fmt: skip
    return out


def test_truth_grid_of_office_seed_0_agrees_with_its_walls(office_world_map: Path) -> None:
    world = generate("office", seed=0)
    walls = world.obstacle_segments
    cells, doc = load_map(office_world_map / "world.yaml")
    res = doc["resolution"]
    assert res == 0.05
    rows, cols = cell_of(along(walls, res / 10), doc)
    on_occupied = cells[rows, cols] == 100
    assert on_occupied.mean() >= 0.95, on_occupied.mean()  # wall length on occupied cells
    # every occupied cell is within one cell of a wall (its centre within res of one)
    r, c = np.nonzero(cells == 100)
    centres = np.column_stack([doc["origin"][0] + (c + 0.5) * res,
                               doc["origin"][1] + (r + 0.5) * res])  # fmt: skip
    lines = shapely.linestrings(walls.reshape(-1, 2, 2))
    _, distance = shapely.STRtree(lines).query_nearest(shapely.points(centres),
                                                       return_distance=True)  # fmt: skip
    assert distance.max() <= res, distance.max()
    # free cells are free space, and most of the free space is free cells
    r, c = np.nonzero(cells == 0)
    free_centres = np.column_stack([doc["origin"][0] + (c + 0.5) * res,
                                    doc["origin"][1] + (r + 0.5) * res])  # fmt: skip
    assert shapely.contains_xy(world.free_space, *free_centres.T).all()
    assert len(free_centres) * res**2 >= 0.95 * world.free_space.area
    print(
        f"office seed 0 at {res} m: {on_occupied.mean():.4f} of wall length on occupied "
        f"cells, farthest occupied cell centre {distance.max():.4f} m from a wall"
    )


def test_run_exports_every_mappers_grid_in_the_world_frame(tmp_path: Path) -> None:
    out = tmp_path / "run"
    assert main(["run", "--out", str(out), "--max-frames", "40", "--no-figures",
                 "--mapper", "albot1", "naive", "truth", "--export", "occupancy",
                 "--map-resolution", "0.1"]) == 0  # fmt: skip
    names = {p.name for p in out.iterdir()}
    for stem in ("world", "map_albot1", "map_naive", "map_truth"):
        assert {f"{stem}.pgm", f"{stem}.yaml"} <= names
    world, wdoc = load_map(out / "world.yaml")
    truth, tdoc = load_map(out / "map_truth.yaml")
    assert tdoc["resolution"] == wdoc["resolution"] == 0.1
    assert set(np.unique(truth).tolist()) == {-1, 100}  # surfaces only: no free cells
    # The truth mapper's surfaces (views at true poses) fall on the world's walls: its
    # occupied cells are (within a cell) the world's occupied cells.
    r, c = np.nonzero(truth == 100)
    x = tdoc["origin"][0] + (c + 0.5) * 0.1
    y = tdoc["origin"][1] + (r + 0.5) * 0.1
    wr, wc = cell_of(np.column_stack([x, y]), wdoc)
    near = np.zeros(len(wr), dtype=bool)
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            near |= world[np.clip(wr + dr, 0, world.shape[0] - 1),
                          np.clip(wc + dc, 0, world.shape[1] - 1)] == 100  # fmt: skip
    assert len(r) > 100 and near.mean() > 0.97, near.mean()
