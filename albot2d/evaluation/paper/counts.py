"""``counts``: views and local maps per dataset and route, and path integrations.

The paper: dataset 1, S → E5: 795 views → 307 local maps; dataset 3, the whole route:
217 → 133; the non-corridor route: 153 → 103; path integrations 5 (dataset 1) vs 7
(dataset 2) on S → E7 (Fig. 16). Ours are counted at the same places on the same routes
(E5 for dataset 1, the end for the others; E7 for the path integrations of Fig. 16).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import cast

from albot2d.evaluation.paper.jobs import FigureRun, JobSummary, MarkCounts
from albot2d.evaluation.paper.outputs import ExperimentOutput, FigureSpec, OverSeeds
from albot2d.evaluation.paper.stats import over_seeds, verdict_of

__all__ = ["CLAIM", "NAME", "RUNS", "compute", "figures"]

NAME = "counts"
CLAIM = (
    "Albot₁ remembers only some views (dataset 1: 795 views → 307 local maps; dataset 3: "
    "217 → 133; non-corridor route: 153 → 103) and uses path integration more often "
    "when odometry is worse (dataset 2: 7 times vs 5)."
)
RUNS = ("fig6_dataset1", "fig6_dataset2", "fig6_dataset3", "fig6_start_stop", "fig11_open")
# dataset -> (run, mark at which it is counted, paper views, paper local maps, paper PI)
_DATASETS = {
    "dataset1": ("fig6_dataset1", "E5", 795, 307, 5),
    "dataset2": ("fig6_dataset2", "E7", None, None, 7),
    "dataset3": ("fig6_dataset3", "end", 217, 133, None),
    "start_stop": ("fig6_start_stop", "end", None, None, None),
    "non_corridor": ("fig11_open", "end", 153, 103, None),
}
RATIO_TOLERANCE = 0.25  # the issue: update-count ratios within ±25 % of the paper's
_PI_MARK = "E7"  # Fig. 16's route ends at E7


def _counts_at(job: JobSummary, mark: str) -> MarkCounts | None:
    return job.counts_at(mark)


def compute(jobs: Mapping[str, Sequence[JobSummary]], seeds: Sequence[int]) -> ExperimentOutput:
    ours: dict[str, object] = {}
    paper: dict[str, object] = {}
    pi_per_seed: dict[str, dict[str, float | None]] = {}
    checks = []
    for dataset, (run, mark, p_views, p_maps, p_pi) in _DATASETS.items():
        rows = [_counts_at(j, mark) for j in jobs[run]]
        pi_rows = [
            _counts_at(
                j,
                _PI_MARK
                if run.startswith("fig6_dataset") and dataset in ("dataset1", "dataset2")
                else mark,
            )
            for j in jobs[run]
        ]
        views = [None if r is None else r.views for r in rows]
        maps = [None if r is None else r.local_maps for r in rows]
        ratio = [None if r is None or not r.views else r.local_maps / r.views for r in rows]
        ratio_stats = over_seeds(ratio, seeds)
        pis = over_seeds([None if r is None else r.path_integrations for r in pi_rows], seeds)
        pi_per_seed[dataset] = pis["per_seed"]
        mine: dict[str, object] = {
            "counted_at": mark,
            "views": over_seeds(views, seeds),
            "local_maps": over_seeds(maps, seeds),
            "local_maps_per_view": ratio_stats,
            "path_integrations": pis,
            "path_integrations_counted_at": _PI_MARK if dataset in ("dataset1", "dataset2")
            else mark,
        }  # fmt: skip
        ours[dataset] = mine
        entry: dict[str, object] = {}
        if p_views is not None and p_maps is not None:
            entry |= {
                "views": p_views,
                "local_maps": p_maps,
                "local_maps_per_view": p_maps / p_views,
            }
        if p_pi is not None:
            entry["path_integrations"] = p_pi
        paper[dataset] = entry
        mean_ratio = ratio_stats["mean"]
        if p_views is not None and p_maps is not None and mean_ratio is not None:
            target = p_maps / p_views
            ok = abs(mean_ratio / target - 1.0) <= RATIO_TOLERANCE
            mine["ratio_within_25pct"] = ok
            checks.append(ok)
    d1, d2 = pi_per_seed["dataset1"], pi_per_seed["dataset2"]
    more = [b > a for s, a in d1.items() if a is not None and (b := d2.get(s)) is not None]
    share = sum(more) / len(more) if more else None
    ours["path_integrations_more_with_dataset2_share"] = share
    checks.append(share is not None and share > 0.5)
    causes = {
        d: _pi_causes(jobs[run], _PI_MARK, seeds)
        for d, run in (("dataset1", "fig6_dataset1"), ("dataset2", "fig6_dataset2"))
    }
    ours["path_integration_causes"] = causes
    same = [_path_at(a) is not None and _path_at(a) == _path_at(b)
            for a, b in zip(jobs["fig6_dataset1"], jobs["fig6_dataset2"], strict=True)]  # fmt: skip
    same_share = sum(same) / len(same) if same else None
    ours["same_true_path_datasets_1_and_2_share"] = same_share
    spec = next((j.reading_mapper for j in jobs["fig6_dataset1"]), None) or "albot1"
    reason = _pi_reason(causes, share, same_share, spec)
    return {
        "claim": CLAIM, "paper": paper, "ours": ours, "verdict": verdict_of(checks),
        "notes": [reason] if reason else [],
        "rule": "reproduced when the local-maps-per-view ratio is within ±25 % of the "
                "paper's for dataset 1, dataset 3 and the non-corridor route, and dataset 2 "
                "needs more path integrations than dataset 1 on most seeds; partly when "
                "some of these hold",
    }  # fmt: skip


def _path_at(job: JobSummary) -> str | None:
    """The digest of the true path up to Fig. 16's end (if the run got there)."""
    snap = job.marks.get(_PI_MARK)
    return None if snap is None else snap.true_path_sha256


def _pi_causes(rows: Sequence[JobSummary], mark: str, seeds: Sequence[int]) -> dict[str, OverSeeds]:
    """Why Albot₁ used path integration up to ``mark``: per seed, the path-integration
    updates with no tracked surface left vs with some left (the triangulation afforded no
    pose within its gates), those at the end of a turn, by region kind, and the runs of
    consecutive path-integration updates (a coarser count: one per stretch)."""
    keys = ("total", "no_tracked_surface", "tracked_but_no_pose", "after_a_turn",
            "in_corridor", "in_hall", "in_room", "runs", "updates")  # fmt: skip
    per: dict[str, list[float | None]] = {k: [] for k in keys}
    for j in rows:
        c = j.path_integration_causes
        snap = j.marks.get(mark)
        if snap is None:
            for k in keys:
                per[k].append(None)
            continue
        last = snap.frame
        pick = [k for k, f in enumerate(c.frames) if f <= last]
        tracked = [c.tracked[k] for k in pick]
        regions = [c.regions[k] for k in pick]
        methods = [m for f, m in zip(c.update_frames, c.update_methods, strict=True)
                   if f <= last]  # fmt: skip
        runs = sum(1 for k, m in enumerate(methods)
                   if m == "path_integration" and (k == 0 or methods[k - 1] != m))  # fmt: skip
        values = (len(pick), tracked.count(0), sum(1 for t in tracked if t > 0),
                  sum(1 for k in pick if c.turning[k]), regions.count("corridor"),
                  regions.count("hall"), regions.count("room"), runs, len(methods))  # fmt: skip
        for k, v in zip(keys, values, strict=True):
            per[k].append(v)
    return {k: over_seeds(v, seeds) for k, v in per.items()}


def _gate_text(spec: str) -> tuple[str, str]:
    """How the reading ``spec`` treats affordances far from path integration, and what
    follows a view with no tracked surface (built from its parameters)."""
    import math

    from albot2d.mapping.registry import mapper_factory

    params = mapper_factory(spec)().params  # type: ignore[attr-defined]
    t, tri = params.tracking, params.triangulation
    gate_m = t.match_distance_m if tri.max_pi_deviation_m is None else tri.max_pi_deviation_m
    gate_deg = t.match_angle_deg if tri.max_pi_deviation_deg is None else tri.max_pi_deviation_deg
    if math.isinf(gate_m) and math.isinf(gate_deg):
        gate = "no gate against path integration"
    else:
        gate = (f"affordances farther than {gate_m:g} m / {gate_deg:g}° per step from the "
                "path-integration pose are dropped")  # fmt: skip
    gate += f"; positions from position_endpoint={tri.position_endpoint}"
    if params.move_using_pi == "as_written":
        after = ("algorithm #4 as written: after a view with no trackable surface, every view "
                 "is remembered by path integration until one has more than three trackable "
                 "surfaces; after one with trackable surfaces but none tracked, tracking "
                 "resumes from it")  # fmt: skip
    elif params.move_using_pi == "on_lost_tracking":
        after = ("after a view with no tracked surface, every view is remembered by path "
                 "integration until one has more than three trackable surfaces")  # fmt: skip
    else:
        after = "after a view with no tracked surface, tracking resumes from it"
    return gate, after


def _pi_reason(
    causes: Mapping[str, Mapping[str, OverSeeds]],
    share: float | None,
    same: float | None,
    spec: str = "albot1",
) -> str | None:
    """One sentence with the numbers, built from them (not written by hand); ``share``:
    of the seeds, those with more path integrations with dataset 2; ``same``: those on
    which both datasets drove the same true path."""
    c1, c2 = causes["dataset1"], causes["dataset2"]
    m = {d: {k: v["mean"] for k, v in c.items()} for d, c in causes.items()}
    if m["dataset1"]["total"] is None or m["dataset2"]["total"] is None:
        return None
    # every mean is known when the totals are (they count the same seeds)
    t1 = {k: float(v or 0.0) for k, v in m["dataset1"].items()}
    t2 = {k: float(v or 0.0) for k, v in m["dataset2"].items()}
    from albot2d.mapping.albot1.mapper import Albot1Params
    from albot2d.sim.driving import get_profile

    gate = Albot1Params().tracking
    gate_text, after_text = _gate_text(spec)
    d2 = get_profile("dataset2")

    def pct(a: float | None, b: float | None) -> str:
        return "–" if not a or b is None else f"{100.0 * b / a:.0f} %"

    n1 = c1["no_tracked_surface"]["per_seed"]
    n2 = c2["no_tracked_surface"]["per_seed"]
    pairs = [(a, b) for k, a in n1.items() if a is not None and (b := n2.get(k)) is not None]
    more_none = sum(b > a for a, b in pairs)
    return (
        f"Up to {_PI_MARK}, Albot₁ placed {t1['total']:.0f} ± {c1['total']['sd']:.0f} local "
        f"maps by path integration with dataset 1 and {t2['total']:.0f} ± "
        f"{c2['total']['sd']:.0f} with dataset 2 (of {t1['updates']:.0f} / "
        f"{t2['updates']:.0f} updates). With dataset 1, "
        f"{pct(t1['total'], t1['no_tracked_surface'])} had no tracked surface left (the "
        f"paper's case) and {pct(t1['total'], t1['tracked_but_no_pose'])} had some but the "
        f"triangulation afforded no pose ({spec}: {gate_text}; {after_text}); "
        f"{pct(t1['total'], t1['after_a_turn'])} came "
        f"at the end of a turn step and {pct(t1['total'], t1['in_corridor'])} in corridors. "
        f"Counting only those with no tracked surface left gives "
        f"{t1['no_tracked_surface']:.1f} / {t2['no_tracked_surface']:.1f} (the paper: 5 / 7),"
        f" more with dataset 2 on {more_none} of {len(pairs)} seeds; counted as stretches "
        f"of consecutive path-integration updates they are {t1['runs']:.0f} / "
        f"{t2['runs']:.0f}. The true path to {_PI_MARK} (hence every scan) is the same with "
        f"both datasets on {'–' if same is None else f'{100.0 * same:.0f} %'} of seeds; "
        f"dataset 2 only adds {d2.induced_step_m:g} m / {d2.induced_step_deg:g}° to each "
        f"odometry step, inside RTSV's match gates ({gate.match_distance_m:g} m / "
        f"{gate.match_angle_deg:g}° per step); the count moves by "
        f"{t2['total'] - t1['total']:+.1f} on average"
        + ("" if share is None else f" (more with dataset 2 on {100.0 * share:.0f} % of seeds)")
        + "."
    )


def figures(fig: Mapping[str, FigureRun], result: ExperimentOutput) -> list[FigureSpec]:
    """Local maps per view, ours (mean ± sd over seeds) beside the paper's."""
    bars = []
    for dataset, ours in result["ours"].items():
        if not isinstance(ours, dict) or "local_maps_per_view" not in ours:
            continue
        r: OverSeeds = ours["local_maps_per_view"]
        paper = cast("Mapping[str, float]", result["paper"][dataset])  # as compute wrote it
        bars.append(
            {
                "label": dataset,
                "ours": r["mean"],
                "sd": r["sd"],
                "paper": paper.get("local_maps_per_view"),
            }
        )
    return [
        {
            "file": "counts.png",
            "plot": "bars",
            "caption": "Local maps remembered per view, per dataset (ours: bar the mean "
            "over the seeds, whisker ± sd; "
            "paper: hatched).",
            "data": {"bars": bars, "ylabel": "local maps per view"},
        }
    ]
