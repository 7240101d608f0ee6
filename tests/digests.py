"""Stored digests of four short runs, with the readable values they hash: the "behaviour
unchanged" regression check.

Four cases run through the real command line (in this process, real files):

- ``run``: ``albot2d run`` with its defaults (office world seed 0, dataset1, typical noise,
  mappers albot1 naive truth), cut to the first 1000 views (36 m: two homing stops), no figures;
- ``slam``: ``albot2d run --mapper slam`` (the loop-closing mapper, the ``[slam]`` extra),
  cut to the first 600 views;
- ``replay``: ``albot2d replay`` of the first 300 scans of the shared MIT CSAIL log (needs
  the shared data: ``$ALBOT2D_DATA``, ``../shared/data`` or ``/work/shared/data``);
- ``fuzz``: ``albot2d fuzz`` with 6 episodes on one worker (the issue's 20 episodes take
  ~35 s of CPU alone; 6 cover every invariant and both drawn kinds within the test budget).

Each output (report.json; the campaign's summary.json and episodes.jsonl) is made
canonical — wall-clock fields, the version and file lists dropped, paths reduced to their
file names, floats rounded to 12 significant digits (so a last-bit difference from another
CPU's SIMD or libm does not count, anything larger does) — and cut into sections
(``mappers.albot1.homing``, ``episodes.3.metrics``, …). ``tests/digests.json`` stores, per
section, the SHA-256 prefix of its canonical JSON *and the value itself* (a section longer
than ``_FULL_CHARS`` characters of JSON keeps a table of key numbers instead: its first
numeric leaves and the count, minimum, maximum and sum of all of them), so a reviewer
reads in the diff what changed, and a failing test prints old and new values.

A change of behaviour made on purpose is recorded by naming what is expected to change::

    python -m tests.digests                          # rerun, list what differs (old → new)
    python -m tests.digests --update --expect 'run:mappers.albot1.*' --expect 'fuzz:*'

``--update`` rewrites only when every changed section matches an ``--expect`` pattern
(``case:section`` globs; ``case`` alone means all its sections) and refuses otherwise,
writing nothing and naming the sections nobody expected to change.

numba (a default dependency) runs the raycaster, line extraction and laser noise compiled.
The two paths are not bit-identical here (measured: ``run`` and ``replay`` match, but the
fuzz episodes' own pose/map byte digests and one homing maximum differ without numba), so
digests.json records which path made it (``numba``) and a failure names both paths.
"""

from __future__ import annotations

import argparse
import contextlib
import fnmatch
import hashlib
import io
import json
import math
import os
import sys
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

__all__ = [
    "CASES",
    "DIGEST_FILE",
    "canonical",
    "compute",
    "differences",
    "find_mit_log",
    "load",
    "main",
    "readable_changes",
    "unexpected",
]

DIGEST_FILE = Path(__file__).with_name("digests.json")
MIT_LOG = Path("raw") / "mit-csail.clf.gz"
# Wall-clock fields and things that name this build or machine rather than the result.
_DROPPED = frozenset({
    "wall_time_s", "timing_ms", "timings", "episodes_per_min", "workers", "albot2d_version",
    "kernels", "figures", "exports",
})  # fmt: skip
_SIGNIFICANT_DIGITS = 12
# A section whose canonical JSON is longer keeps a table of key numbers, not its value.
_FULL_CHARS = 2000
_KEY_NUMBERS = 12

Section = dict[str, Any]  # {"sha256": str, "value": ...} or {"sha256": str, "numbers": ...}


def find_mit_log() -> Path | None:
    """The shared MIT CSAIL log, or None when no shared data folder is around."""
    from tests.conftest import SHARED_DATA

    roots = [os.environ.get("ALBOT2D_DATA"), SHARED_DATA, "/work/shared/data"]
    for root in roots:
        if root and (Path(root) / MIT_LOG).is_file():
            return Path(root) / MIT_LOG
    return None


def canonical(value: Any) -> Any:
    """``value`` without timings and paths, floats rounded (see the module docstring)."""
    if isinstance(value, dict):
        return {k: canonical(v) for k, v in value.items() if k not in _DROPPED}
    if isinstance(value, list):
        return [canonical(v) for v in value]
    if isinstance(value, float):
        return float(f"{value:.{_SIGNIFICANT_DIGITS}g}") if math.isfinite(value) else repr(value)
    if isinstance(value, str) and ("/" in value or os.sep in value):
        return Path(value).name
    return value


def _text(value: Any) -> str:
    return json.dumps(value, sort_keys=True, separators=(",", ":"), allow_nan=False)


def _leaves(value: Any, prefix: str = "") -> Iterator[tuple[str, Any]]:
    """(path, value) of every leaf, in sorted key order."""
    if isinstance(value, dict):
        for key in sorted(value):
            yield from _leaves(value[key], f"{prefix}.{key}" if prefix else str(key))
    elif isinstance(value, list):
        for i, item in enumerate(value):
            yield from _leaves(item, f"{prefix}[{i}]")
    else:
        yield prefix, value


def key_numbers(value: Any) -> dict[str, Any]:
    """A section too long to store whole: its first numeric leaves and the count, minimum,
    maximum and sum of all of them (and its length in characters of JSON)."""
    numbers = [(p, v) for p, v in _leaves(value)
               if isinstance(v, int | float) and not isinstance(v, bool)]  # fmt: skip
    values = [float(v) for _, v in numbers]
    return {
        "chars": len(_text(value)),
        "count": len(values),
        "min": min(values) if values else None,
        "max": max(values) if values else None,
        "sum": float(f"{math.fsum(values):.{_SIGNIFICANT_DIGITS}g}") if values else None,
        "first": dict(numbers[:_KEY_NUMBERS]),
    }


def section(value: Any) -> Section:
    """One section as stored: its digest and its value (or its key numbers)."""
    text = _text(value)
    digest = hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]
    if len(text) <= _FULL_CHARS:
        return {"sha256": digest, "value": value}
    return {"sha256": digest, "numbers": key_numbers(value)}


def _sections(value: Any, prefix: str, depth: int) -> Iterator[tuple[str, Section]]:
    if isinstance(value, dict) and depth > 0 and value:
        for key, item in value.items():
            yield from _sections(item, f"{prefix}.{key}" if prefix else key, depth - 1)
    else:
        yield prefix, section(value)


def _cli(argv: list[str]) -> None:
    from albot2d.cli import main as cli_main

    with contextlib.redirect_stdout(io.StringIO()) as out:
        status = cli_main(argv)
    if status != 0:
        raise RuntimeError(f"albot2d {' '.join(argv)} exited {status}:\n{out.getvalue()}")


def _read_json(path: Path) -> Any:
    return json.loads(path.read_text(encoding="utf-8"))


def _report(out: Path) -> dict[str, Section]:
    return dict(_sections(canonical(_read_json(out / "report.json")), "", 3))


def _run(out: Path) -> dict[str, Section]:
    _cli(["run", "--max-frames", "1000", "--no-figures", "--out", str(out)])
    return _report(out)


def _slam(out: Path) -> dict[str, Section]:
    _cli(["run", "--mapper", "slam", "--max-frames", "600", "--no-figures", "--out", str(out)])
    return _report(out)


def _replay(out: Path) -> dict[str, Section]:
    log = find_mit_log()
    if log is None:
        raise FileNotFoundError("the shared MIT CSAIL log is not found")
    _cli(["replay", str(log), "--max-frames", "300", "--no-figures", "--out", str(out)])
    return _report(out)


def _fuzz(out: Path) -> dict[str, Section]:
    _cli(["fuzz", "--episodes", "6", "--workers", "1", "--no-figures", "--out", str(out)])
    digests = dict(_sections(canonical(_read_json(out / "summary.json")), "summary", 2))
    lines = (out / "episodes.jsonl").read_text(encoding="utf-8").splitlines()
    episodes = sorted((json.loads(line) for line in lines), key=lambda e: e["episode"])
    for episode in episodes:
        digests |= dict(_sections(canonical(episode), f"episodes.{episode['episode']}", 1))
    return digests


CASES: dict[str, Callable[[Path], dict[str, Section]]] = {
    "run": _run, "slam": _slam, "replay": _replay, "fuzz": _fuzz,
}  # fmt: skip


def numba_available() -> bool:
    from albot2d.sim.raycast import numba_available as available

    return bool(available())


def slam_available() -> bool:
    """Whether the ``[slam]`` extra (kiss-icp, gtsam) imports."""
    import importlib.util

    return all(importlib.util.find_spec(name) for name in ("kiss_icp", "gtsam"))


def compute(case: str) -> dict[str, Section]:
    """Section → stored form of one case, run in a fresh temporary directory."""
    with tempfile.TemporaryDirectory(prefix=f"albot2d-digest-{case}.") as tmp:
        return CASES[case](Path(tmp) / "out")


def load() -> dict[str, Any]:
    """The stored digests: ``{"numba": bool, "cases": {case: {section: Section}}}``."""
    data: dict[str, Any] = _read_json(DIGEST_FILE)
    return data


def _digest(entry: Section | str | None) -> str:
    if entry is None:
        return "missing"
    return entry if isinstance(entry, str) else str(entry["sha256"])


def differences(stored: dict[str, Any], now: dict[str, Any]) -> list[str]:
    """The sections whose digest changed, appeared or disappeared (sorted)."""
    return [
        key for key in sorted(set(stored) | set(now))
        if _digest(stored.get(key)) != _digest(now.get(key))
    ]  # fmt: skip


def _shown(entry: Section | str | None) -> Any:
    if entry is None or isinstance(entry, str):
        return "(not stored)"
    return entry.get("value", entry.get("numbers"))


def readable_changes(stored: dict[str, Any], now: dict[str, Any], keys: list[str]) -> list[str]:
    """For each changed section, what changed, readably: the leaves whose value changed
    (old → new), or the section's old and new values / key numbers."""
    out = []
    for key in keys:
        old, new = _shown(stored.get(key)), _shown(now.get(key))
        if not isinstance(stored.get(key), dict) or now.get(key) is None:
            out.append(f"{key}: {_text(old)[:300]} -> {_text(new)[:300]}")
            continue
        a, b = dict(_leaves(old)), dict(_leaves(new))
        changed = [p for p in sorted(set(a) | set(b)) if a.get(p, "missing") != b.get(p, "missing")]
        out.append(f"{key}: {len(changed)} value(s) differ")
        for path in changed[:8]:
            out.append(f"    {path or '(value)'}: {a.get(path, 'missing')!r} -> "
                       f"{b.get(path, 'missing')!r}")  # fmt: skip
        if len(changed) > 8:
            out.append(f"    … and {len(changed) - 8} more")
    return out


def unexpected(case: str, changed: list[str], expect: list[str]) -> list[str]:
    """The changed sections of ``case`` no ``--expect`` pattern covers: ``case`` alone
    covers every section of it, ``case:GLOB`` the sections matching the glob."""
    patterns = []
    for pattern in expect:
        name, colon, glob = pattern.partition(":")
        if name == case:
            patterns.append(glob if colon else "*")
    return [key for key in changed if not any(fnmatch.fnmatchcase(key, p) for p in patterns)]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m tests.digests",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "--update", action="store_true",
        help=f"rewrite {DIGEST_FILE.name} from fresh runs (every change must be --expect-ed)",
    )  # fmt: skip
    parser.add_argument(
        "--expect", action="append", default=[], metavar="CASE[:SECTION_GLOB]",
        help="a section expected to change (repeatable), e.g. 'run:mappers.albot1.*' or 'fuzz'",
    )  # fmt: skip
    parser.add_argument("cases", nargs="*", help=f"of {', '.join(CASES)} (default: all)")
    args = parser.parse_args(argv)
    cases = args.cases or list(CASES)
    unknown = sorted(set(cases) - set(CASES))
    if unknown:
        parser.error(f"unknown case(s) {', '.join(unknown)}; valid: {', '.join(CASES)}")
    bad = sorted({p.partition(":")[0] for p in args.expect} - set(CASES))
    if bad:
        parser.error(f"--expect names unknown case(s) {', '.join(bad)}; valid: {', '.join(CASES)}")
    stored = load() if DIGEST_FILE.exists() else {"numba": None, "cases": {}}
    if find_mit_log() is None and "replay" in cases:
        print("the shared MIT log is not found: the replay digests are kept", file=sys.stderr)
        cases.remove("replay")
    if not slam_available() and "slam" in cases:
        print("the [slam] extra is not installed: the slam digests are kept", file=sys.stderr)
        cases.remove("slam")
    fresh: dict[str, dict[str, Section]] = {}
    refused: list[str] = []
    changed_any = False
    for case in cases:
        old = stored["cases"].get(case, {})
        now = compute(case)
        diff = differences(old, now)
        changed_any |= bool(diff)
        print(f"{case}: {'identical' if not diff else f'{len(diff)} section(s) differ'}")
        for line in readable_changes(old, now, diff):
            print(f"  {line}")
        refused += [f"{case}:{key}" for key in unexpected(case, diff, args.expect)]
        fresh[case] = now
    if not args.update:
        return 1 if changed_any else 0
    if refused:
        print(
            f"refused: {len(refused)} changed section(s) not named by --expect (nothing "
            "written): " + ", ".join(refused[:20]) + (" …" if len(refused) > 20 else ""),
            file=sys.stderr,
        )
        return 1
    stored["cases"].update(fresh)
    stored["numba"] = numba_available()
    DIGEST_FILE.write_text(json.dumps(stored, indent=1, sort_keys=True) + "\n", encoding="utf-8")
    print(f"wrote {DIGEST_FILE}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
