"""Run-folder exports of maps for ROS and pose-graph tools: occupancy grids and g2o.

``albot2d run/replay --export occupancy`` (``occupancy_files``; the CLI's registry of
formats is ``albot2d.cli.exporters``): per mapper ``NAME``,
``map_NAME.pgm`` + ``map_NAME.yaml``, its final global map as a ROS ``map_server`` map
(``albot2d.logs.map_server``) and, in simulation, ``world.pgm`` + ``world.yaml``, the true
world (``world_grid``). ``--export g2o`` (``g2o_files``): per ``slam`` mapper ``NAME``,
``graph_NAME.g2o`` (its keyframe pose graph, ``albot2d.mapping.slam.graph_export``) and
``graph_NAME.tum`` (the keyframes' timestamps and poses, the g2o vertices in order).

Frames as the other exports (``albot2d.evaluation.run.export``): with the truth every map and
graph is in the world frame (a mapper anchored at the first true pose), on a real log in
the mapper's own frame. The true world's grid marks free the cells whose centre lies in
the world's free space, occupied those any wall or clutter outline passes through, the
rest unknown. A mapper's map is only surfaces: its grid has occupied cells where a surface
passes and every other cell unknown (a segment map says nothing about the space between
its surfaces, and Albot1's map deletes surfaces, so marking swept space free would claim
what the map does not hold).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from albot2d.errors import InputError
from albot2d.evaluation.metrics.alignment import in_world_frame, map_in_world_frame
from albot2d.evaluation.run.export import file_stem, tum_text
from albot2d.geometry.grid import OccupancyGrid, grid_for_segments, rasterise_segments
from albot2d.logs.g2o import g2o_text
from albot2d.logs.map_server import map_server_files

__all__ = [
    "DEFAULT_MAP_RESOLUTION_M",
    "WORLD_MAP_NAME",
    "g2o_files",
    "occupancy_files",
    "pose_graph_files",
    "world_grid",
]

DEFAULT_MAP_RESOLUTION_M = 0.05
WORLD_MAP_NAME = "world"


def world_grid(world: Any, resolution_m: float = DEFAULT_MAP_RESOLUTION_M) -> OccupancyGrid:
    """The true world as an occupancy grid (world frame; see the module docstring)."""
    xmin, ymin, xmax, ymax = world.bounds
    grid = grid_for_segments(world.obstacle_segments, resolution_m,
                             points=[[xmin, ymin], [xmax, ymax]])  # fmt: skip
    return rasterise_segments(grid, world.obstacle_segments, free_space=world.free_space)


def mapper_grid(segments: Any, poses: Any, resolution_m: float) -> OccupancyGrid:
    """A mapper's map as a grid covering its surfaces and path: surfaces occupied, the
    rest unknown."""
    grid = grid_for_segments(segments, resolution_m, points=np.asarray(poses)[:, :2])
    return rasterise_segments(grid, segments)


def occupancy_files(
    result: Any, resolution_m: float = DEFAULT_MAP_RESOLUTION_M
) -> dict[str, bytes]:
    """``map_NAME.pgm/.yaml`` per mapper and ``world.pgm/.yaml`` (simulation)."""
    trace = result.trace
    start = trace.true_poses[0] if trace.true_poses is not None else None
    files: dict[str, bytes] = {}
    if result.world is not None:
        files |= map_server_files(world_grid(result.world, resolution_m), WORLD_MAP_NAME)
    for name, mapper in trace.mappers.items():
        segments = np.asarray(mapper.global_map().segments, dtype=np.float64).reshape(-1, 4)
        poses = np.asarray(mapper.trajectory(), dtype=np.float64).reshape(-1, 3)
        if start is not None:
            segments = map_in_world_frame(segments, start)
            poses = in_world_frame(poses, start)
        grid = mapper_grid(segments, poses, resolution_m)
        files |= map_server_files(grid, f"map_{file_stem(name)}")
    return files


def _pose_graphs(result: Any) -> dict[str, Any]:
    """The run's mappers that keep a ``PoseGraph`` (the slam mapper), by name."""
    from albot2d.mapping.slam.pose_graph import PoseGraph

    return {name: mapper for name, mapper in result.trace.mappers.items()
            if isinstance(getattr(mapper, "graph", None), PoseGraph)}  # fmt: skip


def pose_graph_files(
    name: str, mapper: Any, timestamps: Any, start: Any = None
) -> dict[str, bytes]:
    """``graph_NAME.g2o`` and ``graph_NAME.tum`` of a mapper keeping a ``PoseGraph`` as
    ``.graph`` (with ``.keyframe_rows``: each keyframe's row in ``timestamps``), in the
    world frame when ``start`` (the first true pose) is given."""
    from albot2d.mapping.slam.graph_export import pose_graph_edges

    vertices = np.array(mapper.graph.estimate, dtype=np.float64)
    if start is not None:
        vertices = in_world_frame(vertices, start)
    edges = pose_graph_edges(mapper.graph)
    stem = f"graph_{file_stem(name)}"
    stamps = np.asarray(timestamps, dtype=np.float64)[
        np.asarray(mapper.keyframe_rows, dtype=np.int64)
    ]
    return {
        f"{stem}.g2o": g2o_text(vertices, edges.ij, edges.measurements,
                                edges.information).encode("utf-8"),
        f"{stem}.tum": tum_text(stamps, vertices).encode("utf-8"),
    }  # fmt: skip


def g2o_files(result: Any) -> dict[str, bytes]:
    """``pose_graph_files`` of every pose-graph mapper of a run or replay."""
    trace = result.trace
    start = trace.true_poses[0] if trace.true_poses is not None else None
    files: dict[str, bytes] = {}
    for name, mapper in _pose_graphs(result).items():
        files |= pose_graph_files(name, mapper, trace.timestamps, start)
    if not files:
        raise InputError("--export g2o: no mapper of this run keeps a pose graph (give "
                         "--mapper slam)")  # fmt: skip
    return files
