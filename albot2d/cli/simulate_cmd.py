"""``albot2d simulate``: drive the robot through a world and write a run directory.

Takes the world and driving options of ``albot2d run``, with the same defaults (the
office world, seed 0, profile dataset1, odometry noise typical, a loop tour of at least
100 m) and the same seeds, so ``albot2d simulate`` logs exactly the frames that
``albot2d run`` with the same options maps. Writes ``DIR/log.clf`` (CARMEN), ``truth.txt``,
``log.relations``, ``run.json`` and ``paths.png`` (world, true path, odometry path), and with
``--export rosbag2 rosbag1`` the run as ROS bags (``log_ros2/``, ``log.bag``: /scan, /odom,
/tf, /tf_static, /ground_truth; see docs/ros.md) that ``albot2d replay`` reads too. Every
input is checked before anything is written; a failure leaves no partial output files.
Prints a one-line summary.
"""

from __future__ import annotations

import argparse
import contextlib
import itertools
import shutil
import sys
from collections.abc import Iterable
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from albot2d.atomic import atomic_write_bytes
from albot2d.errors import InputError

if TYPE_CHECKING:
    from albot2d.cli.options import Subcommands
    from albot2d.frames import Frame
    from worldgen.world import World

__all__ = ["PNG_NAME", "register", "run"]

PNG_NAME = "paths.png"


def register(subparsers: Subcommands) -> None:
    from albot2d.cli.common import add_export_option, add_out_option, add_run_options

    p = subparsers.add_parser(
        "simulate",
        help="simulate a run (CARMEN log, truth, relations, paths plot) in a world",
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter,
    )  # fmt: skip
    add_run_options(p)
    add_out_option(p)
    p.add_argument("--no-png", action="store_true", help=f"do not draw {PNG_NAME}")
    add_export_option(p)
    p.set_defaults(handler=run)


def _out_dir(text: str) -> Path:
    out = Path(text)
    if out.exists() and not out.is_dir():
        raise InputError(f"--out {out} exists and is not a directory")
    return out


def _frames(frames: Iterable[Frame], total: int | None, show_progress: bool) -> list[Frame]:
    from tqdm import tqdm

    with tqdm(
        itertools.islice(frames, total),
        total=total,
        desc="simulate",
        unit=" frames",
        file=sys.stderr,
        disable=not show_progress,
    ) as bar:
        return list(bar)


def _render_png(world: World, frames: list[Frame], title: str) -> bytes | None:
    try:
        from albot2d.viz.paths import render_paths_png

        truth = [f.true_pose for f in frames]
        assert all(t is not None for t in truth)  # the simulator's frames carry their truth
        true_xy = np.array([[t.x, t.y] for t in truth if t is not None])
        odom_xy = np.array([[f.odom_pose.x, f.odom_pose.y] for f in frames])
        collided = np.array([f.collided for f in frames], dtype=bool)
        return render_paths_png(
            world, true_xy=true_xy, odom_xy=odom_xy, collided=collided, title=title
        )
    except ImportError as exc:
        print(
            f"albot2d simulate: note: no {PNG_NAME} ({exc}); pip install 'albot2d[viz]'",
            file=sys.stderr,
        )
        return None


def run(args: argparse.Namespace) -> int:
    from albot2d.cli.common import spec_from_args
    from albot2d.cli.exporters import export_options
    from albot2d.evaluation.run.setup import build_run
    from albot2d.logs import write_run
    from albot2d.logs.run_files import LOG_NAME, MANIFEST_NAME, RELATIONS_NAME, TRUTH_NAME

    out = _out_dir(args.out)
    options = export_options(args)
    spec = spec_from_args(args)
    setup = build_run(spec)
    world, tour, profile, sim = setup.world, setup.tour, setup.profile, setup.simulator
    frames = _frames(sim.drive(tour, profile), spec.max_frames, sys.stderr.isatty())
    travelled = f"first {len(frames)} frames of a " if spec.max_frames is not None else ""
    title = (
        f"{world.kind} seed {world.seed}  {profile.name}  {travelled}{tour.kind} tour "
        f"{tour.length_m:.0f} m  odometry noise {spec.noise}"
    )
    png = None if args.no_png else _render_png(world, frames, title)
    params = {
        "seed": spec.seed,
        "world_source": spec.world_file or f"generate({spec.kind!r}, seed={spec.seed})",
        "world_params": dict(spec.world_params),
        "profile": profile.name,
        "odometry_preset": spec.noise,
        "laser_noise_preset": spec.laser_noise,
        "tour": spec.tour_record(tour),
        "max_frames": spec.max_frames,
        **sim.params(),
    }
    manifest = write_run(out, frames, params=params)
    exported: list[str] = []
    try:
        if args.export:
            from albot2d.cli.exporters import ExportSource, write_exports

            source = ExportSource(frames, world, None, options)
            exported = write_exports(out, args.export, source)
        if png is not None:
            atomic_write_bytes(out / PNG_NAME, png)
    except BaseException:
        for name in (LOG_NAME, TRUTH_NAME, RELATIONS_NAME, MANIFEST_NAME, *exported):
            with contextlib.suppress(OSError):
                path = out / name
                shutil.rmtree(path) if path.is_dir() else path.unlink()
        raise
    counts = manifest["counts"]
    print(
        f"{profile.name}: {counts['frames']} frames, {tour.kind} tour {tour.length_m:.1f} m, "
        f"{frames[-1].timestamp:.0f} s, {counts['collided_frames']} collided -> {out}"
        + (f" (+ {', '.join(exported)})" if exported else "")
    )
    return 0
