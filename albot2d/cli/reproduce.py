"""``albot2d run --reproduce REPRODUCER`` for a fuzzing reproducer: the failing episode run
again with every invariant check, and whether it fails the same way.

Shared by the ``run`` command (which takes the file) and written by ``fuzz`` (which makes
it); neither command imports the other.
"""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING

from albot2d.errors import InputError

if TYPE_CHECKING:
    from multiprocessing.connection import Connection

    from albot2d.evaluation.fuzz.record import EpisodeRecord, JsonObject
    from albot2d.evaluation.fuzz.reproducer import Reproducer

__all__ = ["reproduce_failure", "reproducer_document"]


def _failure_lines(record: EpisodeRecord) -> list[str]:
    if record.status == "crash":
        error = record.error
        return [f"crash: {error and error.type}: {error and error.message}"]
    return [
        f"{name} violated: {messages[0]}"
        + (f" (+{len(messages) - 1} more)" if len(messages) > 1 else "")
        for name, messages in record.violations.items()
    ] or ["?"]


def _replay_isolated(reproducer: Reproducer, where: str) -> tuple[int | None, EpisodeRecord | None]:
    """Run the episode in a child process (its worker died: it may kill this one too);
    returns the child's exit code and, when it lived, the new record."""
    import multiprocessing

    from albot2d.evaluation.fuzz.record import EpisodeRecord

    context = multiprocessing.get_context("spawn")
    receive, send = context.Pipe(duplex=False)
    child = context.Process(
        target=_replay_child, args=(reproducer.report, where, send), daemon=True
    )
    child.start()
    send.close()
    try:
        record = EpisodeRecord.from_json(receive.recv(), where)
    except EOFError:
        record = None
    child.join()
    return child.exitcode, record


def _replay_child(doc: JsonObject, where: str, send: Connection) -> None:
    """In the child: the new record goes back as plain data."""
    from albot2d.evaluation.fuzz.reproducer import Reproducer, reproduce_episode

    outcome = reproduce_episode(Reproducer.from_json(doc, where), where=where)[0]
    send.send(outcome.record.to_json())


def reproducer_document(path: str) -> JsonObject | None:
    """The fuzzing reproducer at ``path``; ``None`` when it is anything else (a report,
    or not readable: ``read_report`` then says what is wrong)."""
    from albot2d.inputfiles import read_json_file

    try:
        doc = read_json_file(path, "report")
    except (OSError, InputError):
        return None
    return doc if isinstance(doc, dict) and isinstance(doc.get("reproducer"), dict) else None


def reproduce_failure(args: argparse.Namespace, doc: JsonObject) -> int:
    """``albot2d run --reproduce REPRODUCER``: run the failing episode again with every
    invariant check, write its report and figures to ``--out`` (unless it crashes), say
    whether the run and the failure came out the same; exit 1 when it still fails."""
    from albot2d.cli import common
    from albot2d.evaluation.fuzz.reproducer import Reproducer, reproduce_episode

    where = args.reproduce
    section = doc["reproducer"]
    episode = section.get("episode") if isinstance(section, dict) else None
    if not isinstance(episode, dict) or episode.get("status") not in ("violation", "crash"):
        raise InputError(f"{where}: not a fuzzing reproducer (no failing episode in it)")
    reproducer = Reproducer.from_json(doc, where)
    recorded = reproducer.episode
    try:
        spec = reproducer.spec(where)
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
        if recorded.error is not None and recorded.error.type == "WorkerDiedError":
            code, isolated = _replay_isolated(reproducer, where)
            if isolated is None:
                print(
                    f"reproduce: the episode killed its process again (exit code {code}); "
                    f"recorded: {_failure_lines(recorded)[0]}"
                )
                common.remove_if_empty(out, created)
                return 1
        outcome, result = reproduce_episode(reproducer, where=where)
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
        if recorded.status != "crash":
            verdict = "identical to" if not diff else f"differs at {', '.join(diff[:5])} from"
            print(f"reproduce: run {verdict} {where} (apart from wall-clock timings)")
    else:
        print((record.error and record.error.traceback) or "", file=sys.stderr, end="")
    checked = len(record.checked)
    if record.status == "ok":
        print(
            f"reproduce: every invariant holds ({checked} checked); the recorded failure "
            f"does not reproduce: {_failure_lines(recorded)[0]}"
        )
        return 0
    for line in _failure_lines(record):
        print(f"reproduce: {line}")
    same = (
        record.status == recorded.status
        and sorted(record.violations) == sorted(recorded.violations)
        and (record.error and record.error.type) == (recorded.error and recorded.error.type)
    )
    print(
        "reproduce: the recorded failure reproduces"
        if same
        else f"reproduce: fails differently from the record ({_failure_lines(recorded)[0]})"
    )
    return 1
