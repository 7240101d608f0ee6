"""Path integrations per reading on Fig. 16's route (S → E7), datasets 1 and 2, and why.

The paper's Albot₁ used path integration 5 times with dataset 1 and 7 with dataset 2 on
this route (Fig. 16). Every reading given is driven on the same frames of each seed (one
run per seed and dataset, Albot₁ alone), and each path-integration update is split by
cause: no tracked surface left (the paper's case; with ``move_using_pi="as_written"`` also
every view of algorithm #4's loop that follows it) or tracked surfaces left whose
triangulation afforded no pose (none had an end usable to localise, or every affordance
was beyond the gate against path integration). Run::

    python -m albot2d.evaluation.paper.readings_counts --seeds 0-9 --workers 2 \\
        --readings default 'albot1[max_pi_deviation_m=inf,max_pi_deviation_deg=inf]' \\
        'albot1[max_endpoint_gap_m=inf]' paper_literal original
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from typing import Literal, TypedDict

import numpy as np

from albot2d.validation import parse_seed_list

__all__ = ["main", "path_integration_counts"]

_RUNS = {"dataset1": "fig16_dataset1", "dataset2": "fig16_dataset2"}

Quantity = Literal["pi", "no_tracked", "tracked_no_pose", "local_maps", "views"]
_QUANTITIES: tuple[Quantity, ...] = ("pi", "no_tracked", "tracked_no_pose", "local_maps", "views")


class _Row(TypedDict):
    """One reading's counts on one (run, seed), up to E7."""

    pi: int
    no_tracked: int
    tracked_no_pose: int
    local_maps: int
    views: int


class _Counted(TypedDict):
    """A worker's result (plain data, across the process pool)."""

    run: str
    seed: int
    rows: dict[str, _Row]


class QuantityStats(TypedDict):
    mean: float
    sd: float
    max: float
    per_seed: dict[str, int]


def _one(job: tuple[str, int, tuple[str, ...]]) -> _Counted:
    from albot2d.evaluation.paper.runs import run_job_readings

    run, seed, readings = job
    out = run_job_readings(run, seed, quick=False, albot_x=False, keep_figures=False,
                           readings=readings)  # fmt: skip
    rows: dict[str, _Row] = {}
    for reading, summary in out.items():
        causes = summary.path_integration_causes
        mark = summary.marks.get("E7")
        last = mark.frame if mark else max(causes.update_frames, default=0)
        tracked = [t for f, t in zip(causes.frames, causes.tracked, strict=True)
                   if f <= last]  # fmt: skip
        updates = sum(1 for f in causes.update_frames if f <= last)
        rows[reading] = {"pi": len(tracked), "no_tracked": tracked.count(0),
                         "tracked_no_pose": len(tracked) - tracked.count(0),
                         "local_maps": updates, "views": int(last) + 1}  # fmt: skip
    return {"run": run, "seed": seed, "rows": rows}


def path_integration_counts(
    seeds: Sequence[int], readings: Sequence[str], workers: int = 1
) -> dict[str, dict[str, dict[Quantity, QuantityStats]]]:
    """dataset → reading → {quantity: {"mean", "sd", "per_seed"}}."""
    from albot2d.evaluation.paper.campaign import check_readings

    readings = check_readings(readings)
    jobs = [(run, seed, readings) for run in _RUNS.values() for seed in seeds]
    if workers > 1:
        with ProcessPoolExecutor(max_workers=workers) as pool:
            results = list(pool.map(_one, jobs))
    else:
        results = [_one(j) for j in jobs]
    out: dict[str, dict[str, dict[Quantity, QuantityStats]]] = {}
    for dataset, run in _RUNS.items():
        mine = [r for r in results if r["run"] == run]
        out[dataset] = {}
        for reading in readings:
            table: dict[Quantity, QuantityStats] = {}
            for q in _QUANTITIES:
                values = np.array([r["rows"][reading][q] for r in mine], dtype=float)
                table[q] = {
                    "mean": float(values.mean()),
                    "sd": float(values.std(ddof=1)) if len(values) > 1 else 0.0,
                    "max": float(values.max()),
                    "per_seed": {str(r["seed"]): r["rows"][reading][q] for r in mine},
                }
            out[dataset][reading] = table  # fmt: skip
    return out


def main(argv: Sequence[str] | None = None) -> int:
    from albot2d.errors import InputError
    from albot2d.evaluation.paper.runs import DEFAULT_READINGS

    ap = argparse.ArgumentParser(prog="python -m albot2d.evaluation.paper.readings_counts",
                                 description=__doc__.split("\n\n")[0])  # fmt: skip
    ap.add_argument("--seeds", default="0-9", help="A-B (inclusive) or A,B,C")
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--readings", nargs="+", default=list(DEFAULT_READINGS))
    ap.add_argument("--json", action="store_true", help="print the numbers as JSON")
    args = ap.parse_args(argv)
    try:
        counts = path_integration_counts(parse_seed_list(args.seeds), args.readings, args.workers)
    except InputError as exc:
        print(f"readings_counts: {exc}")
        return 2
    if args.json:
        import json

        print(json.dumps(counts, indent=1))
        return 0
    print(f"path integrations up to E7 on Fig. 16's route, seeds {args.seeds} (paper: 5 / 7)")
    print(f"{'reading':<60} {'dataset 1':>22} {'dataset 2':>22}")
    for reading in args.readings:
        cells = []
        for dataset in _RUNS:
            t = counts[dataset][reading]
            pi, none = t["pi"], t["no_tracked"]
            cells.append(
                f"{pi['mean']:5.1f} ± {pi['sd']:4.1f} (max {pi['max']:3.0f}; "
                f"{none['mean']:.1f} none)"
            )
        print(f"{reading:<60} " + " ".join(f"{c:>22}" for c in cells))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
