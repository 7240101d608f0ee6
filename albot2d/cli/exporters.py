"""The ``--export`` formats of ``albot2d simulate`` and ``albot2d run``: a registry.

Each :class:`Exporter` writes some files for a finished run (its frames, world and, for
``run``, the mappers' result) into a staging directory; :func:`write_exports` runs the ones
asked for and moves what they wrote into the output directory, so nothing appears unless
every export succeeded. Add a format by adding an entry to :data:`EXPORTERS`.

``rosbag2`` writes ``log_ros2/`` (a ROS 2 bag, MCAP unless ``--bag-storage sqlite3``) and
``rosbag1`` writes ``log.bag`` (``albot2d.logs.rosbag_writer``). ``occupancy`` writes
``world.pgm/.yaml`` (the true world) and, for a run, ``map_NAME.pgm/.yaml`` per mapper as
ROS ``map_server`` maps (``--map-resolution``); ``g2o`` writes the ``slam`` mapper's pose
graph, ``graph_NAME.g2o`` and ``graph_NAME.tum`` (``albot2d.evaluation.run.map_exports``).
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from albot2d.errors import InputError

if TYPE_CHECKING:
    import argparse

    from albot2d.evaluation.run.experiment import ExperimentResult
    from albot2d.frames import Frame
    from albot2d.logs.rosbag_writer import BagStorage
    from worldgen.world import World

__all__ = [
    "EXPORTERS",
    "ROSBAG1_NAME",
    "ROSBAG2_NAME",
    "ExportOptions",
    "ExportSource",
    "Exporter",
    "export_names",
    "export_options",
    "write_exports",
]

ROSBAG1_NAME = "log.bag"
ROSBAG2_NAME = "log_ros2"
DEFAULT_MAP_RESOLUTION_M = 0.05


@dataclass(frozen=True)
class ExportOptions:
    """The exporters' options: the ROS 2 bag's storage (``--bag-storage``; ``None``: MCAP)
    and the occupancy maps' cell size (``--map-resolution``; ``None``: the default)."""

    bag_storage: BagStorage | None = None
    map_resolution_m: float | None = None


@dataclass(frozen=True, eq=False)
class ExportSource:
    """What a run leaves to export: its frames (with true poses in simulation), its world,
    the mappers' result (``albot2d run``; ``None`` for ``simulate``) and the options."""

    frames: Sequence[Frame]
    world: World | None = None
    result: ExperimentResult | None = None
    options: ExportOptions = field(default_factory=ExportOptions)


@dataclass(frozen=True)
class Exporter:
    """One ``--export`` value: ``write(source, directory)`` puts its files in ``directory``.

    ``needs_frames``: the run's frames must be kept while it runs (``albot2d run``).
    """

    name: str
    help: str
    write: Callable[[ExportSource, Path], None]
    needs_frames: bool = False


def _rosbag(version: int) -> Callable[[ExportSource, Path], None]:
    def write(source: ExportSource, directory: Path) -> None:
        from albot2d import __version__
        from albot2d.logs.rosbag_writer import write_bag

        if version == 1:
            write_bag(directory / ROSBAG1_NAME, source.frames, ros_version=1)
        else:
            storage: BagStorage = source.options.bag_storage or "mcap"
            write_bag(
                directory / ROSBAG2_NAME, source.frames, ros_version=2, storage=storage,
                metadata={"albot2d_version": __version__},
            )  # fmt: skip

    return write


def _write_files(directory: Path, files: Mapping[str, bytes]) -> None:
    for name, data in files.items():
        (directory / name).write_bytes(data)


def _occupancy(source: ExportSource, directory: Path) -> None:
    from albot2d.evaluation.run.map_exports import WORLD_MAP_NAME, occupancy_files, world_grid
    from albot2d.logs.map_server import map_server_files

    resolution = source.options.map_resolution_m or DEFAULT_MAP_RESOLUTION_M
    if source.result is not None:  # every mapper's map, and the world's in simulation
        _write_files(directory, occupancy_files(source.result, resolution))
    elif source.world is not None:
        _write_files(directory, map_server_files(world_grid(source.world, resolution),
                                                 WORLD_MAP_NAME))  # fmt: skip


def _g2o(source: ExportSource, directory: Path) -> None:
    from albot2d.evaluation.run.map_exports import g2o_files

    if source.result is not None:  # (export_options refuses g2o where there is none)
        _write_files(directory, g2o_files(source.result))


EXPORTERS: dict[str, Exporter] = {
    exporter.name: exporter
    for exporter in (
        Exporter("rosbag2", f"ROS 2 bag {ROSBAG2_NAME}/", _rosbag(2), needs_frames=True),
        Exporter("rosbag1", f"ROS 1 bag {ROSBAG1_NAME}", _rosbag(1), needs_frames=True),
        Exporter(
            "occupancy", "ROS map_server maps: world.pgm/.yaml, map_NAME.pgm/.yaml", _occupancy
        ),
        Exporter("g2o", "the slam mapper's pose graph: graph_NAME.g2o/.tum", _g2o),
    )
}


def export_options(args: argparse.Namespace) -> ExportOptions:
    """The exporters' options from ``args`` (``--bag-storage``, ``--map-resolution``),
    refused where unused; ``--export g2o`` refused where no mapper keeps a pose graph."""
    from albot2d.cli.options import positive_number

    names = list(getattr(args, "export", None) or [])
    storage = getattr(args, "bag_storage", None)
    if storage is not None and "rosbag2" not in names:
        raise InputError(f"--bag-storage {storage} applies to --export rosbag2 only")
    if any(name.startswith("rosbag") for name in names):
        from albot2d.logs.rosbag import require_rosbags

        require_rosbags()  # before the run, not after it
    resolution = positive_number(getattr(args, "map_resolution", None), "--map-resolution")
    if resolution is not None and "occupancy" not in names:
        raise InputError("--map-resolution sets the cell size of --export occupancy; give both")
    if "g2o" in names:
        if not hasattr(args, "mapper"):  # albot2d simulate: no mappers, no graph
            raise InputError("--export g2o writes the slam mapper's pose graph: use albot2d "
                             "run (or replay) --mapper slam")  # fmt: skip
        mappers = [str(m) for m in args.mapper or ()]
        if not any(m.split("[")[0] == "slam" or ":" in m for m in mappers):
            raise InputError("--export g2o writes the slam mapper's pose graph: add --mapper slam")
    return ExportOptions(storage, resolution)


def export_names() -> list[str]:
    """The ``--export`` values, in registry order."""
    return list(EXPORTERS)


def write_exports(out: Path, names: Sequence[str], source: ExportSource) -> list[str]:
    """Run the exporters ``names`` (duplicates once) and move their files into ``out``.

    Returns the names of the entries written to ``out``. On any failure nothing is moved
    (entries already moved are removed again) and the error propagates.
    """
    chosen = list(dict.fromkeys(names))
    if not chosen:
        return []
    staging = Path(tempfile.mkdtemp(prefix=".albot2d-export.", dir=out))
    moved: list[Path] = []
    try:
        for name in chosen:
            EXPORTERS[name].write(source, staging)
        for entry in sorted(staging.iterdir()):
            target = out / entry.name
            if target.is_dir() and not target.is_symlink():
                shutil.rmtree(target)
            os.replace(entry, target)
            moved.append(target)
    except BaseException:
        for target in moved:
            with contextlib.suppress(OSError):
                shutil.rmtree(target) if target.is_dir() else target.unlink()
        raise
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return [p.name for p in moved]
