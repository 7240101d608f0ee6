"""``albot2d experiments``: the paper's experiments regenerated, side by side with its numbers.

Runs the named experiments (default: all) over ``--seeds`` on the fig6 world (the paper's
Fig. 6 building, a different one per seed) and the open halls, on a local process pool
(``--workers``) or a dask cluster (``--backend dask``); results are the same whatever the
worker count. Writes ``DIR/experiments.json`` (the paper's numbers beside ours, mean ± sd
over seeds and per seed, a verdict per experiment), the figures as PNG files and
``DIR/index.html``. ``--quick`` is a smoke run (seeds 0-1, long runs cut short) whose
numbers are not comparable to the paper's. Bad input: one line, exit 2, nothing written.

Experiments: counts, table1, fig7, fig10, fig11_12, fig13, fig14, fig15, fig16.

Readings (``--readings``, default ``default paper_literal``): every experiment is computed
under each reading of the paper, each an Albot₁ driven on the same frames beside the
others: ``default`` (albot2d's reading), ``paper_literal`` (the paper's text wherever it
speaks: no gate against path integration, an endpoint occluded only behind something
nearer, the occluding endpoint in the current view, algorithm #4 as written),
``original`` (the authors' C++ code), ``start_stop``, or any
``albot1[KEY=VALUE,...]`` spec. The first is the primary reading: its results are each
experiment's top-level ``ours`` and ``verdict``; ``readings`` holds every reading's.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path
from typing import TYPE_CHECKING, NoReturn

from albot2d.errors import InputError
from albot2d.validation import parse_seed_list

if TYPE_CHECKING:
    from tqdm import tqdm

    from albot2d.evaluation.paper.campaign import ExperimentsData, ExperimentsOutcome

__all__ = ["register", "run"]

SMOKE_RUN = "smoke run"  # the words --quick output is marked with, everywhere it shows
FULL_SEEDS = "0-19"
QUICK_SEEDS = "0-1"


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = subparsers.add_parser(
        "experiments", help="the paper's experiments regenerated beside its numbers",
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter,
    )  # fmt: skip
    p.add_argument(
        "--only",
        nargs="+",
        action="extend",
        metavar="NAME",
        help="run only these experiments (default: all)",
    )
    p.add_argument(
        "--seeds",
        metavar="RANGE",
        help=f"seeds: A-B, A,B,C or N (default {FULL_SEEDS}; --quick {QUICK_SEEDS})",
    )
    p.add_argument("--workers", metavar="K", help="worker processes (default: every core)")
    p.add_argument("--backend", default="local", help="local (default) or dask")
    p.add_argument("--address", metavar="tcp://HOST:PORT", help="dask scheduler (dask only)")
    p.add_argument(
        "--quick", action="store_true", help="smoke run for CI: few seeds, the long runs cut short"
    )
    p.add_argument(
        "--readings",
        nargs="+",
        metavar="READING",
        help="readings of the paper to run side by side: default, paper_literal, original, "
        "start_stop or albot1[KEY=VALUE,...] (default: default paper_literal)",
    )
    p.add_argument("--no-figures", action="store_true", help="skip the PNG figures")
    p.add_argument("--out", metavar="DIR", help="output directory (required)")
    p.set_defaults(handler=run)


def _workers(text: str | None) -> int:
    from albot2d.cli.options import positive_int

    value = positive_int(text, "--workers")
    return value if value is not None else max(1, len(os.sched_getaffinity(0)))


def _check_out(text: str | None) -> Path:
    if not text:
        raise InputError("--out DIR is required")
    out = Path(text)
    if out.exists() and not out.is_dir():
        raise InputError(f"--out {text}: exists and is not a directory")
    return out


def run(args: argparse.Namespace) -> int:
    from albot2d.evaluation.fuzz.backends import make_backend
    from albot2d.evaluation.paper import EXPERIMENTS, plan_jobs, run_experiments
    from albot2d.evaluation.paper.campaign import check_readings
    from albot2d.evaluation.paper.runs import DEFAULT_READINGS

    out = _check_out(args.out)
    names = list(dict.fromkeys(args.only or EXPERIMENTS))
    seeds = parse_seed_list(args.seeds or (QUICK_SEEDS if args.quick else FULL_SEEDS))
    jobs = plan_jobs(names, seeds)  # checks the names before anything runs
    readings = check_readings(args.readings or DEFAULT_READINGS)
    workers = min(_workers(args.workers), len(jobs))
    if args.address is not None and args.backend != "dask":
        raise InputError("--address is for --backend dask")
    if not args.no_figures:
        try:
            import matplotlib  # noqa: F401
        except ImportError:
            raise InputError(
                "figures need matplotlib: pip install 'albot2d[viz]' (or pass --no-figures)"
            ) from None
    backend = make_backend(args.backend, workers=workers, address=args.address)
    if args.quick:  # said first, before anything else is printed
        print(f"albot2d experiments --quick: {SMOKE_RUN} (seeds {', '.join(map(str, seeds))}, "
              "long runs cut short): its numbers and verdicts are not comparable to the "
              "paper's", flush=True)  # fmt: skip
    bar = _progress(len(jobs))
    try:
        outcome = run_experiments(names, seeds, quick=args.quick, backend=backend,
                                  on_job=lambda r, s: _tick(bar, r, s),
                                  readings=readings)  # fmt: skip
    finally:
        backend.close()
        if bar is not None:
            bar.close()
    _write(out, outcome, figures=not args.no_figures)
    _print_summary(outcome.data, out)
    return 0


def _progress(total: int) -> tqdm[NoReturn]:
    from tqdm import tqdm

    return tqdm(total=total, unit="run", desc="experiments", file=sys.stderr,
                disable=None, dynamic_ncols=True)  # fmt: skip


def _tick(bar: tqdm[NoReturn] | None, run_name: str, seed: int) -> None:
    if bar is not None:
        bar.set_postfix_str(f"{run_name} seed {seed}", refresh=False)
        bar.update(1)


def _write(out: Path, outcome: ExperimentsOutcome, *, figures: bool) -> None:
    """Figures first, then the page, experiments.json last (atomically)."""
    from albot2d.atomic import atomic_write_text
    from albot2d.viz.paper_page import PAGE_NAME, render_page

    out.mkdir(parents=True, exist_ok=True)
    written: dict[str, list[dict[str, object]]] = {}
    if figures:
        from albot2d.viz.paper import save_figure

        for name, specs in outcome.figures.items():
            for spec in specs:
                save_figure(dict(spec), out / spec["file"])  # the viz layer reads plain dicts
            written[name] = [{"file": s["file"], "caption": s["caption"], "plot": s["plot"]}
                             for s in specs]  # fmt: skip
    else:
        for result in outcome.data["experiments"].values():
            result["figures"] = []
    atomic_write_text(out / PAGE_NAME, render_page(outcome.data, written))
    atomic_write_text(
        out / "experiments.json", json.dumps(outcome.data, indent=1, allow_nan=False) + "\n"
    )


def _print_summary(data: ExperimentsData, out: Path) -> None:
    width = max(len(n) for n in data["verdicts"])
    by_reading = data.get("verdicts_by_reading") or {
        n: {"default": v} for n, v in data["verdicts"].items()
    }
    readings = list(next(iter(by_reading.values())))
    smoke = f"  ({SMOKE_RUN})" if data.get("quick") else ""
    cols = [max(len(r), 14) for r in readings]
    print(f"{'':<{width}}  " + "  ".join(f"{r:<{c}}" for r, c in zip(readings, cols, strict=True)))
    for name, verdicts in by_reading.items():
        cells = "  ".join(f"{verdicts[r]:<{c}}" for r, c in zip(readings, cols, strict=True))
        print(f"{name:<{width}}  {cells}{smoke}".rstrip())
    print(f"{len(data['seeds'])} seeds, {data['wall_time_s']:.0f} s -> {out}/index.html")
