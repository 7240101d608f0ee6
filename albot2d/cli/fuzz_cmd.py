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

``albot2d run --reproduce REPRODUCER`` (``reproduce_failure`` here) re-runs a failing
episode with its invariant checks and exits 1 when it still fails.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import sys
from pathlib import Path
from typing import Any

from albot2d.atomic import atomic_write_bytes
from albot2d.cli.common import add_json_option
from albot2d.cli.options import positive_int, positive_number, seed_value
from albot2d.errors import InputError

__all__ = ["register", "reproduce_failure", "reproducer_document", "run"]

# CampaignParams' defaults, named here only for --help (tests/test_setup.py checks them).
DEFAULTS = {
    "profile": "dataset3",
    "noise": "typical",
    "laser_noise": "sick_lms200",
    "mapper": "albot1",
    "tour_kind": "loop",
    "backend": "local",
}


def register(subparsers: Any) -> None:
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
        help="world kinds to draw from (default: all: corridors rooms open office mixed)",
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
        help="minimum tour length range in metres (default 30 60)",
    )
    p.add_argument("--tour-kind", help="loop, out_and_back, backtracking (default loop)")
    p.add_argument("--profile", help=f"driving profile (default {DEFAULTS['profile']})")
    p.add_argument(
        "--noise", help=f"odometry noise: none, low, typical, high (default {DEFAULTS['noise']})"
    )
    p.add_argument("--laser-noise", help="sick_lms200 or zero (default sick_lms200)")
    p.add_argument(
        "--mapper",
        metavar="NAME",
        help="mapper under test: albot1, naive, truth, … or module:Class (default albot1)",
    )
    p.add_argument("--workers", metavar="K", help="worker processes (default: every core)")
    p.add_argument("--backend", help="local (process pool) or dask (default local)")
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


def _params(args: argparse.Namespace) -> Any:
    from albot2d.evaluation.fuzz.campaign import CampaignParams

    if args.episodes is None:
        raise InputError("give --episodes N, the number of episodes to run")
    values: dict[str, Any] = {"episodes": positive_int(args.episodes, "--episodes")}
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
    return CampaignParams(**values)


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

    name = args.backend or DEFAULTS["backend"]
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
        png = render_campaign_histograms_png([records[k] for k in sorted(records)])
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


# -- albot2d run --reproduce of a fuzzing reproducer -------------------------------------
def _failure_lines(record: dict[str, Any]) -> list[str]:
    if record.get("status") == "crash":
        error = record.get("error") or {}
        return [f"crash: {error.get('type')}: {error.get('message')}"]
    return [
        f"{name} violated: {messages[0]}"
        + (f" (+{len(messages) - 1} more)" if len(messages) > 1 else "")
        for name, messages in (record.get("violations") or {}).items()
    ] or ["?"]


def _replay_isolated(doc: dict[str, Any], where: str) -> tuple[int | None, dict[str, Any] | None]:
    """Run the episode in a child process (its worker died: it may kill this one too);
    returns the child's exit code and, when it lived, the new record."""
    import multiprocessing

    context = multiprocessing.get_context("spawn")
    receive, send = context.Pipe(duplex=False)
    child = context.Process(target=_replay_child, args=(doc, where, send), daemon=True)
    child.start()
    send.close()
    try:
        record = receive.recv()
    except EOFError:
        record = None
    child.join()
    return child.exitcode, record


def _replay_child(doc: dict[str, Any], where: str, send: Any) -> None:
    from albot2d.evaluation.fuzz.reproducer import reproduce_episode

    send.send(reproduce_episode(doc, where=where)[0].record)


def reproducer_document(path: str) -> dict[str, Any] | None:
    """The fuzzing reproducer at ``path``; ``None`` when it is anything else (a report,
    or not readable: ``read_report`` then says what is wrong)."""
    try:
        with open(path, encoding="utf-8") as handle:
            doc = json.load(handle)
    except (OSError, ValueError, RecursionError):
        return None
    return doc if isinstance(doc, dict) and isinstance(doc.get("reproducer"), dict) else None


def reproduce_failure(args: argparse.Namespace, doc: dict[str, Any]) -> int:
    """``albot2d run --reproduce REPRODUCER``: run the failing episode again with every
    invariant check, write its report and figures to ``--out`` (unless it crashes), say
    whether the run and the failure came out the same; exit 1 when it still fails."""
    from albot2d.cli import common
    from albot2d.evaluation.fuzz.reproducer import reproduce_episode, reproducer_spec

    where = args.reproduce
    recorded = doc["reproducer"].get("episode")
    if not isinstance(recorded, dict) or recorded.get("status") not in ("violation", "crash"):
        raise InputError(f"{where}: not a fuzzing reproducer (no failing episode in it)")
    try:
        spec = reproducer_spec(doc, where=where)
    except InputError:
        raise
    except Exception as exc:  # the episode cannot even be drawn: that is the failure
        print(f"reproduce: crash: {type(exc).__name__}: {exc} (drawing the episode)")
        return 1
    # A mapper that cannot be imported here is bad input, not a reproduced crash.
    from albot2d.evaluation.run.setup import check_spec

    check_spec(spec.run_spec())
    out, created = common.prepare_out_dir(args.out)
    result = None
    try:
        if (recorded.get("error") or {}).get("type") == "WorkerDiedError":
            code, record = _replay_isolated(doc, where)
            if record is None:
                print(
                    f"reproduce: the episode killed its process again (exit code {code}); "
                    f"recorded: {_failure_lines(recorded)[0]}"
                )
                common.remove_if_empty(out, created)
                return 1
        outcome, result = reproduce_episode(doc, where=where)
        if result is not None:
            common.finish(out, created, "run", lambda: result, args.no_figures)
        else:
            common.remove_if_empty(out, created)
    except BaseException:
        common.remove_if_empty(out, created)
        raise
    record = outcome.record
    if result is not None:
        common.print_tables(result, out)
        diff = common.report_differences(doc, result.report)
        if recorded["status"] != "crash":
            verdict = "identical to" if not diff else f"differs at {', '.join(diff[:5])} from"
            print(f"reproduce: run {verdict} {where} (apart from wall-clock timings)")
    else:
        print((record["error"] or {}).get("traceback", ""), file=sys.stderr, end="")
    checked = len(record["checked"])
    if record["status"] == "ok":
        print(
            f"reproduce: every invariant holds ({checked} checked); the recorded failure "
            f"does not reproduce: {_failure_lines(recorded)[0]}"
        )
        return 0
    for line in _failure_lines(record):
        print(f"reproduce: {line}")
    same = (
        record["status"] == recorded["status"]
        and sorted(record["violations"]) == sorted(recorded.get("violations") or {})
        and (record["error"] or {}).get("type") == (recorded.get("error") or {}).get("type")
    )
    print(
        "reproduce: the recorded failure reproduces"
        if same
        else f"reproduce: fails differently from the record ({_failure_lines(recorded)[0]})"
    )
    return 1
