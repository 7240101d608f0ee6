"""Start–stop homing sensitivity to odometry noise, and moves per update by region.

``homing_sensitivity(seeds, presets)`` runs the main experiment (``run_experiment``) with
Albot1 alone for every (seed, odometry preset) pair — by default start–stop driving on a
``circuit`` tour of an office world, as the paper's Table 1 and Fig. 14 were — and
returns, per preset, how many homing stops hold the paper's Table 1 bound (bearing within
±``bearing_bound_deg`` *and* distance within ±``distance_bound_m``), the worst errors,
and Albot1's instructions / moves per global-map update by region kind
(``albot2d.evaluation.updates``), pooled over the seeds.

Runs are independent, so ``workers > 1`` spreads them over a process pool; results are
collected in (preset, seed) order, so they do not depend on the number of workers.
Rerun it after any mapper change, e.g.::

    from albot2d.evaluation.sensitivity import homing_sensitivity, format_table
    result = homing_sensitivity(range(20), ("pioneer3dx", "low", "typical", "high"))
    print(format_table(result))
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from albot2d.errors import InputError
from albot2d.evaluation.updates import (
    albot1_update_flags,
    region_labels,
    summarise_counts,
    update_counts,
)

__all__ = ["SensitivitySetup", "format_table", "homing_sensitivity", "run_one"]

DEFAULT_PRESETS = ("pioneer3dx", "low", "typical", "high")


@dataclass(frozen=True)
class SensitivitySetup:
    """What every run shares: world kind (and generator parameters), driving profile,
    tour, and the homing bound."""

    kind: str = "office"
    world_params: dict[str, Any] = field(default_factory=dict)
    profile: str = "start_stop"
    tour_kind: str = "circuit"
    tour_length_m: float = 100.0
    bearing_bound_deg: float = 7.0
    distance_bound_m: float = 3.0


def run_one(seed: int, preset: str, setup: SensitivitySetup) -> dict[str, Any]:
    """One run: its homing errors per stop and Albot1's update counts per region kind."""
    from albot2d.evaluation.experiment import RunSpec, run_experiment
    from albot2d.mapping import Albot1

    spec = RunSpec(
        seed=seed,
        kind=setup.kind,
        world_params=setup.world_params,
        profile=setup.profile,
        noise=preset,
        tour_kind=setup.tour_kind,
        tour_length_m=setup.tour_length_m,
        mappers=("albot1",),
    )
    result = run_experiment(spec)
    stops = []
    for stop in result.scores.mappers["albot1"].homing:
        h = stop.homing
        assert h.bearing_error_deg is not None and h.distance_error_m is not None  # simulated
        stops.append((h.bearing_error_deg, h.distance_error_m))
    trace = result.trace
    assert trace.true_poses is not None  # simulated runs always have the truth
    albot1_mapper = trace.mappers["albot1"]
    assert isinstance(albot1_mapper, Albot1)  # the run's spec names the albot1 mapper
    flags = albot1_update_flags(albot1_mapper.steps, trace.frame_indices)
    xy = trace.true_poses[:, :2]
    labels = np.full(len(xy), "", dtype="<U8")  # only update rows are read
    labels[flags] = region_labels(result.world, xy[flags])
    instructions, moves = update_counts(xy, flags, labels)
    return {
        "seed": seed,
        "preset": preset,
        "frames": trace.n_frames,
        "tour_m": float(result.tour.length_m) if result.tour is not None else 0.0,
        "stops": stops,
        "instructions": instructions,
        "moves": moves,
    }


def _summarise(runs: list[dict[str, Any]], setup: SensitivitySetup) -> dict[str, Any]:
    stops = [s for run in runs for s in run["stops"]]
    within = [
        abs(b) <= setup.bearing_bound_deg and abs(d) <= setup.distance_bound_m for b, d in stops
    ]
    instructions: dict[str, list[int]] = {}
    moves: dict[str, list[int]] = {}
    for run in runs:
        for kind, counts in run["instructions"].items():
            instructions.setdefault(kind, []).extend(counts)
        for kind, counts in run["moves"].items():
            moves.setdefault(kind, []).extend(counts)
    return {
        "runs": len(runs),
        "frames": sum(run["frames"] for run in runs),
        "stops": len(stops),
        "within_bound": int(sum(within)),
        "fraction_within_bound": float(sum(within) / len(stops)) if stops else None,
        "worst_bearing_error_deg": max((abs(b) for b, _ in stops), default=None),
        "worst_distance_error_m": max((abs(d) for _, d in stops), default=None),
        "updates_by_region": summarise_counts(instructions, moves),
    }


def homing_sensitivity(
    seeds: Iterable[int],
    presets: Sequence[str] = DEFAULT_PRESETS,
    setup: SensitivitySetup | None = None,
    *,
    workers: int = 1,
) -> dict[str, Any]:
    """``{"setup": {...}, "presets": {preset: summary}, "runs": [per-run records]}``;
    see the module docstring."""
    setup = setup or SensitivitySetup()
    seeds = [int(s) for s in seeds]
    if not seeds or not presets:
        raise InputError("homing_sensitivity: give at least one seed and one preset")
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise InputError(f"homing_sensitivity: workers must be a positive integer, got {workers!r}")
    jobs = [(seed, preset) for preset in presets for seed in seeds]
    if workers == 1:
        runs = [run_one(seed, preset, setup) for seed, preset in jobs]
    else:
        with ProcessPoolExecutor(max_workers=workers) as pool:
            futures = [pool.submit(run_one, seed, preset, setup) for seed, preset in jobs]
            runs = [f.result() for f in futures]
    return {
        "setup": {**setup.__dict__, "world_params": dict(setup.world_params), "seeds": seeds},
        "presets": {p: _summarise([r for r in runs if r["preset"] == p], setup) for p in presets},
        "runs": runs,
    }


def format_table(result: dict[str, Any]) -> str:
    """The sensitivity table as text: one line per preset, then moves per update."""
    s = result["setup"]
    lines = [
        f"{s['kind']} {s['profile']} {s['tour_kind']} ≥{s['tour_length_m']:g} m, "
        f"{len(s['seeds'])} seeds; bound ±{s['bearing_bound_deg']:g}° and "
        f"±{s['distance_bound_m']:g} m",
        f"{'preset':<11} {'stops':>5} {'within':>6} {'share':>6} {'worst °':>8} {'worst m':>8}",
    ]
    for name, p in result["presets"].items():
        share = "-" if p["fraction_within_bound"] is None else f"{p['fraction_within_bound']:.2f}"
        worst_b = (
            "-" if p["worst_bearing_error_deg"] is None else (f"{p['worst_bearing_error_deg']:.1f}")
        )
        worst_d = (
            "-" if p["worst_distance_error_m"] is None else (f"{p['worst_distance_error_m']:.2f}")
        )
        lines.append(
            f"{name:<11} {p['stops']:>5} {p['within_bound']:>6} {share:>6} "
            f"{worst_b:>8} {worst_d:>8}"
        )
    lines.append("instructions (moves) per update, mean [share ≤2 / ≥2], by region:")
    for name, p in result["presets"].items():
        parts = []
        for kind, u in p["updates_by_region"].items():
            ins, mv = u["instructions_per_update"], u["moves_per_update"]
            parts.append(
                f"{kind} n={u['updates']} {ins['mean']:.2f} ({mv['mean']:.2f}) "
                f"[{ins['share_at_most_2']:.2f}/{ins['share_at_least_2']:.2f}]"
            )
        lines.append(f"  {name:<11} " + "; ".join(parts))
    return "\n".join(lines)
