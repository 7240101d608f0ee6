"""Why Albot₁ places a local map by path integration, view by view, on Fig. 16's route.

The paper's Albot₁ integrated paths 5 times with dataset 1 and 7 with dataset 2 on its
route S → E7 (Fig. 16). This study drives that route (the ``fig16`` route of the ``fig6``
world, the experiments' ``pioneer3dx`` odometry) once per seed and dataset with one
reading of Albot₁, watches it through its public hooks only (``on_view``, ``on_localise``,
the per-view ``steps``), and gives every local map placed by path integration up to E7
one cause:

- ``no_trackable``: the view has no trackable surface at all (the paper's case: "when no
  trackable surfaces are in view, Albot₁ shifts to using path integration");
- ``lost_tracking``: the view has trackable surfaces, but RTSV recognised none of the
  tracked ones, so there is nothing to triangulate from;
- ``no_affordance``: surfaces were tracked, but none afforded a pose;
- ``pi_mode`` / ``pi_mode_exit``: a view inside algorithm #4's loop (fewer than four
  trackable surfaces) / the view that ends it (four or more), placed by path integration
  whatever it would have tracked.

For ``lost_tracking`` every tracked surface that was lost gets a reason, by looking in
the view for the same wall (direction within RTSV's 5°, within 0.2 m of the predicted
line, overlapping it): ``end_moved`` (the wall is there and trackable, but its real ends
lie 40 cm or more from where they were predicted), ``no_shared_end`` (no end real in both
observations), ``not_trackable`` (the wall is there but fails a tracking criterion now)
or ``out_of_view``. An ``end_moved`` loss records how far the end moved and the angle at
which the beam met the wall at that end in the earlier observation (a wall seen at a
grazing angle ends where the beams thin out, not at a corner).

The tracker is replayed from the views with the library's own ``start_tracking`` / ``rtsv``
and checked against the mapper's recorded counts (``StepRecord.tracked``) at every view.
Run::

    python -m albot2d.studies.path_integrations --seeds 5,7 --readings paper_literal
    python -m albot2d.studies.path_integrations --seeds 0-9 --json > pi.json
"""

from __future__ import annotations

import argparse
import dataclasses
import math
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from albot2d.errors import InputError
from albot2d.geometry import Pose
from albot2d.mapping.albot1.mapper import Albot1, Localisation
from albot2d.perception.surfaces import Surfaces
from albot2d.perception.tracking import (
    TrackedSurfaces,
    TrackingParams,
    recognise,
    rtsv,
    start_tracking,
    trackable_mask,
)
from albot2d.validation import parse_seed_list

__all__ = [
    "CAUSES",
    "DATASETS",
    "LOSSES",
    "PathIntegration",
    "PathIntegrationWatcher",
    "RouteBreakdown",
    "lost_reasons",
    "main",
    "route_breakdown",
]

CAUSES = ("no_trackable", "lost_tracking", "no_affordance", "pi_mode", "pi_mode_exit")
LOSSES = ("end_moved", "no_shared_end", "not_trackable", "out_of_view")
DATASETS = ("dataset1", "dataset2")
SAME_WALL_ANGLE_DEG = 5.0  # RTSV's own direction test
SAME_WALL_OFFSET_M = 0.2  # a wall 2.3 m across a corridor is never the "same" one
FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class Loss:
    """One tracked surface RTSV did not recognise: ``reason`` (``LOSSES``); for
    ``end_moved``, how far the nearest real end moved (m), the beam's incidence on the
    wall at that end in the earlier observation (degrees; 90 is head-on) and whether either
    end of the pair is a split point inside a run of hits (``split_end``: a beam shared with
    the next surface, which extraction counts as a real end) rather than the wall's last
    hit before a range jump."""

    reason: str
    end_moved_m: float = math.nan
    incidence_deg: float = math.nan
    split_end: bool = False


@dataclass(frozen=True, slots=True)
class PathIntegration:
    """A local map placed by path integration: its view, ``cause`` (``CAUSES``), the
    view's trackable surfaces, the surfaces tracked into it, the region kind there and,
    for ``lost_tracking``, why each tracked surface was lost."""

    frame: int
    cause: str
    trackable: int
    tracked_before: int
    region: str
    losses: tuple[Loss, ...] = ()


@dataclass(frozen=True, slots=True)
class RouteBreakdown:
    """Every path integration of one reading on one run, up to E7; and how sparse the
    route's views are: ``no_trackable_views`` have no trackable surface, and the longest
    run of consecutive views with fewer than ``min_tracked`` (four) trackable surfaces
    (what ends algorithm #4's loop) is ``longest_sparse_run`` views long."""

    seed: int
    dataset: str
    reading: str
    views: int
    local_maps: int
    path_integrations: tuple[PathIntegration, ...] = field(default_factory=tuple)
    no_trackable_views: int = 0
    longest_sparse_run: int = 0

    def causes(self) -> dict[str, int]:
        counts = Counter(p.cause for p in self.path_integrations)
        return {c: counts.get(c, 0) for c in CAUSES}

    def losses(self) -> dict[str, int]:
        counts = Counter(loss.reason for p in self.path_integrations for loss in p.losses)
        return {r: counts.get(r, 0) for r in LOSSES}

    def to_dict(self) -> dict[str, Any]:
        moved = [x.end_moved_m for p in self.path_integrations for x in p.losses
                 if x.reason == "end_moved"]  # fmt: skip
        incidence = [x.incidence_deg for p in self.path_integrations for x in p.losses
                     if x.reason == "end_moved"]  # fmt: skip
        return {
            "seed": self.seed, "dataset": self.dataset, "reading": self.reading,
            "views": self.views, "local_maps": self.local_maps,
            "no_trackable_views": self.no_trackable_views,
            "longest_sparse_run": self.longest_sparse_run,
            "path_integrations": len(self.path_integrations),
            "causes": self.causes(), "losses": self.losses(),
            "regions": dict(Counter(p.region for p in self.path_integrations)),
            "end_moved_median_m": float(np.median(moved)) if moved else None,
            "end_moved_at_split": sum(x.split_end for p in self.path_integrations
                                      for x in p.losses if x.reason == "end_moved"),
            "end_incidence_median_deg": float(np.median(incidence)) if incidence else None,
            "frames": [p.frame for p in self.path_integrations],
        }  # fmt: skip


def _incidence_deg(surface: FloatArray, end: int) -> float:
    """The angle at which the beam from the robot (origin) meets the surface at ``end``."""
    p = surface[2 * end : 2 * end + 2]
    d = surface[2:4] - surface[0:2]
    cross = abs(p[0] * d[1] - p[1] * d[0])
    return math.degrees(math.asin(min(1.0, cross / (math.hypot(*p) * math.hypot(*d) + 1e-12))))


def _split_ends(surfaces: Surfaces) -> NDArray[np.bool_]:
    """``(N, 2)``: the end's beam is shared with another surface of the same view (a split
    point inside a run of hits)."""
    beams = np.asarray(surfaces.beams)
    counts = Counter(beams.ravel().tolist())
    return np.array([[counts[int(b)] > 1 for b in row] for row in beams], bool).reshape(-1, 2)


def lost_reasons(
    predicted: Surfaces,
    view: Surfaces,
    params: TrackingParams,
    earlier: Surfaces | None = None,
) -> tuple[Loss, ...]:
    """Why each of ``predicted`` (tracked surfaces moved into ``view``'s frame, none of
    which RTSV recognised) was lost; see the module docstring. ``earlier``: the whole view
    ``predicted`` was observed in (to tell split points; default: ``predicted`` itself)."""
    trackable = trackable_mask(view, params)
    view_split = _split_ends(view)
    earlier_split = _split_ends(earlier if earlier is not None else predicted)
    earlier_beams = np.asarray((earlier if earlier is not None else predicted).beams)
    out: list[Loss] = []
    v = view.segments
    v_dir = np.arctan2(v[:, 3] - v[:, 1], v[:, 2] - v[:, 0])
    for k in range(len(predicted)):
        p = predicted.segments[k]
        d = p[2:4] - p[0:2]
        length = math.hypot(*d)
        u = d / max(length, 1e-12)
        n = np.array([-u[1], u[0]])
        gap = np.abs(np.angle(np.exp(2j * (v_dir - math.atan2(d[1], d[0]))))) / 2
        mid = 0.5 * (v[:, :2] + v[:, 2:])
        offset = np.abs((mid - p[0:2]) @ n)
        s0, s1 = (v[:, :2] - p[0:2]) @ u, (v[:, 2:] - p[0:2]) @ u
        overlap = (np.maximum(s0, s1) > 0.0) & (np.minimum(s0, s1) < length)
        same = (gap < math.radians(SAME_WALL_ANGLE_DEG)) & (offset < SAME_WALL_OFFSET_M) & overlap
        if not same.any():
            out.append(Loss("out_of_view"))
            continue
        if not (same & trackable).any():
            out.append(Loss("not_trackable"))
            continue
        best: tuple[float, float, bool] = (math.inf, math.nan, False)
        for j in np.flatnonzero(same & trackable):
            for end in (0, 1):  # corresponding ends (scan order), real in both
                if predicted.occluded[k, end] or view.occluded[j, end]:
                    continue
                moved = math.hypot(*(p[2 * end : 2 * end + 2] - v[j, 2 * end : 2 * end + 2]))
                if moved < best[0]:
                    row = np.flatnonzero((earlier_beams == predicted.beams[k]).all(axis=1))
                    split = bool(view_split[j, end]) or (
                        len(row) > 0 and bool(earlier_split[row[0], end])
                    )
                    best = (moved, _incidence_deg(p, end), split)
        if math.isinf(best[0]):
            out.append(Loss("no_shared_end"))
        else:
            out.append(Loss("end_moved", *best))
    return tuple(out)


class PathIntegrationWatcher:
    """Watches an ``Albot1`` through its hooks (``on_view``, ``on_localise``; attach before
    the first view), replays its tracker from the views it is given, and gives each local
    map it places by path integration a cause (``breakdown``)."""

    def __init__(self, mapper: Albot1) -> None:
        self.m = mapper
        self.params = mapper.params.tracking
        self.state: TrackedSurfaces | None = None
        self.views: dict[int, tuple[Surfaces, Pose]] = {}
        self.trackable: dict[int, int] = {}
        self.replayed: dict[int, int] = {}  # frame → |RTSV| against the tracked set in force
        self.tracked_before: dict[int, int] = {}
        self.losses: dict[int, tuple[Loss, ...]] = {}
        self.no_affordance: set[int] = set()
        self.prev_frame: int | None = None
        mapper.on_view = self._on_view
        mapper.on_localise = self._on_localise
        self._localising: int | None = None

    def _settle(self) -> None:
        """Bring the replayed tracker up to date with the mapper's record of the last view."""
        if self.prev_frame is None:
            return
        step = self.m.steps[-1]
        frame = step.frame_index
        view, inc = self.views[frame]
        if step.remembered and step.remembered[-1] == frame:
            self.state = start_tracking(view, self.params)
        elif step.remembered:  # V(c-1) remembered, V(c) re-tracked from it (≥ 4 kept)
            before, _ = self.views[step.remembered[-1]]
            self.state, _ = rtsv(start_tracking(before, self.params), view, inc, self.params)
        else:
            assert self.state is not None
            self.state, _ = rtsv(self.state, view, inc, self.params)

    def _on_view(self, frame: int, view: Surfaces, increment: Pose) -> None:
        self._settle()
        self.views[frame] = (view, increment)
        self.trackable[frame] = int(np.count_nonzero(trackable_mask(view, self.params)))
        self._localising = frame
        if self.state is not None:
            info = recognise(self.state.current, view, increment, self.params)
            self.replayed[frame] = len(info)
            self.tracked_before[frame] = len(self.state)
            if not len(info) and len(self.state) and self.trackable[frame]:
                earlier = self.views[self.prev_frame][0] if self.prev_frame is not None else None
                self.losses[frame] = lost_reasons(info.predicted, view, self.params, earlier)
        self.prev_frame = frame

    def _on_localise(self, loc: Localisation) -> None:
        if loc.method == "path_integration" and len(loc.tracked):
            assert self._localising is not None
            self.no_affordance.add(self._localising)

    def breakdown(self, last_frame: int | None = None) -> list[PathIntegration]:
        """Every local map placed by path integration up to ``last_frame`` (default: all),
        with its cause (``region`` left empty). Raises ``RuntimeError`` if the replayed
        tracker disagrees with the mapper's recorded counts at any view."""
        self._settle()
        m = self.m
        inside = _pi_mode_views(m, self.trackable, self.replayed)
        for step in m.steps:
            f = step.frame_index
            if f in self.replayed and f not in inside and step.tracked != self.replayed[f]:
                raise RuntimeError(
                    f"view {f}: the mapper tracked {step.tracked} surfaces, the replay "
                    f"{self.replayed[f]}"
                )
        need = m.params.min_tracked
        out: list[PathIntegration] = []
        for lm in m.route:
            f = lm.frame_index
            if lm.method != "path_integration" or (last_frame is not None and f > last_frame):
                continue
            if f in inside:
                cause = "pi_mode_exit" if self.trackable[f] >= need else "pi_mode"
            elif f in self.no_affordance:
                cause = "no_affordance"
            elif self.trackable[f] == 0:
                cause = "no_trackable"
            else:
                cause = "lost_tracking"
            losses = self.losses.get(f, ()) if cause == "lost_tracking" else ()
            out.append(PathIntegration(f, cause, self.trackable[f],
                                       self.tracked_before.get(f, 0), "", losses))  # fmt: skip
        return out


def _pi_mode_views(m: Albot1, trackable: dict[int, int], replayed: dict[int, int]) -> set[int]:
    """The views inside algorithm #4's loop, by the mapper's own rule
    (``Albot1Params.move_using_pi``)."""
    rule, need = m.params.move_using_pi, m.params.min_tracked
    pis = {lm.frame_index for lm in m.route if lm.method == "path_integration"}
    inside: set[int] = set()
    mode = False
    for step in m.steps:
        f = step.frame_index
        if mode:
            inside.add(f)
            mode = trackable[f] < need
            continue
        if step.remembered and step.remembered[-1] == f and f in pis:
            mode = (rule == "as_written" and trackable[f] == 0) or (
                rule == "on_lost_tracking" and replayed.get(f, 0) == 0
            )
    return inside


def route_breakdown(
    seed: int, dataset: str, reading: str = "paper_literal", laser_noise: str = "sick_lms200"
) -> RouteBreakdown:
    """Drive Fig. 16's route on ``seed`` with ``dataset`` and Albot₁ under ``reading``
    (a name of ``paper.runs.READINGS`` or an ``albot1[...]`` spec); every path integration
    up to E7 with its cause. ``laser_noise``: a ``sim.laser.LASER_NOISE_PRESETS`` name (the
    experiments use ``sick_lms200``; ``zero`` tells what the laser's noise contributes)."""
    from albot2d.evaluation.metrics.updates import region_labels
    from albot2d.evaluation.paper.runs import PAPER_NOISE, reading_spec
    from albot2d.evaluation.run.experiment import RunSpec, run_experiment
    from worldgen.routes import waypoint_arclength_m

    if dataset not in DATASETS:
        raise InputError(f"dataset must be one of {', '.join(DATASETS)}, got {dataset!r}")
    spec_name = reading_spec(reading)
    state: dict[str, Any] = {"travelled": 0.0, "last": None, "e7_frame": None, "truth": {}}

    def on_start(world: Any, _tour: Any) -> None:
        state["e7"] = waypoint_arclength_m(world, "fig16")["E7"][0]

    def on_mappers(made: Any) -> None:
        mapper = made[spec_name]
        if not isinstance(mapper, Albot1):
            raise InputError(f"reading {reading!r} is not an Albot1 mapper")
        state["watcher"] = PathIntegrationWatcher(mapper)

    def on_frame(frame: Any, _travelled: float) -> None:
        pose = frame.true_pose.as_array()
        if state["last"] is not None:
            state["travelled"] += math.hypot(*(pose[:2] - state["last"][:2]))
        state["last"] = pose
        state["truth"][frame.index] = pose[:2]
        if state["e7_frame"] is None and state["travelled"] >= state["e7"] - 0.05:
            state["e7_frame"] = frame.index

    spec = RunSpec(seed=seed, kind="fig6", world_params={}, profile=dataset, noise=PAPER_NOISE,
                   tour_kind="loop", tour_length_m=100.0, route="fig16",
                   laser_noise=laser_noise, mappers=(spec_name,))  # fmt: skip
    result = run_experiment(spec, on_start=on_start, on_frame=on_frame, on_mappers=on_mappers,
                            score=False)  # fmt: skip
    w: PathIntegrationWatcher = state["watcher"]
    m = w.m
    last = state["e7_frame"] if state["e7_frame"] is not None else m.steps[-1].frame_index
    rows = w.breakdown(last)
    xy = np.array([state["truth"][p.frame] for p in rows]).reshape(-1, 2)
    regions: Any = region_labels(result.world, xy) if rows else []
    out = [dataclasses.replace(p, region=str(r)) for p, r in zip(rows, regions, strict=True)]
    maps = sum(1 for lm in m.route if lm.frame_index <= last)
    counts = [n for f, n in sorted(w.trackable.items()) if f <= last]
    longest = run = 0
    for n in counts:
        run = run + 1 if n < m.params.min_tracked else 0
        longest = max(longest, run)
    return RouteBreakdown(seed, dataset, reading, last + 1, maps, tuple(out),
                          counts.count(0), longest)  # fmt: skip


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m albot2d.studies.path_integrations",
                                 description=(__doc__ or "").split("\n\n")[0])  # fmt: skip
    ap.add_argument("--seeds", default="5,7", help="A-B (inclusive) or A,B,C")
    ap.add_argument("--datasets", nargs="+", default=list(DATASETS), choices=DATASETS)
    ap.add_argument("--readings", nargs="+", default=["paper_literal"])
    ap.add_argument("--laser-noise", default="sick_lms200",
                    help="laser noise preset: sick_lms200 (the experiments'), zero or "
                         "sick_lms200_any_jump (the former mixed-pixel model)")  # fmt: skip
    ap.add_argument("--json", action="store_true", help="print every route's breakdown as JSON")
    args = ap.parse_args(argv)
    rows: list[dict[str, Any]] = []
    try:
        for reading in args.readings:
            for dataset in args.datasets:
                for seed in parse_seed_list(args.seeds):
                    rows.append(route_breakdown(seed, dataset, reading, args.laser_noise).to_dict())
                    if not args.json:
                        _print_row(rows[-1])
    except InputError as exc:
        print(f"path_integrations: {exc}")
        return 2
    if args.json:
        import json

        print(json.dumps(rows, indent=1))
    return 0


def _print_row(r: dict[str, Any]) -> None:
    causes = " ".join(f"{k}={v}" for k, v in r["causes"].items() if v)
    losses = " ".join(f"{k}={v}" for k, v in r["losses"].items() if v)
    moved = r["end_moved_median_m"]
    extra = (
        ""
        if moved is None
        else (
            f"; ends moved median {moved:.2f} m at {r['end_incidence_median_deg']:.0f}° incidence"
        )
    )
    print(
        f"{r['reading']} {r['dataset']} seed {r['seed']}: {r['views']} views, "
        f"{r['local_maps']} local maps, {r['path_integrations']} path integrations "
        f"[{causes or '-'}] lost surfaces [{losses or '-'}]{extra}; "
        f"{r['no_trackable_views']} views with no trackable surface, longest run with < 4: "
        f"{r['longest_sparse_run']} views"
    )


if __name__ == "__main__":
    raise SystemExit(main())
