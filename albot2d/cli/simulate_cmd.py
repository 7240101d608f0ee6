"""``albot2d simulate``: drive the robot through a world and write a run directory.

Loads (``--world``) or generates (``--kind``/``--seed``) a world, plans a tour on its
roadmap, drives it with a profile (dataset1, dataset2, dataset3, start_stop) and writes
``DIR/log.clf`` (CARMEN), ``truth.txt``, ``log.relations``, ``run.json`` and ``paths.png``
(world, true path, odometry path). Every input is checked before anything is written;
a failure leaves no partial output files. Prints a one-line summary.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np

from albot2d.atomic import atomic_write_bytes
from albot2d.cli.options import seed_value
from albot2d.errors import InputError
from albot2d.seeding import spawn_rngs

__all__ = ["DEFAULT_TOUR_LENGTH_M", "LASER_NOISE_CHOICES", "PNG_NAME", "register", "run"]

PNG_NAME = "paths.png"
DEFAULT_TOUR_LENGTH_M = 100.0
LASER_NOISE_CHOICES = ("sick_lms200", "zero")
# Stream of the run seed's children that seeds the simulator (0 and 1 stay free).
_SIMULATION_STREAM = 2


def register(subparsers: Any) -> None:
    p = subparsers.add_parser(
        "simulate",
        help="simulate a run (CARMEN log, truth, relations, paths plot) in a world",
        description=__doc__,
    )
    source = p.add_argument_group("world (give --world or --kind)")
    source.add_argument("--world", metavar="world.json", help="a world file (albot2d world)")
    source.add_argument("--kind", help="generate a world of this kind, e.g. office, corridors")
    p.add_argument(
        "--seed", metavar="N",
        help="non-negative integer: the generated world's seed and the run's (default 0)",
    )  # fmt: skip
    p.add_argument("--profile", default="dataset1",
                   help="driving profile: dataset1, dataset2, dataset3, start_stop")
    p.add_argument("--tour-kind", default="loop", help="loop, out_and_back or backtracking")
    p.add_argument(
        "--tour-length", default=str(DEFAULT_TOUR_LENGTH_M), metavar="METRES",
        help=f"minimum tour length in metres (default {DEFAULT_TOUR_LENGTH_M:g})",
    )  # fmt: skip
    p.add_argument("--noise", default="none",
                   help="odometry noise preset: none, low, typical, high (default none)")
    p.add_argument("--laser-noise", default="sick_lms200",
                   help=f"laser noise: {', '.join(LASER_NOISE_CHOICES)} (default sick_lms200)")
    p.add_argument("--out", metavar="DIR", help="output directory (created if missing)")
    p.add_argument("--no-png", action="store_true", help=f"do not draw {PNG_NAME}")
    p.set_defaults(handler=run)


def _tour_length(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0.0):
        raise InputError(f"--tour-length must be a positive number of metres, got {text!r}")
    return value


def _laser_noise(name: str) -> Any:
    from albot2d.sim.laser import LaserNoise

    if name not in LASER_NOISE_CHOICES:
        raise InputError(
            f"unknown --laser-noise {name!r}; valid: {', '.join(LASER_NOISE_CHOICES)}"
        )
    return LaserNoise.zero() if name == "zero" else LaserNoise.sick_lms200()


def _out_dir(text: str | None) -> Path:
    if not text:
        raise InputError("give --out DIR, the directory for the run's files")
    out = Path(text)
    if out.exists() and not out.is_dir():
        raise InputError(f"--out {out} exists and is not a directory")
    return out


def _world(args: argparse.Namespace, seed: int) -> Any:
    if (args.world is None) == (args.kind is None):
        raise InputError("give --world world.json or --kind KIND (not both)")
    if args.world is not None:
        from worldgen.io import load

        return load(args.world)
    from worldgen.generate import generate

    return generate(args.kind, seed=seed)


def _tour(world: Any, kind: str, length_m: float) -> Any:
    # The same stream as ``albot2d world`` uses, so both plan the same tour for a world.
    rng = spawn_rngs(world.seed or 0, 2)[1]
    return world.tour(rng, kind=kind, min_length_m=length_m)


def _frames(frames: Any, show_progress: bool) -> list[Any]:
    from tqdm import tqdm

    with tqdm(frames, desc="simulate", unit=" frames", file=sys.stderr,
              disable=not show_progress) as bar:
        return list(bar)


def _render_png(world: Any, frames: list[Any], title: str) -> bytes | None:
    try:
        from albot2d.plots import render_paths_png

        true_xy = np.array([[f.true_pose.x, f.true_pose.y] for f in frames])
        odom_xy = np.array([[f.odom_pose.x, f.odom_pose.y] for f in frames])
        collided = np.array([f.collided for f in frames], dtype=bool)
        return render_paths_png(world, true_xy, odom_xy, collided=collided, title=title)
    except ImportError as exc:
        print(f"albot2d simulate: note: no {PNG_NAME} ({exc}); pip install 'albot2d[viz]'",
              file=sys.stderr)
        return None


def run(args: argparse.Namespace) -> int:
    from albot2d.logs import write_run
    from albot2d.logs.run_files import LOG_NAME, MANIFEST_NAME, RELATIONS_NAME, TRUTH_NAME
    from albot2d.sim.driving import get_profile
    from albot2d.sim.odometry import noise_preset
    from albot2d.sim.simulator import Simulator

    out = _out_dir(args.out)
    seed = seed_value(args.seed) or 0
    profile = get_profile(args.profile)
    odometry = noise_preset(args.noise)
    laser_noise = _laser_noise(args.laser_noise)
    length = _tour_length(args.tour_length)
    world = _world(args, seed)
    tour = _tour(world, args.tour_kind, length)
    sim_seed = np.random.SeedSequence(seed).spawn(_SIMULATION_STREAM + 1)[_SIMULATION_STREAM]
    sim = Simulator(world, seed=sim_seed, odometry=odometry, laser_noise=laser_noise)
    frames = _frames(sim.drive(tour, profile), show_progress=sys.stderr.isatty())
    title = (f"{world.kind} seed {world.seed}  {profile.name}  {tour.kind} "
             f"{tour.length_m:.0f} m  odometry noise {args.noise}")
    png = None if args.no_png else _render_png(world, frames, title)
    params = {
        "seed": seed,
        "world_source": args.world or f"generate({args.kind!r}, seed={seed})",
        "profile": profile.name,
        "odometry_preset": args.noise,
        "laser_noise_preset": args.laser_noise,
        "tour": {"kind": tour.kind, "min_length_m": length, "length_m": tour.length_m,
                 "waypoints": len(tour.waypoints)},
        **sim.params(),
    }
    manifest = write_run(out, frames, params=params)
    if png is not None:
        try:
            atomic_write_bytes(out / PNG_NAME, png)
        except OSError:
            for name in (LOG_NAME, TRUTH_NAME, RELATIONS_NAME, MANIFEST_NAME):
                with contextlib.suppress(OSError):
                    (out / name).unlink()
            raise
    counts = manifest["counts"]
    print(
        f"{profile.name}: {counts['frames']} frames, {tour.kind} tour {tour.length_m:.1f} m, "
        f"{frames[-1].timestamp:.0f} s, {counts['collided_frames']} collided -> {out}"
    )
    return 0
