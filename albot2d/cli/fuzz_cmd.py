"""``albot2d fuzz``: a fuzzing campaign — many small random episodes, every invariant checked.

Each episode draws a world kind, a world size and a tour length from its own seed (a
``SeedSequence.spawn`` child of ``--seed``), drives the tour with the profile and noise,
maps it with the mapper and checks the invariants (route map connected, the local-map
rule, algorithm #5's deletions, robot clear of obstacles, laser hits on obstacles, heading
error within the noise bound, zero-noise localisation when there is no noise). Results do
not depend on ``--workers`` or the backend.

Episodes run on a process pool on this machine (``--workers``, default: every core) or on
a dask.distributed cluster (``--backend dask --address tcp://HOST:PORT``; without an
address a local dask cluster is started). Written to ``--out DIR``: ``episodes.jsonl`` (one
line per episode, on disk as soon as it finishes), ``reproducers/episode-K.json`` for
each failing episode (``albot2d run --reproduce FILE --out D`` replays it),
``summary.json``, ``histograms.png`` and ``campaign.json``. ``--resume`` continues an
interrupted campaign (only one written with the same options; the folder is locked
while a campaign runs). Ctrl-C once: the running episodes finish and are kept; twice: it
stops at once. Exit status: 0 when every episode passed, 1 when any failed, 2 on bad
input, 130 when interrupted.

``albot2d run --reproduce REPRODUCER`` (``albot2d.cli.reproduce``) re-runs a failing
episode with its invariant checks and exits 1 when it still fails.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from albot2d.atomic import atomic_write_bytes
from albot2d.cli.common import add_json_option, add_noise_options, choices
from albot2d.cli.options import positive_int, positive_number, seed_value
from albot2d.errors import InputError

if TYPE_CHECKING:
    from albot2d.evaluation.fuzz.campaign import CampaignParams

__all__ = ["register", "run"]


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    from albot2d.evaluation.fuzz.backends import BACKENDS
    from albot2d.evaluation.fuzz.campaign import CampaignParams

    names, default = choices(), CampaignParams(episodes=1)
    p = subparsers.add_parser(
        "fuzz", help="fuzzing campaign: many random episodes, invariants checked, reproducers",
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter,
    )  # fmt: skip
    p.add_argument("--episodes", metavar="N", required=True, help="number of episodes")
    p.add_argument("--seed", metavar="S", help="campaign seed (default 0)")
    p.add_argument(
        "--kinds",
        nargs="+",
        action="extend",
        metavar="KIND",
        help=f"world kinds to draw from: {', '.join(names.world_kinds)} "
        f"(default {' '.join(default.kinds)})",
    )
    p.add_argument(
        "--world-size",
        nargs=2,
        metavar=("MIN", "MAX"),
        help="world width and height range in metres (default 15 30; offices are "
        "at least 24 m, mixed worlds 32 m)",
    )
    p.add_argument(
        "--tour-length",
        nargs=2,
        metavar=("MIN", "MAX"),
        help="minimum tour length range in metres "
        f"(default {default.tour_length_min_m:g} {default.tour_length_max_m:g})",
    )
    p.add_argument(
        "--tour-kind", help=f"{', '.join(names.tour_kinds)} (default {default.tour_kind})"
    )
    add_noise_options(
        p, profile=default.profile, noise=default.noise, laser_noise=default.laser_noise
    )
    p.add_argument(
        "--mapper",
        metavar="NAME",
        help="mapper under test: albot1, naive, truth, albot1[KEY=VALUE,...] (keys listed "
        f"below) or module:Class (default {default.mapper})",
    )
    from albot2d.cli.common import add_albot1_keys_to_help

    add_albot1_keys_to_help(p)
    p.add_argument("--workers", metavar="K", help="worker processes (default: every core)")
    p.add_argument(
        "--backend",
        help=f"{' or '.join(BACKENDS)}: a local process pool or a dask cluster "
        f"(default {BACKENDS[0]})",
    )
    p.add_argument("--address", metavar="tcp://HOST:PORT", help="dask scheduler to use")
    p.add_argument(
        "--resume",
        action="store_true",
        help="continue the campaign in --out (skip the episodes already done)",
    )
    p.add_argument("--no-figures", action="store_true", help="no histograms.png")
    add_json_option(p, "print summary.json on stdout instead of the summary table")
    p.add_argument(
        "--out", metavar="DIR", required=True, help="output directory (created if missing)"
    )
    p.set_defaults(handler=run)


def _range(values: list[str] | None, option: str) -> tuple[float, float] | None:
    if values is None:
        return None
    low, high = (positive_number(v, option) for v in values)
    assert low is not None and high is not None
    if low > high:
        raise InputError(f"{option}: MIN {low:g} is larger than MAX {high:g}")
    return low, high


def _params(args: argparse.Namespace) -> CampaignParams:
    from albot2d.evaluation.fuzz.campaign import CampaignParams

    if args.episodes is None:
        raise InputError("give --episodes N, the number of episodes to run")
    values: dict[str, object] = {"episodes": positive_int(args.episodes, "--episodes")}
    seed = seed_value(args.seed)
    if seed is not None:
        values["seed"] = seed
    if args.kinds:
        values["kinds"] = tuple(args.kinds)
    for name in ("profile", "noise", "laser_noise", "mapper", "tour_kind"):
        if getattr(args, name):  # not given: CampaignParams' default
            values[name] = getattr(args, name)
    size = _range(args.world_size, "--world-size")
    if size is not None:
        values["world_size_min_m"], values["world_size_max_m"] = size
    tour = _range(args.tour_length, "--tour-length")
    if tour is not None:
        values["tour_length_min_m"], values["tour_length_max_m"] = tour
    return CampaignParams(**values)  # type: ignore[arg-type]  # checked in __post_init__


def _workers(text: str | None) -> int:
    workers = positive_int(text, "--workers")
    if workers is not None:
        return workers
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def _check_backend(args: argparse.Namespace) -> str:
    from albot2d.evaluation.fuzz.backends import BACKENDS

    name = args.backend or BACKENDS[0]
    if name not in BACKENDS:
        raise InputError(f"unknown backend {name!r}; valid: {', '.join(BACKENDS)}")
    if name == "local" and args.address is not None:
        raise InputError("--address is for --backend dask")
    if name == "dask":
        try:
            import dask.distributed  # noqa: F401
        except ImportError:
            raise InputError(
                "--backend dask needs dask.distributed: pip install 'albot2d[dask]'"
            ) from None
    return name


def _write_histograms(out: Path, no_figures: bool) -> str | None:
    from albot2d.evaluation.fuzz.campaign import EPISODES_NAME, HISTOGRAMS_NAME, read_episodes

    if no_figures:
        return None
    try:
        from albot2d.viz.campaign import render_campaign_histograms_png

        records, _ = read_episodes(out / EPISODES_NAME)
        # the figure reads records as episodes.jsonl has them (plain data)
        png = render_campaign_histograms_png([records[k].to_json() for k in sorted(records)])
    except ImportError as exc:
        print(
            f"albot2d fuzz: note: no histograms ({exc}); pip install 'albot2d[viz]'",
            file=sys.stderr,
        )
        return None
    atomic_write_bytes(out / HISTOGRAMS_NAME, png)
    return HISTOGRAMS_NAME


def _note(line: str) -> None:
    print(f"albot2d fuzz: {line}", file=sys.stderr, flush=True)


def run(args: argparse.Namespace) -> int:
    from albot2d.cli.common import prepare_out_dir
    from albot2d.evaluation.fuzz.backends import make_backend
    from albot2d.evaluation.fuzz.campaign import CampaignInterrupted, run_campaign
    from albot2d.evaluation.fuzz.summary import format_summary

    params = _params(args)
    workers = _workers(args.workers)
    backend_name = _check_backend(args)
    out, created = prepare_out_dir(args.out)
    try:
        backend = make_backend(backend_name, workers=workers, address=args.address)
        try:
            summary = run_campaign(
                params, out, backend=backend, resume=args.resume, progress=True, on_note=_note
            )
        finally:
            backend.close()
    except CampaignInterrupted as exc:
        _note(
            f"interrupted: {exc.done} of {exc.total} episodes are in "
            f"{out / 'episodes.jsonl'}; continue with the same options and --resume"
        )
        return 130
    except BaseException:
        if created:
            with contextlib.suppress(OSError):
                out.rmdir()  # only when nothing was written
        raise
    figure = _write_histograms(out, args.no_figures)
    if args.json:
        print(json.dumps(summary, indent=2, allow_nan=False))
        return 1 if summary["violations"] + summary["crashes"] else 0
    print(format_summary(summary))
    failing = summary["violations"] + summary["crashes"]
    files = ["episodes.jsonl", "summary.json"] + ([figure] if figure else [])
    if failing:
        files.append(f"{failing} reproducer(s) in reproducers/")
    print(f"-> {out}: {', '.join(files)}")
    return 1 if failing else 0
