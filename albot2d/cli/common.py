"""Helpers the subcommands share: the world and driving options of ``run``/``simulate`` →
``RunSpec``, scoring and ``--json`` options, the output directory,
drawing and writing a run's files, progress bars, the printed tables, report comparison.

``run``, ``replay`` and ``fuzz`` (its ``--reproduce``) write a run the same way: ``finish``
computes the result, draws the figures, exports trajectories and maps and writes
everything atomically with report.json last, removing the output directory again on
failure if the command created it.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import functools
import os
import sys
import tempfile
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, NamedTuple, NoReturn

from albot2d.atomic import atomic_paths
from albot2d.cli.options import positive_int, positive_number, world_params
from albot2d.errors import InputError

if TYPE_CHECKING:
    from tqdm import tqdm

    from albot2d.evaluation.run.experiment import ExperimentResult
    from albot2d.evaluation.run.scoring import EvaluationParams
    from albot2d.evaluation.run.setup import RunSpec


__all__ = [
    "Choices",
    "add_albot1_keys_to_help",
    "add_export_option",
    "add_json_option",
    "add_mapper_option",
    "add_noise_options",
    "add_out_option",
    "add_run_options",
    "add_scoring_options",
    "choices",
    "differences",
    "finish",
    "prepare_out_dir",
    "print_tables",
    "progress_bar",
    "remove_if_empty",
    "report_differences",
    "scoring_params",
    "spec_from_args",
    "write_outputs",
]


class Choices(NamedTuple):
    """The names each run option accepts, read from the registry that defines them."""

    world_kinds: tuple[str, ...]
    profiles: tuple[str, ...]
    noises: tuple[str, ...]
    laser_noises: tuple[str, ...]
    tour_kinds: tuple[str, ...]
    albot1_options: tuple[str, ...]


@functools.cache
def choices() -> Choices:
    """Every registry's names, for --help and validation (read once per process)."""
    from albot2d.mapping.registry import albot1_option_keys
    from albot2d.sim.driving import PROFILES
    from albot2d.sim.laser import LASER_NOISE_PRESETS
    from albot2d.sim.odometry import NOISE_PRESETS
    from worldgen.kinds import world_kinds
    from worldgen.tours import TOUR_KINDS

    return Choices(
        world_kinds=tuple(world_kinds()),
        profiles=tuple(PROFILES),
        noises=tuple(NOISE_PRESETS),
        laser_noises=tuple(LASER_NOISE_PRESETS),
        tour_kinds=tuple(TOUR_KINDS),
        albot1_options=albot1_option_keys(),
    )


def add_noise_options(
    group: argparse.ArgumentParser | argparse._ArgumentGroup,
    *,
    profile: str,
    noise: str,
    laser_noise: str,
) -> None:
    """``--profile``, ``--noise`` and ``--laser-noise``, their help naming the given
    defaults (a run's and a fuzzing campaign's differ)."""
    names = choices()
    group.add_argument("--profile", help=f"{', '.join(names.profiles)} (default {profile})")
    group.add_argument(
        "--noise", help=f"odometry noise preset: {', '.join(names.noises)} (default {noise})"
    )
    group.add_argument(
        "--laser-noise", help=f"{' or '.join(names.laser_noises)} (default {laser_noise})"
    )


# Fields two reports of the same run may differ in: file lists, the version, and a fuzzing
# reproducer's own section (wall-clock timings are dropped by ``without_timings``).
_NOT_COMPARED = ("figures", "exports", "albot2d_version", "kernels", "reproducer")


def add_run_options(p: argparse.ArgumentParser) -> None:
    """World and driving options, shared by ``run`` and ``simulate`` (same defaults)."""
    from albot2d.evaluation.run.setup import RunSpec
    from worldgen.tours import TOUR_LENGTH_TOLERANCE

    names, default = choices(), RunSpec()
    world = p.add_argument_group(f"world (default: --kind {default.kind} --seed 0)")
    world.add_argument("--world", metavar="world.json", help="a world file (albot2d world)")
    world.add_argument("--kind", help=f"generate a world: {', '.join(names.world_kinds)}")
    world.add_argument("--seed", metavar="N", help="world and run seed (default 0)")
    world.add_argument("--width", metavar="W", help="generated world's width in metres")
    world.add_argument("--height", metavar="H", help="generated world's height in metres")
    world.add_argument(
        "--param",
        action="append",
        metavar="NAME=VALUE",
        help="a generator parameter, e.g. door_width_min_m=0.9 (repeatable)",
    )
    drive = p.add_argument_group("driving")
    add_noise_options(
        drive, profile=default.profile, noise=default.noise, laser_noise=default.laser_noise
    )
    drive.add_argument(
        "--tour-kind",
        "--tour",
        dest="tour_kind",
        help=f"{', '.join(names.tour_kinds)} (default {default.tour_kind}), or explore: "
        "a frontier explorer drives until it has seen everything it can reach or for 30 "
        "simulated minutes",
    )
    drive.add_argument(
        "--tour-length",
        metavar="METRES",
        help=f"tour length: the tour is METRES to {1 + TOUR_LENGTH_TOLERANCE:g}×METRES long "
        f"(default {default.tour_length_m:g})",
    )
    drive.add_argument(
        "--min-tour-length",
        metavar="METRES",
        help="plan the tour through far-apart places and repeat it until it is at least "
        "METRES long (it may be several times longer); instead of --tour-length",
    )
    drive.add_argument("--max-frames", metavar="N", help="stop after N views")


def spec_from_args(args: argparse.Namespace) -> RunSpec:
    """The RunSpec of ``run``'s (and ``simulate``'s) options; options not given take
    RunSpec's defaults."""
    from albot2d.evaluation.run.setup import RunSpec

    params = world_params(args)
    if args.world is not None and (args.kind is not None or params):
        raise InputError("give --world, or --kind with its parameters, not both")
    seed = positive_int(args.seed, "--seed", allow_zero=True)
    length = positive_number(args.tour_length, "--tour-length")
    max_frames = positive_int(args.max_frames, "--max-frames")
    minimum = positive_number(getattr(args, "min_tour_length", None), "--min-tour-length")
    if minimum is not None and length is not None:
        raise InputError("give --tour-length or --min-tour-length, not both")
    if minimum is not None:
        length = minimum
    default = RunSpec()  # what an option not given means
    return RunSpec(
        seed=default.seed if seed is None else seed,
        kind=None if args.world is not None else args.kind or default.kind,
        world_file=args.world,
        world_params=params,
        profile=args.profile or default.profile,
        noise=args.noise or default.noise,
        laser_noise=args.laser_noise or default.laser_noise,
        tour_kind=args.tour_kind or default.tour_kind,
        tour_length_m=default.tour_length_m if length is None else length,
        tour_length_is_minimum=minimum is not None,
        mappers=tuple(getattr(args, "mapper", None) or ()) or default.mappers,
        max_frames=max_frames,
    )


def add_export_option(p: argparse.ArgumentParser, names: Sequence[str] | None = None) -> None:
    """``--export FORMAT ...`` (the registry of ``albot2d.cli.exporters``, or the formats
    ``names`` of it) and its options."""
    from albot2d.cli.exporters import DEFAULT_MAP_RESOLUTION_M, EXPORTERS

    chosen = [EXPORTERS[name] for name in (names or EXPORTERS)]
    g = p.add_argument_group("export")
    g.add_argument(
        "--export",
        nargs="+",
        action="extend",
        choices=[e.name for e in chosen],
        metavar="FORMAT",
        help="also write the run as: " + "; ".join(f"{e.name} ({e.help})" for e in chosen),
    )
    if any(e.name == "rosbag2" for e in chosen):
        g.add_argument(
            "--bag-storage",
            choices=("mcap", "sqlite3"),
            help="storage of the ROS 2 bag (default mcap)",
        )
    g.add_argument(
        "--map-resolution",
        metavar="METRES",
        help=f"cell size of --export occupancy maps (default {DEFAULT_MAP_RESOLUTION_M:g})",
    )


def add_mapper_option(p: argparse.ArgumentParser, builtins: str, default: str) -> None:
    """``--mapper NAME ...`` (``builtins``, the built-in names the command takes; any
    ``albot1[KEY=VALUE,...]``; a plugin ``module:Class``), with every albot1 key listed at
    the end of ``--help``; ``default`` says what runs without it."""
    p.add_argument(
        "--mapper",
        nargs="+",
        action="extend",
        metavar="NAME",
        help=f"mappers: {builtins}, albot1[KEY=VALUE,...] (keys listed below) or "
        f"module:Class ({default})",
    )
    add_albot1_keys_to_help(p)


def add_out_option(p: argparse.ArgumentParser, no_figures: str | None = None) -> None:
    """``--out DIR`` (required) and, where the command draws figures, ``--no-figures``
    (its help: what is written then)."""
    p.add_argument(
        "--out", metavar="DIR", required=True, help="output directory (created if missing)"
    )
    if no_figures is not None:
        p.add_argument("--no-figures", action="store_true", help=no_figures)


def add_json_option(
    p: argparse.ArgumentParser, help: str = "print report.json on stdout instead of the tables"
) -> None:
    p.add_argument("--json", action="store_true", help=help)


def add_scoring_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("scoring")
    g.add_argument(
        "--stop-every",
        metavar="METRES",
        help="homing: stop every this many odometer metres (default 20)",
    )
    g.add_argument(
        "--min-start-distance",
        metavar="METRES",
        help="homing: skip stops nearer the start than this (default 3)",
    )
    g.add_argument(
        "--last-k-views",
        metavar="K",
        help="map completeness over the walls seen in the last K views (default 10)",
    )
    g.add_argument(
        "--snapshots", metavar="N", help="moments of the map history to draw and report (default 4)"
    )


def scoring_params(
    args: argparse.Namespace, base: EvaluationParams | None = None
) -> EvaluationParams:
    """EvaluationParams from the scoring options (unset ones from ``base`` or defaults)."""

    from albot2d.evaluation import EvaluationParams

    base = base or EvaluationParams()
    homing = base.homing
    every = positive_number(args.stop_every, "--stop-every")
    near = positive_number(args.min_start_distance, "--min-start-distance", allow_zero=True)
    if every is not None:
        homing = dataclasses.replace(homing, stop_every_m=every)
    if near is not None:
        homing = dataclasses.replace(homing, min_start_distance_m=near)
    quality = base.map_quality
    k = positive_int(args.last_k_views, "--last-k-views")
    if k is not None:
        quality = dataclasses.replace(quality, last_k_views=k)
    snapshots = positive_int(args.snapshots, "--snapshots") or base.snapshots
    return dataclasses.replace(base, homing=homing, map_quality=quality, snapshots=snapshots)


# -- output -----------------------------------------------------------------------------
def prepare_out_dir(text: str | None) -> tuple[Path, bool]:
    """Create ``--out`` if needed and check it is writable; returns (dir, created)."""
    if not text:
        raise InputError("give --out DIR, the directory for report.json and the figures")
    out = Path(text)
    if out.exists() and not out.is_dir():
        raise InputError(f"--out {out} exists and is not a directory")
    created = not out.exists()
    out.mkdir(parents=True, exist_ok=True)
    try:
        fd, probe = tempfile.mkstemp(prefix=".albot2d-probe.", dir=out)
    except OSError as exc:
        remove_if_empty(out, created)
        raise OSError(exc.errno, f"cannot write there ({exc.strerror})", str(out)) from None
    os.close(fd)
    os.unlink(probe)
    return out, created


def remove_if_empty(out: Path, created: bool) -> None:
    """Remove ``out`` again if this command created it and nothing was left in it."""
    if created:
        with contextlib.suppress(OSError):
            out.rmdir()  # only succeeds when nothing was left in it


def _render(
    result: ExperimentResult, no_figures: bool, command: str, animate: bool = False
) -> dict[str, bytes]:
    if no_figures:
        return {}
    try:
        from albot2d.viz.run_figures import render_experiment_figures

        figures = render_experiment_figures(result)
        if animate:
            from albot2d.viz.anim import render_map_animation

            animation = render_map_animation(result)
            if not animation:
                print(
                    f"albot2d {command}: note: no animation (no mapper keeps a map history; "
                    "give --mapper albot1)",
                    file=sys.stderr,
                )
            figures.update(animation)
        return figures
    except ImportError as exc:
        if not (exc.name or "").startswith("matplotlib"):
            raise  # our own import broke: a bug to see, not a missing extra
        print(
            f"albot2d {command}: note: no figures ({exc}); pip install 'albot2d[viz]'",
            file=sys.stderr,
        )
        return {}


def _step_figure(result: ExperimentResult, no_figures: bool) -> dict[str, bytes]:
    if no_figures:
        return {}
    try:
        from albot2d.viz.steps import render_step_times_png

        return {"steps.png": render_step_times_png(result.trace.step_times)}
    except ImportError as exc:
        if not (exc.name or "").startswith("matplotlib"):
            raise
        return {}  # _render already said that matplotlib is missing


def write_outputs(out: Path, report: Mapping[str, object], figures: Mapping[str, bytes]) -> None:
    """Write the files (figures, exports) and report.json atomically; report.json is
    renamed into place last."""
    from albot2d.evaluation.run.report import REPORT_NAME, report_json

    text = report_json(report).encode("utf-8")
    # the report (given first) is renamed into place last
    with atomic_paths([out / REPORT_NAME, *(out / name for name in figures)]) as temps:
        temps[out / REPORT_NAME].write_bytes(text)
        for name, data in figures.items():
            temps[out / name].write_bytes(data)


def finish(
    out: Path,
    created: bool,
    command: str,
    compute: Callable[[], ExperimentResult],
    no_figures: bool,
    stage: Callable[[str], None] | None = None,
    animate: bool = False,
    extra_exports: Callable[[ExperimentResult], list[str]] | None = None,
) -> ExperimentResult:
    """Run ``compute`` (→ ExperimentResult), draw the figures, export the trajectories and
    maps, write everything; on any failure remove the output directory again if this
    command created it. ``extra_exports(result)`` writes the ``--export`` files itself
    (before report.json) and returns their names."""
    from albot2d.evaluation.run.export import export_files

    try:
        result = compute()
        if stage is not None and not no_figures:
            stage("figures")
        figures = _render(result, no_figures, command, animate)
        figures.update(_step_figure(result, no_figures))
        exports = export_files(result)
        extra = extra_exports(result) if extra_exports is not None else []
        result.report["figures"] = sorted(figures)
        result.report["exports"] = sorted([*exports, *extra])
        # steps.csv: one row per view (stage times, counters), for profiling a run.
        files = {
            **figures,
            **exports,
            "steps.csv": result.trace.step_times.to_csv().encode("utf-8"),
        }
        write_outputs(out, result.report, files)
    except BaseException:
        remove_if_empty(out, created)
        raise
    return result


def progress_bar(total: float | None, unit: str, desc: str) -> tqdm[NoReturn]:
    from tqdm import tqdm

    return tqdm(
        total=total,
        unit=unit,
        desc=desc,
        file=sys.stderr,
        leave=False,
        disable=not sys.stderr.isatty(),
        dynamic_ncols=True,
    )


def print_tables(result: ExperimentResult, out: Path, as_json: bool = False) -> None:
    """The result tables on stdout, or (``--json``) the report itself."""
    from albot2d.evaluation.run.report import (
        REPORT_NAME,
        format_homing_table,
        format_summary_table,
        report_json,
    )

    report = result.report
    if as_json:
        print(report_json(report))
        return
    print(f"{result.title}  ({report['wall_time_s']:.1f} s)")
    print(format_summary_table(result.scores))
    print(format_homing_table(result.scores))
    if "exploration" in report:  # albot2d run --tour explore
        from albot2d.control.exploration import format_coverage_table

        print(format_coverage_table(report["exploration"]))
    files = report["figures"] + report.get("exports", [])
    print(
        f"-> {out / REPORT_NAME} + {len(files)} files ({', '.join(files)})"
        if len(files) <= 4
        else f"-> {out / REPORT_NAME} + {len(files)} files"
    )


def differences(a: object, b: object, path: str = "") -> list[str]:
    """Dotted paths (``mappers.albot1.rpe``) where two JSON values differ."""
    if isinstance(a, dict) and isinstance(b, dict):
        out: list[str] = []
        for key in sorted(set(a) | set(b)):
            out += differences(a.get(key), b.get(key), f"{path}.{key}" if path else key)
        return out
    if isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        return [
            d
            for i, (x, y) in enumerate(zip(a, b, strict=True))
            for d in differences(x, y, f"{path}[{i}]")
        ]
    return [] if a == b else [path]


def report_differences(recorded: Mapping[str, object], report: Mapping[str, object]) -> list[str]:
    """Where ``report`` differs from the ``recorded`` one (a report.json or a fuzzing
    reproducer), apart from wall-clock timings, file lists and the version."""
    from albot2d.evaluation.run.report import without_timings

    return differences(
        {k: v for k, v in without_timings(dict(recorded)).items() if k not in _NOT_COMPARED},
        {k: v for k, v in without_timings(dict(report)).items() if k not in _NOT_COMPARED},
    )


def add_albot1_keys_to_help(parser: argparse.ArgumentParser) -> None:
    """``parser --help`` ends with every ``albot1[KEY=VALUE]`` key, generated from the
    ``Albot1Params`` dataclasses when help is asked for (not at every start-up)."""
    plain = parser.format_help

    def format_help() -> str:
        from albot2d.mapping.albot1.options import option_help

        parser.epilog = option_help()
        return str(plain())

    # (help is generated on demand: a method replaced on this one parser)
    parser.format_help = format_help  # type: ignore[method-assign]
