"""``albot2d run``: the main experiment — world, tour, every mapper, report.json and figures.

Generates (``--kind``/``--seed``) or loads (``--world``) a world, drives a tour through it
with a profile and an odometry noise preset, runs every mapper on the same frames and
writes ``DIR/report.json`` (homing, relative pose error, map quality, process counts,
timings, and every parameter needed to reproduce the run) plus PNGs: the paths, every
mapper's map, Albot1's map history and route map, and homing. ``--reproduce report.json``
re-runs a recorded run and says whether the new report matches it.

Defaults (``albot2d run --out DIR``): office world seed 0, profile dataset1, odometry noise
``typical``, a loop tour of 100-130 m, mappers albot1 naive truth. Every input is
checked before the run; the figures are drawn in memory and report.json is written last,
so a failure leaves no report and no figures.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, TypeVar

from albot2d.cli.common import (
    add_export_option,
    add_json_option,
    add_mapper_option,
    add_out_option,
    add_run_options,
    add_scoring_options,
    finish,
    prepare_out_dir,
    print_tables,
    progress_bar,
    report_differences,
    scoring_params,
    spec_from_args,
)
from albot2d.cli.viewer import add_viewer_options, check_viewer_options, open_viewer
from albot2d.errors import InputError

if TYPE_CHECKING:
    from albot2d.cli.options import Subcommands
    from albot2d.evaluation.run.experiment import ExperimentResult
    from albot2d.frames import Frame
    from worldgen.world import Tour, World

__all__ = ["register", "run"]

T = TypeVar("T")

# Options that describe the run itself; --reproduce takes them from the report instead.
_RUN_OPTIONS = (
    "world",
    "kind",
    "seed",
    "width",
    "height",
    "param",
    "profile",
    "mapper",
    "noise",
    "laser_noise",
    "tour_kind",
    "tour_length",
    "min_tour_length",
    "max_frames",
    "stop_every",
    "min_start_distance",
    "last_k_views",
    "snapshots",
)


def register(subparsers: Subcommands) -> None:
    p = subparsers.add_parser(
        "run", help="run the main experiment: world → tour → every mapper → report + figures",
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter,
    )  # fmt: skip
    add_run_options(p)
    add_mapper_option(
        p,
        "albot1, naive, truth, slam and scan_odometry ([slam] extra)",
        "default: albot1 naive truth",
    )
    add_scoring_options(p)
    p.add_argument(
        "--reproduce",
        metavar="report.json",
        help="re-run the run recorded in a report (give only --out with it)",
    )
    add_out_option(p, no_figures="write report.json only")
    p.add_argument(
        "--animate",
        action="store_true",
        help="also write albot1_map.mp4 (albot1_map.gif where ffmpeg is missing): the global map "
        "over time beside the truth",
    )
    add_export_option(p)
    add_viewer_options(p)
    p.add_argument(
        "--cprofile",
        metavar="FILE",
        help="also write a cProfile pstats file of the run (python -m pstats FILE)",
    )
    add_json_option(p)
    p.set_defaults(handler=run)


def _profiled(path: str | None, compute: Callable[[], T]) -> Callable[[], T]:
    """``compute`` run under cProfile, its pstats written to ``path`` (``--cprofile``)."""
    if path is None:
        return compute

    def profiled() -> T:
        import cProfile

        profiler = cProfile.Profile()
        try:
            return profiler.runcall(compute)
        finally:
            profiler.dump_stats(path)

    return profiled


def _keeps_frames(names: list[str]) -> bool:
    from albot2d.cli.exporters import EXPORTERS

    return any(EXPORTERS[name].needs_frames for name in names)


def _exporting(
    args: argparse.Namespace, frames: list[Frame]
) -> Callable[[Path], Callable[[ExperimentResult], list[str]]] | None:
    """``finish``'s hook writing the ``--export`` files of a finished run (its options
    checked now), given the output directory; None without ``--export``."""
    from albot2d.cli.exporters import ExportSource, export_options, write_exports

    options = export_options(args)
    names = list(args.export or [])
    if not names:
        return None

    def hook(out: Path) -> Callable[[ExperimentResult], list[str]]:
        def write(result: ExperimentResult) -> list[str]:
            source = ExportSource(frames, result.world, result, options)
            return write_exports(out, names, source)

        return write

    return hook


def run(args: argparse.Namespace) -> int:
    from albot2d.control.exploration import DEFAULT_MAX_TIME_S
    from albot2d.evaluation import RunSpec, evaluation_params_from_report, run_experiment
    from albot2d.evaluation.run.report import read_report
    from albot2d.evaluation.run.setup import check_spec

    recorded = None
    if args.reproduce is not None:
        given = [name for name in _RUN_OPTIONS if getattr(args, name) is not None]
        if given:
            flags = ", ".join("--" + n.replace("_", "-") for n in given)
            raise InputError(f"--reproduce takes the run's settings from the report; drop {flags}")
        from albot2d.cli.reproduce import reproduce_failure, reproducer_document

        doc = reproducer_document(args.reproduce)
        if doc is not None:  # a fuzzing reproducer: its invariant checks run too
            return reproduce_failure(args, doc)
        recorded = read_report(args.reproduce)
        spec = RunSpec.from_report(recorded, where=args.reproduce)
        params = evaluation_params_from_report(recorded)
    else:
        spec = spec_from_args(args)
        params = scoring_params(args)
    check_spec(spec)
    kept: list[Frame] = []  # the run's frames, for the exports that need them
    extra = _exporting(args, kept)
    if args.cprofile is not None and not Path(args.cprofile).parent.is_dir():
        raise InputError(f"--cprofile {args.cprofile}: its directory does not exist")
    check_viewer_options(args)
    out, created = prepare_out_dir(args.out)
    viewer = open_viewer(args, f"albot2d run {args.out}")
    bar = None
    total = 0.0  # the bar's end: views, simulated seconds or metres
    keep = _keeps_frames(list(args.export or []))

    def start(world: World, tour: Tour) -> None:
        # With --max-frames the run ends after that many views, not at the tour's end.
        nonlocal bar, total
        if viewer is not None:
            viewer.on_start(world, tour)
        if spec.max_frames is not None:
            total = spec.max_frames
            bar = progress_bar(total, " views", "run")
        elif tour.kind == "explore":  # no tour to measure by: simulated time
            total = DEFAULT_MAX_TIME_S
            bar = progress_bar(total, " s", "explore")
        else:
            total = round(tour.length_m, 1)
            bar = progress_bar(total, "m", "run")

    def frame(f: Frame, travelled: float) -> None:
        if keep:
            kept.append(f)
        if viewer is not None:
            viewer.on_frame(f, travelled)
        if bar is None:
            return
        if spec.max_frames is None and spec.tour_kind == "explore":
            bar.n = round(min(f.timestamp, total), 1)
            bar.set_postfix_str(f"{f.index + 1} views, {travelled:.0f} m", refresh=False)
        elif spec.max_frames is not None:
            bar.n = f.index + 1
            bar.set_postfix_str(f"{travelled:.0f} m", refresh=False)
        else:
            bar.n = round(min(travelled, total), 1)
            bar.set_postfix_str(f"{f.index + 1} views", refresh=False)
        bar.update(0)

    def stage(name: str) -> None:
        if bar is not None:
            bar.set_description(name)

    ok = False
    try:
        result = finish(
            out, created, "run",
            _profiled(args.cprofile, lambda: run_experiment(
                spec, params, on_start=start, on_frame=frame, on_stage=stage,
                on_mappers=None if viewer is None else viewer.on_mappers)),
            args.no_figures, stage, animate=args.animate,
            extra_exports=extra(out) if extra is not None else None,
        )  # fmt: skip
        ok = True
    finally:
        if bar is not None:
            bar.close()
        if viewer is not None:
            viewer.finish(ok)
    print_tables(result, out, args.json)
    if recorded is not None:
        diff = report_differences(recorded, result.report)
        if diff:
            shown = ", ".join(diff[:5]) + (f" and {len(diff) - 5} more" if len(diff) > 5 else "")
            print(f"reproduce: differs from {args.reproduce} at {shown}")
        else:
            print(f"reproduce: identical to {args.reproduce} (apart from wall-clock timings)")
    return 0
