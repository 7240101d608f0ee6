"""Start–stop homing sensitivity to odometry noise, and moves per update by region.

``homing_sensitivity(seeds, presets)`` drives every (seed, odometry preset) pair — by
default start–stop on a ``circuit`` tour of an office world, as the paper's Table 1 and
Fig. 14 were — once each way round the circuit (``directions``: the paper's Table 1 pools
a clockwise and an anticlockwise journey, Fig. 8), runs every mapper of ``mappers`` on the
same frames (default Albot1 as ``albot2d run`` makes it, Albot1 with the start–stop
reading ``albot1[preset=start_stop]``, and naive odometry) and returns, per preset and
mapper, how many homing stops hold the paper's Table 1 bound (bearing within
±``bearing_bound_deg`` *and* distance within ±``distance_bound_m``), over two sets of
stops, reported side by side and never mixed:

- ``all``: every homing stop (every 20 odometer metres and the last view) of the whole
  circuit (≥ ``tour_length_m``);
- ``table1``: the stops whose true straight-line distance from the start lies within
  ``table1_range_m`` (17–35 m: where the paper's Table 1 stops were).

It also gives each view-based mapper's instructions / moves per global-map update by
region kind (``albot2d.evaluation.metrics.updates``; the paper's Fig. 14), pooled over the runs.

Runs are independent, so ``workers > 1`` spreads them over a process pool; results are
collected in (preset, seed, direction) order, so they do not depend on the number of
workers. ``PAPER_FIG8`` (``--paper-fig8``) is the paper's own Table 1 setting instead: the
Fig. 6 world and its Fig. 8 clockwise and anticlockwise journeys, a stop every 4 m. Rerun
it after any mapper change, e.g.::

    python -m albot2d.studies.sensitivity --seeds 20 --workers 2
    python -m albot2d.studies.sensitivity --seeds 20 --paper-fig8 --presets pioneer3dx
"""

from __future__ import annotations

import argparse
import dataclasses
from collections.abc import Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from albot2d.errors import InputError
from albot2d.evaluation.metrics.updates import (
    albot1_update_flags,
    region_labels,
    summarise_counts,
    update_counts,
)

__all__ = ["PAPER_FIG8", "SensitivitySetup", "format_table", "homing_sensitivity", "run_one"]

DEFAULT_PRESETS = ("pioneer3dx", "low", "typical", "high")
DEFAULT_MAPPERS = ("albot1", "albot1[preset=start_stop]", "naive")
DIRECTIONS = ("forward", "reverse")
# The paper's Table 1 setting: the Fig. 6 world, its Fig. 8 journeys, a stop every 4 m.
PAPER_FIG8: dict[str, Any] = {
    "kind": "fig6",
    "routes": ("fig8_clockwise", "fig8_anticlockwise"),
    "stop_every_m": 4.0,
}


@dataclass(frozen=True)
class SensitivitySetup:
    """What every run shares: world kind (and generator parameters), driving profile,
    tour, directions driven, mappers, the homing bound and the Table 1 distance window.

    ``routes``: instead of a planned tour driven each way round, drive each of these routes
    named by the world (e.g. ``PAPER_FIG8``: the paper's Fig. 8 clockwise and anticlockwise
    journeys in the ``fig6`` world); ``stop_every_m``: odometer metres between homing stops.
    """

    kind: str = "office"
    world_params: dict[str, Any] = field(default_factory=dict)
    profile: str = "start_stop"
    tour_kind: str = "circuit"
    tour_length_m: float = 100.0
    directions: tuple[str, ...] = DIRECTIONS
    mappers: tuple[str, ...] = DEFAULT_MAPPERS
    bearing_bound_deg: float = 7.0
    distance_bound_m: float = 3.0
    table1_range_m: tuple[float, float] = (17.0, 35.0)
    routes: tuple[str, ...] = ()
    stop_every_m: float = 20.0

    def __post_init__(self) -> None:
        if not self.stop_every_m > 0.0:
            raise InputError(
                f"SensitivitySetup.stop_every_m must be > 0, got {self.stop_every_m!r}"
            )
        bad = [d for d in self.directions if d not in DIRECTIONS]
        if not self.directions or bad:
            raise InputError(
                f"SensitivitySetup.directions: give some of {', '.join(DIRECTIONS)}, "
                f"got {list(self.directions)!r}"
            )
        if not self.mappers:
            raise InputError("SensitivitySetup.mappers: give at least one mapper")
        lo, hi = self.table1_range_m
        if not 0.0 <= lo <= hi:
            raise InputError(
                f"SensitivitySetup.table1_range_m must be (low, high) with 0 <= low <= high, "
                f"got {self.table1_range_m!r}"
            )


def run_one(
    seed: int, preset: str, setup: SensitivitySetup, direction: str = "forward"
) -> dict[str, Any]:
    """One run: per mapper, the homing errors per stop (bearing °, distance m, true
    straight-line distance from the start m) and the update counts per region kind."""
    from albot2d.evaluation.run.scoring import homing_section
    from albot2d.evaluation.run.setup import RunSpec, build_world, make_simulator
    from albot2d.evaluation.run.trace import HomingParams, drive_mappers
    from albot2d.mapping.registry import resolve_mappers
    from albot2d.sim.driving import get_profile
    from worldgen import plan_tour

    journeys = setup.routes or DIRECTIONS
    if direction not in journeys:
        raise InputError(f"run_one: direction must be one of {', '.join(journeys)}")
    spec = RunSpec(
        seed=seed, kind=setup.kind, world_params=setup.world_params, profile=setup.profile,
        noise=preset, tour_kind=setup.tour_kind, tour_length_m=setup.tour_length_m,
        tour_length_is_minimum=True, mappers=setup.mappers,
    )  # fmt: skip
    factories = resolve_mappers(list(spec.mappers))
    world = build_world(spec)
    if setup.routes:
        from worldgen.routes import route_start, route_tour

        tour = route_tour(world, direction)
        world = dataclasses.replace(world, start=route_start(world, direction))
    else:
        tour = plan_tour(world, kind=spec.tour_kind, length_m=spec.tour_length_m,
                          at_least=spec.tour_length_is_minimum)  # fmt: skip
    if direction == "reverse":
        # A circuit starts and ends at the start: driven backwards it is the other way round.
        tour = dataclasses.replace(tour, waypoints=tour.waypoints[::-1].copy())
    frames = make_simulator(world, spec).drive(tour, get_profile(spec.profile))
    mappers = {name: factory() for name, factory in factories.items()}
    trace = drive_mappers(frames, mappers, homing=HomingParams(stop_every_m=setup.stop_every_m))
    assert trace.true_poses is not None  # simulated runs always have the truth
    xy = trace.true_poses[:, :2]
    out: dict[str, Any] = {}
    for name, mapper in trace.mappers.items():
        stops = [
            (float(h.bearing_error_deg), float(h.distance_error_m), float(h.distance_true_m))
            for h in (stop.homing for stop in homing_section(trace, name))
            if h.bearing_error_deg is not None and h.distance_error_m is not None
            and h.distance_true_m is not None
        ]  # fmt: skip
        instructions: dict[str, list[int]] = {}
        moves: dict[str, list[int]] = {}
        steps = getattr(mapper, "steps", None)
        if isinstance(steps, list):
            flags = albot1_update_flags(steps, trace.frame_indices)
            labels = np.full(len(xy), "", dtype="<U8")  # only update rows are read
            labels[flags] = region_labels(world, xy[flags])
            instructions, moves = update_counts(xy, flags, labels)
        out[name] = {"stops": stops, "instructions": instructions, "moves": moves}
    return {
        "seed": seed,
        "preset": preset,
        "direction": direction,
        "frames": trace.n_frames,
        "tour_m": float(tour.length_m),
        "mappers": out,
    }


def _share(stops: list[tuple[float, float, float]], setup: SensitivitySetup) -> dict[str, Any]:
    within = [
        abs(b) <= setup.bearing_bound_deg and abs(d) <= setup.distance_bound_m for b, d, _ in stops
    ]
    return {
        "stops": len(stops),
        "within_bound": int(sum(within)),
        "fraction_within_bound": float(sum(within) / len(stops)) if stops else None,
        "worst_bearing_error_deg": max((abs(b) for b, _, _ in stops), default=None),
        "worst_distance_error_m": max((abs(d) for _, d, _ in stops), default=None),
    }


def _summarise(runs: list[dict[str, Any]], name: str, setup: SensitivitySetup) -> dict[str, Any]:
    lo, hi = setup.table1_range_m
    stops = [s for run in runs for s in run["mappers"][name]["stops"]]
    instructions: dict[str, list[int]] = {}
    moves: dict[str, list[int]] = {}
    for run in runs:
        for kind, counts in run["mappers"][name]["instructions"].items():
            instructions.setdefault(kind, []).extend(counts)
        for kind, counts in run["mappers"][name]["moves"].items():
            moves.setdefault(kind, []).extend(counts)
    return {
        "runs": len(runs),
        "frames": sum(run["frames"] for run in runs),
        "all": _share(stops, setup),
        "table1": _share([s for s in stops if lo <= s[2] <= hi], setup),
        "updates_by_region": summarise_counts(instructions, moves) if instructions else {},
    }


def homing_sensitivity(
    seeds: Iterable[int],
    presets: Sequence[str] = DEFAULT_PRESETS,
    setup: SensitivitySetup | None = None,
    *,
    workers: int = 1,
) -> dict[str, Any]:
    """``{"setup": {...}, "presets": {preset: {mapper: summary}}, "runs": [per-run
    records]}``; see the module docstring."""
    setup = setup or SensitivitySetup()
    seeds = [int(s) for s in seeds]
    if not seeds or not presets:
        raise InputError("homing_sensitivity: give at least one seed and one preset")
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise InputError(f"homing_sensitivity: workers must be a positive integer, got {workers!r}")
    journeys = setup.routes or setup.directions
    jobs = [(seed, preset, d) for preset in presets for seed in seeds for d in journeys]
    if workers == 1:
        runs = [run_one(seed, preset, setup, d) for seed, preset, d in jobs]
    else:
        with ProcessPoolExecutor(max_workers=workers) as pool:
            futures = [pool.submit(run_one, seed, preset, setup, d) for seed, preset, d in jobs]
            runs = [f.result() for f in futures]
    summary = {
        p: {
            name: _summarise([r for r in runs if r["preset"] == p], name, setup)
            for name in setup.mappers
        }
        for p in presets
    }
    return {
        "setup": {**dataclasses.asdict(setup), "seeds": seeds},
        "presets": summary,
        "runs": runs,
    }


def _cell(share: dict[str, Any]) -> str:
    if share["fraction_within_bound"] is None:
        return "- of 0"
    return f"{100 * share['fraction_within_bound']:.0f}% of {share['stops']}"


def format_table(result: dict[str, Any]) -> str:
    """The sensitivity table as text: per preset and mapper the share of all stops and of
    the Table 1 stops within the bound, the worst errors, then moves per update."""
    s = result["setup"]
    lo, hi = s["table1_range_m"]
    tour = "routes" if s["routes"] else f"{s['tour_kind']} ≥{s['tour_length_m']:g} m"
    lines = [
        f"{s['kind']} {s['profile']} {tour}, stops every {s['stop_every_m']:g} m, "
        f"{len(s['seeds'])} seeds × {'/'.join(s['routes'] or s['directions'])}; bound ±"
        f"{s['bearing_bound_deg']:g}° and ±{s['distance_bound_m']:g} m; "
        f"Table 1 stops: {lo:g}–{hi:g} m from the start",
        f"{'preset':<11} {'mapper':<26} {'all stops':>12} {'Table 1 stops':>14} "
        f"{'worst °':>8} {'worst m':>8}",
    ]
    for preset, by_mapper in result["presets"].items():
        for name, p in by_mapper.items():
            a = p["all"]
            worst_b = (
                "-"
                if a["worst_bearing_error_deg"] is None
                else (f"{a['worst_bearing_error_deg']:.1f}")
            )
            worst_d = (
                "-"
                if a["worst_distance_error_m"] is None
                else (f"{a['worst_distance_error_m']:.2f}")
            )
            lines.append(
                f"{preset:<11} {name:<26} {_cell(a):>12} {_cell(p['table1']):>14} "
                f"{worst_b:>8} {worst_d:>8}"
            )
    lines.append("instructions (moves) per update, mean [share ≤2 / ≥2], by region:")
    for preset, by_mapper in result["presets"].items():
        for name, p in by_mapper.items():
            parts = []
            for kind, u in p["updates_by_region"].items():
                ins, mv = u["instructions_per_update"], u["moves_per_update"]
                parts.append(
                    f"{kind} n={u['updates']} {ins['mean']:.2f} ({mv['mean']:.2f}) "
                    f"[{ins['share_at_most_2']:.2f}/{ins['share_at_least_2']:.2f}]"
                )
            if parts:
                lines.append(f"  {preset:<11} {name:<26} " + "; ".join(parts))
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> None:
    """``python -m albot2d.studies.sensitivity``: print the table (and optionally save
    the full result as JSON)."""
    import json

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20, help="seeds 0..N-1 (default 20)")
    ap.add_argument("--presets", nargs="+", default=list(DEFAULT_PRESETS))
    ap.add_argument("--mappers", nargs="+", default=list(DEFAULT_MAPPERS))
    ap.add_argument("--directions", nargs="+", default=list(DIRECTIONS))
    ap.add_argument(
        "--paper-fig8",
        action="store_true",
        help="the paper's Table 1 setting: Fig. 6 world, Fig. 8 journeys",
    )
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--json", metavar="FILE", help="also write the full result here")
    args = ap.parse_args(argv)
    if args.seeds < 1:
        ap.error(f"--seeds must be a positive integer, got {args.seeds}")
    try:
        extra = PAPER_FIG8 if args.paper_fig8 else {}
        setup = SensitivitySetup(
            mappers=tuple(args.mappers), directions=tuple(args.directions), **extra
        )
        result = homing_sensitivity(
            range(args.seeds), tuple(args.presets), setup, workers=args.workers
        )
    except InputError as exc:
        ap.exit(2, f"albot2d.studies.sensitivity: {exc}\n")
    print(format_table(result))
    if args.json:
        with open(args.json, "w", encoding="utf-8") as fh:
            json.dump(result, fh, indent=1)


if __name__ == "__main__":
    main()
