"""Stored digests of three short runs: the "behaviour unchanged" regression check.

Three cases run through the real command line (in this process, real files):

- ``run``: ``albot2d run`` with its defaults (office world seed 0, dataset1, typical noise,
  mappers albot1 naive truth), cut to the first 1000 views (36 m: two homing stops), no figures;
- ``replay``: ``albot2d replay`` of the first 300 scans of the shared MIT CSAIL log (needs
  the shared data: ``$ALBOT2D_DATA``, ``../shared/data`` or ``/work/shared/data``);
- ``fuzz``: ``albot2d fuzz`` with 6 episodes on one worker (the issue's 20 episodes take
  ~35 s of CPU alone; 6 cover every invariant and both drawn kinds within the test budget).

Each output (report.json; the campaign's summary.json and episodes.jsonl) is made
canonical — wall-clock fields, the version and file lists dropped, paths reduced to their
file names, floats rounded to 12 significant digits (so a last-bit difference from another
CPU's SIMD or libm does not count, anything larger does) — and hashed section by section
(``mappers.albot1.homing``, ``episodes.3.metrics``, …), so a mismatch names what changed.

``tests/digests.json`` holds the stored digests. A change of behaviour made on purpose
(mapping, simulation) is recorded deliberately::

    python -m tests.digests --update     # rerun the cases, rewrite tests/digests.json
    python -m tests.digests              # rerun and list the sections that differ

numba (a default dependency) runs the raycaster, line extraction and laser noise compiled.
The two paths are not bit-identical here (measured: ``run`` and ``replay`` match, but the
fuzz episodes' own pose/map byte digests and one homing maximum differ without numba), so
digests.json records which path made it (``numba``) and a failure names both paths.
"""

from __future__ import annotations

import argparse
import contextlib
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

__all__ = ["CASES", "DIGEST_FILE", "canonical", "compute", "find_mit_log", "load", "main"]

DIGEST_FILE = Path(__file__).with_name("digests.json")
MIT_LOG = Path("raw") / "mit-csail.clf.gz"
# Wall-clock fields and things that name this build or machine rather than the result.
_DROPPED = frozenset({
    "wall_time_s", "timing_ms", "timings", "episodes_per_min", "workers", "albot2d_version",
    "kernels", "figures", "exports",
})  # fmt: skip
_SIGNIFICANT_DIGITS = 12


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


def _hash(value: Any) -> str:
    text = json.dumps(value, sort_keys=True, separators=(",", ":"), allow_nan=False)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]


def _sections(value: Any, prefix: str, depth: int) -> Iterator[tuple[str, str]]:
    if isinstance(value, dict) and depth > 0 and value:
        for key, item in value.items():
            yield from _sections(item, f"{prefix}.{key}" if prefix else key, depth - 1)
    else:
        yield prefix, _hash(value)


def _cli(argv: list[str]) -> None:
    from albot2d.cli import main as cli_main

    with contextlib.redirect_stdout(io.StringIO()) as out:
        status = cli_main(argv)
    if status != 0:
        raise RuntimeError(f"albot2d {' '.join(argv)} exited {status}:\n{out.getvalue()}")


def _read_json(path: Path) -> Any:
    return json.loads(path.read_text(encoding="utf-8"))


def _run(out: Path) -> dict[str, str]:
    _cli(["run", "--max-frames", "1000", "--no-figures", "--out", str(out)])
    return dict(_sections(canonical(_read_json(out / "report.json")), "", 3))


def _replay(out: Path) -> dict[str, str]:
    log = find_mit_log()
    if log is None:
        raise FileNotFoundError("the shared MIT CSAIL log is not found")
    _cli(["replay", str(log), "--max-frames", "300", "--no-figures", "--out", str(out)])
    return dict(_sections(canonical(_read_json(out / "report.json")), "", 3))


def _fuzz(out: Path) -> dict[str, str]:
    _cli(["fuzz", "--episodes", "6", "--workers", "1", "--no-figures", "--out", str(out)])
    digests = dict(_sections(canonical(_read_json(out / "summary.json")), "summary", 2))
    lines = (out / "episodes.jsonl").read_text(encoding="utf-8").splitlines()
    episodes = sorted((json.loads(line) for line in lines), key=lambda e: e["episode"])
    for episode in episodes:
        digests |= dict(_sections(canonical(episode), f"episodes.{episode['episode']}", 1))
    return digests


CASES: dict[str, Callable[[Path], dict[str, str]]] = {
    "run": _run, "replay": _replay, "fuzz": _fuzz,
}  # fmt: skip


def numba_available() -> bool:
    from albot2d.sim.raycast import numba_available as available

    return bool(available())


def compute(case: str) -> dict[str, str]:
    """Section → digest of one case, run in a fresh temporary directory."""
    with tempfile.TemporaryDirectory(prefix=f"albot2d-digest-{case}.") as tmp:
        return CASES[case](Path(tmp) / "out")


def load() -> dict[str, Any]:
    """The stored digests (``{"numba": bool, "cases": {case: {section: digest}}}``)."""
    return _read_json(DIGEST_FILE)  # type: ignore[no-any-return]


def differences(stored: dict[str, str], now: dict[str, str]) -> list[str]:
    """The sections whose digest changed, appeared or disappeared."""
    return [
        f"{key}: {stored.get(key, 'missing')} -> {now.get(key, 'missing')}"
        for key in sorted(set(stored) | set(now))
        if stored.get(key) != now.get(key)
    ]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m tests.digests",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "--update", action="store_true", help=f"rewrite {DIGEST_FILE.name} from fresh runs"
    )
    parser.add_argument("cases", nargs="*", help=f"of {', '.join(CASES)} (default: all)")
    args = parser.parse_args(argv)
    cases = args.cases or list(CASES)
    unknown = sorted(set(cases) - set(CASES))
    if unknown:
        parser.error(f"unknown case(s) {', '.join(unknown)}; valid: {', '.join(CASES)}")
    stored = load() if DIGEST_FILE.exists() else {"numba": None, "cases": {}}
    if args.update and find_mit_log() is None and "replay" in cases:
        print("the shared MIT log is not found: the replay digests are kept", file=sys.stderr)
        cases.remove("replay")
    changed = 0
    for case in cases:
        now = compute(case)
        diff = differences(stored["cases"].get(case, {}), now)
        changed += bool(diff)
        print(f"{case}: {'identical' if not diff else f'{len(diff)} section(s) differ'}")
        for line in diff:
            print(f"  {line}")
        stored["cases"][case] = now
    if args.update:
        stored["numba"] = numba_available()
        DIGEST_FILE.write_text(
            json.dumps(stored, indent=1, sort_keys=True) + "\n", encoding="utf-8"
        )
        print(f"wrote {DIGEST_FILE}")
        return 0
    return 1 if changed else 0


if __name__ == "__main__":
    sys.exit(main())
