"""A campaign's summary: throughput, failures by invariant, metric distributions, the table.

``summarise(records, ...)`` turns the episode records of ``episodes.jsonl`` into
``summary.json``'s dict; ``format_summary`` prints it in a few lines. The mapper is
compared with raw odometry episode by episode: better, worse, or tied (equal to float
rounding, ``TIE_RTOL``/``TIE_ATOL``), never a tie counted as a win.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping, Sequence
from typing import TypedDict

import numpy as np

from albot2d.evaluation.fuzz.record import EpisodeRecord, Json, JsonObject

__all__ = [
    "COMPARED_METRICS",
    "TIE_ATOL",
    "TIE_RTOL",
    "CampaignSummary",
    "Comparison",
    "Distribution",
    "FailingEpisode",
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
# Failing episodes listed in the summary (the rest are in episodes.jsonl).
_LISTED_FAILURES = 50


class Distribution(TypedDict, total=False):
    """A metric over the episodes that have it (only ``n`` when none has)."""

    n: int
    mean: float
    min: float
    p10: float
    p50: float
    p90: float
    p99: float
    max: float


class Comparison(TypedDict):
    """The mapper against raw odometry on one metric, episode by episode."""

    episodes: int
    mapper_mean: float
    odometry_mean: float
    mapper_better: int
    mapper_worse: int
    ties: int
    mapper_better_share: float
    mapper_worse_share: float
    tie_share: float


class FailingEpisode(TypedDict):
    episode: int
    status: str
    kind: str | None
    first: str


class CampaignSummary(TypedDict):
    """summary.json (a JSON document, so a dict: its metric names are the records')."""

    format: str
    params: JsonObject
    episodes: int
    ok: int
    violations: int
    crashes: int
    failures_by_invariant: dict[str, int]
    checked_by_invariant: dict[str, int]
    crashes_by_type: dict[str, int]
    kinds: dict[str, int]
    ran: int
    workers: int
    wall_time_s: float
    episodes_per_min: float | None
    metrics: dict[str, Distribution]
    mapper_vs_odometry: dict[str, Comparison]
    failing_episodes: list[FailingEpisode]


def _distribution(values: Sequence[float]) -> Distribution:
    a = np.asarray(values, dtype=np.float64)
    if len(a) == 0:
        return {"n": 0}
    p10, p50, p90, p99 = (float(v) for v in np.percentile(a, (10, 50, 90, 99)))
    return {
        "n": len(a), "mean": float(a.mean()), "min": float(a.min()),
        "p10": p10, "p50": p50, "p90": p90, "p99": p99, "max": float(a.max()),
    }  # fmt: skip


def _number(value: Json) -> float | None:
    return None if isinstance(value, bool) or not isinstance(value, int | float) else value


def _values(metrics: Sequence[Mapping[str, Json]], name: str) -> list[float]:
    return [float(v) for m in metrics if (v := _number(m.get(name))) is not None]


def mapper_vs_odometry(
    records: Sequence[EpisodeRecord | Mapping[str, Json]],
) -> dict[str, Comparison]:
    """For each of ``COMPARED_METRICS``: both means and the episodes where the mapper is
    better than raw odometry, worse, or tied (equal to float rounding). ``records`` are
    typed or as episodes.jsonl has them (the figures read them from the file)."""
    return _compare([_metrics_of(r) for r in records])


def _metrics_of(record: EpisodeRecord | Mapping[str, Json]) -> Mapping[str, Json]:
    if isinstance(record, EpisodeRecord):
        return record.metrics_json()
    metrics = record.get("metrics")
    return metrics if isinstance(metrics, dict) else {}


def _compare(metrics: Sequence[Mapping[str, Json]]) -> dict[str, Comparison]:
    out: dict[str, Comparison] = {}
    for label, (mine, odo) in COMPARED_METRICS.items():
        pairs = [
            (m[mine], m[odo]) for m in metrics if m.get(mine) is not None and m.get(odo) is not None
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


def _first_failure(r: EpisodeRecord) -> str:
    if r.status == "crash":
        assert r.error is not None  # a crash record has its error (files.check_episode_record)
        return r.error.message
    return next(f"{k}: {v[0]}" for k, v in r.violations.items())


def summarise(
    records: Sequence[EpisodeRecord],
    params: JsonObject,
    *,
    ran: int,
    wall_time_s: float,
    workers: int,
) -> CampaignSummary:
    """summary.json: ``ran`` episodes took ``wall_time_s`` here; ``records`` are all of them."""
    status = Counter(r.status for r in records)
    by_invariant: Counter[str] = Counter()
    checked: Counter[str] = Counter()
    for r in records:
        by_invariant.update(r.violations.keys())
        checked.update(r.checked)
    crashes = Counter(r.error.type for r in records if r.status == "crash" and r.error)
    metrics = [r.metrics_json() for r in records]
    names = sorted({k for m in metrics for k in m})
    failing: list[FailingEpisode] = [
        {"episode": r.episode, "status": r.status, "kind": r.kind, "first": _first_failure(r)}
        for r in records
        if r.failed
    ]
    kinds = Counter(r.kind for r in records if r.kind is not None)
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
        "kinds": dict(sorted(kinds.items())),
        "ran": ran,
        "workers": workers,
        "wall_time_s": wall_time_s,
        "episodes_per_min": 60.0 * ran / wall_time_s if ran and wall_time_s > 0 else None,
        "metrics": {name: _distribution(_values(metrics, name)) for name in names},
        "mapper_vs_odometry": _compare(metrics),
        "failing_episodes": failing[:_LISTED_FAILURES],
    }


def _fmt(value: float | None, spec: str) -> str:
    return "-" if value is None else format(value, spec)


def format_summary(summary: CampaignSummary) -> str:
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
