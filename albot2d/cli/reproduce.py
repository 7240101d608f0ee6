"""``albot2d run --reproduce REPRODUCER`` for a fuzzing reproducer: the failing episode run
again with every invariant check, and whether it fails the same way.

Shared by the ``run`` command (which takes the file) and written by ``fuzz`` (which makes
it); neither command imports the other.
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

from albot2d.errors import InputError

__all__ = ["reproduce_failure", "reproducer_document"]


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
