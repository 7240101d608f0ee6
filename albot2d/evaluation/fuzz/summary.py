"""A campaign's summary: throughput, failures by invariant, metric distributions, the table.

``summarise(records, ...)`` turns the episode records of ``episodes.jsonl`` into
``summary.json``'s dict; ``format_summary`` prints it in a few lines. The mapper is
compared with raw odometry episode by episode: better, worse, or tied (equal to float
rounding, ``TIE_RTOL``/``TIE_ATOL``), never a tie counted as a win.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

__all__ = [
    "COMPARED_METRICS",
    "TIE_ATOL",
    "TIE_RTOL",
    "format_summary",
    "mapper_vs_odometry",
    "summarise",
]

# Metrics compared between the mapper and raw odometry: (mapper's, odometry's).
COMPARED_METRICS = {
    "heading_error_mean_deg": ("heading_error_mean_deg", "odometry_heading_error_mean_deg"),
    "heading_error_max_deg": ("heading_error_max_deg", "odometry_heading_error_max_deg"),
    "rpe_rot_deg": ("rpe_rot_deg", "odometry_rpe_rot_deg"),
    "rpe_trans_m": ("rpe_trans_m", "odometry_rpe_trans_m"),
    "end_rot_deg": ("end_rot_deg", "odometry_end_rot_deg"),
}
# A mapper and odometry are tied on an episode when their values agree to float rounding
# (a mapper that integrates odometry itself gets its values by other arithmetic): within
# 1e-9 relative, or 1e-9 absolute (deg or m) near zero.
TIE_RTOL = 1e-9
TIE_ATOL = 1e-9
_PERCENTILES = (10, 50, 90, 99)
# Failing episodes listed in the summary (the rest are in episodes.jsonl).
_LISTED_FAILURES = 50


def _distribution(values: Sequence[float]) -> dict[str, Any]:
    a = np.asarray(values, dtype=np.float64)
    if len(a) == 0:
        return {"n": 0}
    out: dict[str, Any] = {"n": len(a), "mean": float(a.mean()), "min": float(a.min())}
    for q, v in zip(_PERCENTILES, np.percentile(a, _PERCENTILES), strict=True):
        out[f"p{q}"] = float(v)
    out["max"] = float(a.max())
    return out


def _values(records: Sequence[Mapping[str, Any]], name: str) -> list[float]:
    return [
        float(r["metrics"][name])
        for r in records
        if isinstance(r.get("metrics", {}).get(name), int | float)
        and not isinstance(r["metrics"][name], bool)
    ]


def mapper_vs_odometry(records: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """For each of ``COMPARED_METRICS``: both means and the episodes where the mapper is
    better than raw odometry, worse, or tied (equal to float rounding)."""
    out = {}
    for label, (mine, odo) in COMPARED_METRICS.items():
        pairs = [
            (r["metrics"][mine], r["metrics"][odo])
            for r in records
            if r.get("metrics", {}).get(mine) is not None and r["metrics"].get(odo) is not None
        ]
        if not pairs:
            continue
        a = np.asarray(pairs, dtype=np.float64)
        tied = np.isclose(a[:, 0], a[:, 1], rtol=TIE_RTOL, atol=TIE_ATOL)
        better = ~tied & (a[:, 0] < a[:, 1])
        worse = ~tied & (a[:, 0] > a[:, 1])
        out[label] = {
            "episodes": len(a),
            "mapper_mean": float(a[:, 0].mean()),
            "odometry_mean": float(a[:, 1].mean()),
            "mapper_better": int(better.sum()),
            "mapper_worse": int(worse.sum()),
            "ties": int(tied.sum()),
            "mapper_better_share": float(better.mean()),
            "mapper_worse_share": float(worse.mean()),
            "tie_share": float(tied.mean()),
        }
    return out


def summarise(
    records: Sequence[Mapping[str, Any]],
    params: Mapping[str, Any],
    *,
    ran: int,
    wall_time_s: float,
    workers: int,
) -> dict[str, Any]:
    """summary.json: ``ran`` episodes took ``wall_time_s`` here; ``records`` are all of them."""
    status = Counter(r["status"] for r in records)
    by_invariant: Counter[str] = Counter()
    checked: Counter[str] = Counter()
    for r in records:
        by_invariant.update(r.get("violations", {}).keys())
        checked.update(r.get("checked", []))
    crashes = Counter(r["error"]["type"] for r in records if r["status"] == "crash")
    names = sorted({k for r in records for k in r.get("metrics", {})})
    failing = [
        {
            "episode": r["episode"],
            "status": r["status"],
            "kind": r.get("world", {}).get("kind"),
            "first": (
                r["error"]["message"]
                if r["status"] == "crash"
                else next(f"{k}: {v[0]}" for k, v in r["violations"].items())
            ),
        }
        for r in records
        if r["status"] != "ok"
    ]
    return {
        "format": "albot2d-campaign-summary",
        "params": dict(params),
        "episodes": len(records),
        "ok": status.get("ok", 0),
        "violations": status.get("violation", 0),
        "crashes": status.get("crash", 0),
        "failures_by_invariant": dict(sorted(by_invariant.items())),
        "checked_by_invariant": dict(sorted(checked.items())),
        "crashes_by_type": dict(sorted(crashes.items())),
        "kinds": dict(
            sorted(
                Counter(r.get("world", {}).get("kind") for r in records if r.get("world")).items()
            )
        ),
        "ran": ran,
        "workers": workers,
        "wall_time_s": wall_time_s,
        "episodes_per_min": 60.0 * ran / wall_time_s if ran and wall_time_s > 0 else None,
        "metrics": {name: _distribution(_values(records, name)) for name in names},
        "mapper_vs_odometry": mapper_vs_odometry(records),
        "failing_episodes": failing[:_LISTED_FAILURES],
    }


def _fmt(value: Any, spec: str) -> str:
    return "-" if value is None else format(value, spec)


def format_summary(summary: Mapping[str, Any]) -> str:
    """A few lines: counts, throughput, failures by invariant, key metrics."""
    lines = [
        f"{summary['episodes']} episodes: {summary['ok']} ok, {summary['violations']} with "
        f"violations, {summary['crashes']} crashes; ran {summary['ran']} here in "
        f"{summary['wall_time_s']:.1f} s on {summary['workers']} worker(s) "
        f"({_fmt(summary['episodes_per_min'], '.1f')} episodes/min)",
    ]
    if summary["failures_by_invariant"] or summary["crashes_by_type"]:
        parts = [f"{k} {v}" for k, v in summary["failures_by_invariant"].items()]
        parts += [f"crash {k} {v}" for k, v in summary["crashes_by_type"].items()]
        lines.append("failing: " + ", ".join(parts))
        for f in summary["failing_episodes"][:5]:
            lines.append(f"  episode {f['episode']} ({f['kind']}): {f['first'][:160]}")
    metrics = summary["metrics"]
    rows = [
        ("homing_bearing_error_max_deg", ".1f"),
        ("homing_distance_error_max_m", ".2f"),
        ("rpe_rot_deg", ".2f"),
        ("odometry_rpe_rot_deg", ".2f"),
        ("heading_error_max_deg", ".1f"),
        ("odometry_heading_error_max_deg", ".1f"),
    ]
    for name, spec in rows:
        d = metrics.get(name)
        if d and d["n"]:
            lines.append(
                f"  {name:32s} median {d['p50']:{spec}}  p90 {d['p90']:{spec}}  "
                f"max {d['max']:{spec}}  (n={d['n']})"
            )
    cmp = summary["mapper_vs_odometry"].get("heading_error_mean_deg")
    if cmp:
        lines.append(
            f"  mean heading error: mapper {cmp['mapper_mean']:.2f}° vs odometry "
            f"{cmp['odometry_mean']:.2f}° (of {cmp['episodes']} episodes mapper "
            f"better in {cmp['mapper_better']}, worse in {cmp['mapper_worse']}, "
            f"tied in {cmp['ties']})"
        )
    return "\n".join(lines)
