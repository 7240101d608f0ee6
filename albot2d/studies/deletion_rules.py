"""The global map's deletion rules side by side: one run's local maps re-added under each.

Owns the "Measured" table of docs/albot1.md's section "The global map's deletion rule
(algorithm #5)". One run (``RunSpec``, by default the default ``albot2d run``: office seed
0, dataset 1, ``typical`` noise, the default loop tour) is driven through Albot₁ (its
defaults, or ``--albot1 'albot1[KEY=VALUE,…]'``); its route map keeps every remembered
local map (the view's surfaces, the pose Albot₁ gave it) and the run's frames give each its
true pose. The local maps are
then re-added, in order, into a fresh ``GlobalMap`` under each rule of ``RULES`` (the
presets of ``GlobalMapParams.preset``, ``visible`` with lower ``min_visible_share`` or
either seen side, and ``no deletion``: ``GlobalMap.insert``, which adds a view deleting
nothing, the ceiling), once at Albot₁'s poses and once at the true poses. At Albot₁'s poses
each rule's transience is counted too (``Transience``: surfaces kept, revisiting updates
as report.json counts them, time per update).

At each of the run's own homing stops every re-added map is scored exactly as the run
scores Albot₁'s map there (``scoring.egocentric_at`` on the stop's seen window, the map
as it was after the local maps remembered by then, relative to Albot₁'s pose estimate
there, or to the true pose for the true-pose maps). Albot₁'s localisation never reads its
global map, so its poses, and the stops, are the same under any rule.

Faithfulness is checked, not assumed: re-added under Albot₁'s own rule at its own poses,
the map must equal the mapper's global map (same surfaces, same ids, bit for bit) at every
stop and at the end, with the same scores and revisits (``RuntimeError`` otherwise).

Run from the command line (see ``--help``)::

    python -m albot2d.studies.deletion_rules                        # the default run
    python -m albot2d.studies.deletion_rules --min-tour-length 100  # the 283 m tour
    python -m albot2d.studies.deletion_rules --max-frames 600 --json out.json
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal, NoReturn

import numpy as np
from numpy.typing import NDArray

from albot2d.errors import InputError
from albot2d.evaluation.metrics.egocentric import EgocentricQuality, in_robot_frame
from albot2d.evaluation.run.experiment import run_experiment
from albot2d.evaluation.run.scoring import REVISIT_GAP_MAPS, egocentric_at, revisits_section
from albot2d.evaluation.run.setup import RunSpec
from albot2d.evaluation.run.trace import Stop, Trace
from albot2d.frames import Frame
from albot2d.geometry import Pose
from albot2d.mapping.albot1.global_map import GlobalMap, GlobalMapParams, MapSnapshot, UpdateReport
from albot2d.mapping.albot1.mapper import Albot1
from albot2d.mapping.protocol import Mapper
from albot2d.perception.surfaces import transform_segments_fast

__all__ = [
    "POSES",
    "RULES",
    "DeletionStudy",
    "RecordedRun",
    "RememberedMap",
    "Rule",
    "RuleRow",
    "StopScore",
    "Transience",
    "check_faithful",
    "deletion_study",
    "format_table",
    "main",
    "readd",
    "record_run",
    "rule_scores",
    "transience",
]

FloatArray = NDArray[np.float64]
Poses = Literal["albot1", "true"]
POSES: tuple[Poses, ...] = ("albot1", "true")


@dataclass(frozen=True, slots=True)
class Rule:
    """A row of the table: its name, the global map's parameters (``None``: no deletion,
    every view added with ``GlobalMap.insert``) and its label in the markdown table."""

    name: str
    params: GlobalMapParams | None
    label: str


_VISIBLE = GlobalMapParams.preset("visible")
RULES: tuple[Rule, ...] = (
    Rule("no deletion", None, "no deletion (ceiling)"),
    Rule("visible", _VISIBLE, "**`visible`** (default)"),
    Rule("visible, min_visible_share=0.5", dataclasses.replace(_VISIBLE, min_visible_share=0.5),
         "`visible`, `min_visible_share=0.5`"),
    Rule("visible, min_visible_share=0", dataclasses.replace(_VISIBLE, min_visible_share=0.0),
         "`visible`, `min_visible_share=0` (any point)"),
    Rule("visible, seen_side=any", dataclasses.replace(_VISIBLE, seen_side="any"),
         '`visible`, `seen_side="any"`'),
    Rule("paper", GlobalMapParams.preset("paper"), "`paper`"),
    Rule("original", GlobalMapParams.preset("original"), "`original`"),
    Rule("v1", GlobalMapParams.preset("v1"), "`v1`"),
)  # fmt: skip


@dataclass(frozen=True, slots=True)
class RememberedMap:
    """One local map as Albot₁ remembered it: its view's surfaces (in the view's frame), the
    pose Albot₁ gave it (in the first local map's frame) and the true pose of its frame."""

    map_id: int
    frame_index: int
    segments: FloatArray
    pose: Pose
    true_pose: Pose


@dataclass(frozen=True, eq=False)
class RecordedRun:
    """A driven run: its trace (homing stops with their seen windows kept unscored), the
    mapper, its remembered local maps, how many it had remembered after each trace row,
    and the true walls."""

    spec: RunSpec
    trace: Trace
    mapper: Albot1
    name: str
    maps: tuple[RememberedMap, ...]
    remembered_after_row: NDArray[np.int64]
    walls: FloatArray

    def stops(self) -> list[Stop]:
        """The run's homing stops, and its end when that is not one of them."""
        stops = list(self.trace.stops)
        final = self.trace.final
        if final is not None and (not stops or stops[-1].row != final.row):
            stops.append(final)
        return stops


def record_run(spec: RunSpec, albot1: str = "albot1") -> RecordedRun:
    """Drive ``spec`` through one Albot₁ alone (``albot1``: ``"albot1"``, its defaults, or
    ``"albot1[KEY=VALUE,…]"``; the spec's own mappers are replaced) and keep what re-adding
    its local maps needs: the run's stops are captured unscored (``score=False``), so each
    keeps its seen window and Albot₁'s pose estimate there."""
    if albot1 != "albot1" and not albot1.startswith("albot1["):
        raise InputError(f"--albot1: give albot1 or albot1[KEY=VALUE,...], got {albot1!r}")
    spec = dataclasses.replace(spec, mappers=(albot1,))
    got: dict[str, Mapper] = {}
    remembered: list[int] = []

    def capture(mappers: Mapping[str, Mapper]) -> None:
        got.update(mappers)

    def count(frame: Frame, travelled_m: float) -> None:
        remembered.append(len(mapper_of(got, albot1).route))

    result = run_experiment(spec, score=False, on_mappers=capture, on_frame=count)
    mapper = mapper_of(got, albot1)
    truth = result.trace.true_poses
    if truth is None or result.world is None:
        raise RuntimeError("a simulated run has its true poses and world")
    row_of = {int(f): r for r, f in enumerate(result.trace.frame_indices)}
    maps = tuple(
        RememberedMap(lm.map_id, lm.frame_index, lm.view.segments, lm.pose,
                      Pose.from_array(truth[row_of[lm.frame_index]]))
        for lm in mapper.route
    )  # fmt: skip
    return RecordedRun(
        spec, result.trace, mapper, albot1, maps, np.array(remembered, np.int64),
        np.asarray(result.world.obstacle_segments, np.float64),
    )  # fmt: skip


def mapper_of(mappers: Mapping[str, Mapper], name: str) -> Albot1:
    mapper = mappers.get(name)
    if not isinstance(mapper, Albot1):
        raise RuntimeError(f"the run's {name!r} mapper is not Albot1: {mapper!r}")
    return mapper


def readd(
    maps: Sequence[RememberedMap],
    params: GlobalMapParams | None,
    poses: Poses,
    on_update: Callable[[UpdateReport], None] | None = None,
) -> GlobalMap:
    """A fresh global map with ``maps`` added in order, each at Albot₁'s pose or its true
    pose, under the rule ``params`` (``None``: every view inserted, nothing deleted);
    ``on_update`` gets each update's report (not with ``None``).

    The views are placed as Albot₁ places them (``transform_segments_fast``), so under
    Albot₁'s own rule at its own poses the result is its global map bit for bit."""
    if poses not in POSES:
        raise InputError(f"poses must be one of {', '.join(POSES)}, got {poses!r}")
    gm = GlobalMap(params if params is not None else GlobalMapParams())
    for m in maps:
        pose = m.pose if poses == "albot1" else m.true_pose
        segs = transform_segments_fast(pose, m.segments)
        if params is None:
            gm.insert(segs, m.map_id)
        else:
            report = gm.add_view(segs, m.map_id, pose)
            if on_update is not None:
                on_update(report)
    return gm


def _robot_pose(run: RecordedRun, stop: Stop, poses: Poses) -> FloatArray:
    if poses == "albot1":
        return stop.estimates[run.name][0]
    assert run.trace.true_poses is not None  # RecordedRun: a simulated run
    return run.trace.true_poses[stop.row]


def _score(
    run: RecordedRun, stop: Stop, snapshot: MapSnapshot, pose: FloatArray
) -> EgocentricQuality:
    """``snapshot`` scored at ``stop`` as the run scores its mappers there: the map near
    the robot relative to ``pose`` (the reach ``drive_mappers`` takes), then
    ``egocentric_at``."""
    if stop.seen is None:
        raise RuntimeError(f"stop at row {stop.row} kept no seen window")
    reach = float(np.max(np.hypot(stop.seen[:, 0], stop.seen[:, 1]), initial=0.0)) + 1.0
    local = in_robot_frame(pose, snapshot.segments, reach)
    scored = Stop(stop.row, stop.travelled_m, stop.estimates, stop.seen,
                  {"rule": (local, len(snapshot.segments))})  # fmt: skip
    quality = egocentric_at(run.trace, scored, "rule", run.walls)
    if quality is None:
        raise RuntimeError(f"stop at row {stop.row}: no egocentric score")
    return quality


@dataclass(frozen=True, slots=True)
class StopScore:
    """One map's egocentric quality at one stop (``None``: nothing to score)."""

    travelled_m: float
    completeness: float | None
    accuracy_m_p95: float | None
    surfaces: int


def rule_scores(
    run: RecordedRun, params: GlobalMapParams | None, poses: Poses, gm: GlobalMap | None = None
) -> tuple[StopScore, ...]:
    """Each stop's egocentric quality of the run's local maps re-added under ``params``
    (``gm``: that map, when already re-added)."""
    gm = readd(run.maps, params, poses) if gm is None else gm
    out = []
    for stop in run.stops():
        snap = gm.snapshot(at_update=int(run.remembered_after_row[stop.row]))
        q = _score(run, stop, snap, _robot_pose(run, stop, poses))
        out.append(StopScore(stop.travelled_m, q.completeness, q.accuracy_m_p95, q.surfaces))
    return tuple(out)


@dataclass(frozen=True, slots=True)
class Transience:
    """How transient a re-added map is (paper Fig. 10): surfaces added and kept at the end,
    the revisiting updates (a view touching a map more than ``REVISIT_GAP_MAPS`` maps back,
    as report.json's ``mappers.NAME.revisits`` counts them) and what they deleted, and the
    mean wall time of an update (re-adding, this process, whatever else the machine ran)."""

    added: int
    kept: int
    revisit_updates: int
    revisit_deleted: int
    ms_per_update: float


def transience(
    run: RecordedRun, params: GlobalMapParams | None, poses: Poses = "albot1"
) -> tuple[GlobalMap, Transience]:
    """The run's local maps re-added under ``params`` and how transient that map is."""
    revisits = [0, 0]

    def count(report: UpdateReport) -> None:
        oldest = min(report.affected_maps, default=-1)
        if oldest >= 0 and report.map_id - oldest > REVISIT_GAP_MAPS:
            revisits[0] += 1
            revisits[1] += report.deleted_current + report.deleted_older

    t0 = time.perf_counter()
    gm = readd(run.maps, params, poses, count)
    ms = 1e3 * (time.perf_counter() - t0) / max(len(run.maps), 1)
    added = sum(len(m.segments) for m in run.maps)
    return gm, Transience(added, len(gm), revisits[0], revisits[1], ms)


def check_faithful(run: RecordedRun) -> int:
    """Re-add the run's local maps under Albot₁'s own rule at its own poses and check the
    map equals Albot₁'s global map at every stop and at the end, with the run's own scores
    there; returns the number of surfaces compared. ``RuntimeError`` on any difference."""
    mapper = run.mapper
    gm, mine_t = transience(run, mapper.params.global_map)
    if gm.n_updates != mapper.map.n_updates:
        raise RuntimeError(f"re-added {gm.n_updates} updates, Albot₁ made {mapper.map.n_updates}")
    compared = 0
    for stop in run.stops():
        update = int(run.remembered_after_row[stop.row])
        mine, its = gm.snapshot(at_update=update), mapper.global_map(at_update=update)
        _same(mine, its, f"after update {update} (stop at {stop.travelled_m:.1f} m)")
        compared += len(its.segments)
        again = _score(run, stop, mine, _robot_pose(run, stop, "albot1"))
        own = egocentric_at(run.trace, stop, run.name, run.walls)
        if again != own:
            raise RuntimeError(f"stop at {stop.travelled_m:.1f} m: re-added map scores "
                               f"{again}, the run's own {own}")  # fmt: skip
    _same(gm.snapshot(), mapper.global_map(), "at the end")
    own_revisits = revisits_section(mapper, REVISIT_GAP_MAPS)
    if own_revisits is None or (mine_t.revisit_updates, mine_t.revisit_deleted) != (
        own_revisits.updates,
        own_revisits.deleted_surfaces,
    ):
        raise RuntimeError(f"re-added revisits {mine_t}, Albot₁'s own {own_revisits}")
    return compared + len(gm)


def _same(mine: MapSnapshot, its: MapSnapshot, where: str) -> None:
    if not (
        np.array_equal(mine.segments, its.segments) and np.array_equal(mine.map_ids, its.map_ids)
    ):
        raise RuntimeError(
            f"re-added map differs from Albot₁'s {where}: {len(mine.segments)} surfaces "
            f"vs {len(its.segments)}"
        )


@dataclass(frozen=True, slots=True)
class RuleRow:
    """One rule's scores at every stop, at Albot₁'s poses and at the true poses."""

    rule: str
    label: str
    albot1: tuple[StopScore, ...]
    true: tuple[StopScore, ...]
    transience: Transience  # at Albot₁'s poses


@dataclass(frozen=True, slots=True)
class DeletionStudy:
    """The table: the run, its stops (odometer metres) and one row per rule."""

    spec: dict[str, Any]
    frames: int
    travelled_m: float
    local_maps: int
    stops_m: tuple[float, ...]
    rows: tuple[RuleRow, ...]
    faithful_surfaces: int
    cpu_s: float

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)


def deletion_study(
    spec: RunSpec,
    rules: Sequence[Rule] = RULES,
    *,
    albot1: str = "albot1",
    on_rule: Callable[[str], None] | None = None,
) -> DeletionStudy:
    """Record ``spec``'s run through ``albot1`` (``record_run``), check re-adding is
    faithful, and score every rule at every stop both ways (``on_rule(name)`` before each
    rule: progress)."""
    t0 = time.process_time()
    run = record_run(spec, albot1)
    faithful = check_faithful(run)
    rows = []
    for rule in rules:
        if on_rule is not None:
            on_rule(rule.name)
        gm, kept = transience(run, rule.params)
        rows.append(RuleRow(rule.name, rule.label, rule_scores(run, rule.params, "albot1", gm),
                            rule_scores(run, rule.params, "true"), kept))  # fmt: skip
    trace = run.trace
    return DeletionStudy(
        run.spec.to_dict(), trace.n_frames, float(trace.travelled_m[-1]), len(run.maps),
        tuple(float(s.travelled_m) for s in run.stops()), tuple(rows), faithful,
        time.process_time() - t0,
    )  # fmt: skip


# -- the table ----------------------------------------------------------------------


def _pick(stops_m: Sequence[float], at_m: Sequence[float]) -> list[int]:
    """The first stop at or past each distance of ``at_m`` (once each), then the end."""
    picked: list[int] = []
    for want in at_m:
        i = next((i for i, s in enumerate(stops_m) if s >= want), None)
        if i is not None and i < len(stops_m) - 1 and i not in picked:
            picked.append(i)
    if stops_m:
        picked.append(len(stops_m) - 1)
    return picked


def _num(value: float | None) -> str:
    return "–" if value is None else f"{value:.2f}"


def format_table(
    study: DeletionStudy, at_m: Sequence[float] = (20, 60, 100, 200), surfaces_at_m: float = 100
) -> str:
    """The markdown table of docs/albot1.md: completeness and accuracy p95 at the stops
    first at or past ``at_m`` and at the end, surfaces at the stop first past
    ``surfaces_at_m`` and at the end."""
    cols = _pick(study.stops_m, at_m)
    surf = _pick(study.stops_m, [surfaces_at_m])
    stops = " / ".join(f"{study.stops_m[i]:.0f}" for i in cols)
    head = [
        f"{study.frames} frames, {study.travelled_m:.0f} m, {study.local_maps} local maps; "
        f"stops at {stops} m (the last: the end); surfaces at "
        f"{' / '.join(f'{study.stops_m[i]:.0f}' for i in surf)} m",
        "",
        "| rule | Albot₁'s poses: completeness | accuracy p95 | surfaces "
        f"{' / '.join(f'{study.stops_m[i]:.0f} m' for i in surf)} | true poses: completeness |",
        "|---|---|---|---|---|",
    ]
    for row in study.rows:
        cells = [
            " / ".join(_num(row.albot1[i].completeness) for i in cols),
            " / ".join(_num(row.albot1[i].accuracy_m_p95) for i in cols),
            " / ".join(f"{row.albot1[i].surfaces:,}" for i in surf),
            " / ".join(_num(row.true[i].completeness) for i in cols),
        ]
        head.append(f"| {row.label} | " + " | ".join(cells) + " |")
    head += ["", "At Albot₁'s poses, over the whole run (revisit: a view touching a map more "
             "than 20 maps back):"]  # fmt: skip
    for row in study.rows:
        t = row.transience
        gone = t.added - t.kept
        head.append(
            f"- {row.rule}: {t.kept:,} of {t.added:,} surfaces kept, {gone:,} deleted "
            f"({100 * gone / max(t.added, 1):.0f} %); {t.revisit_updates:,} revisiting updates "
            f"deleted {t.revisit_deleted:,}; {t.ms_per_update:.2f} ms per update"
        )
    return "\n".join(head)


# -- command line -------------------------------------------------------------------


class _Parser(argparse.ArgumentParser):
    """argparse whose usage errors are one line (``InputError``), like every other."""

    def error(self, message: str) -> NoReturn:
        raise InputError(message)


def _distances(text: str) -> tuple[float, ...]:
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected metres separated by commas, got {text!r}"
        ) from None
    if not all(math.isfinite(v) and v >= 0 for v in values):
        raise argparse.ArgumentTypeError(f"distances must be non-negative, got {text!r}")
    return values


def _spec(args: argparse.Namespace) -> RunSpec:
    if args.tour_length is not None and args.min_tour_length is not None:
        raise InputError("give --tour-length or --min-tour-length, not both")
    length = args.min_tour_length if args.min_tour_length is not None else args.tour_length
    default = RunSpec()
    return RunSpec(
        seed=args.seed,
        profile=args.profile,
        noise=args.noise,
        laser_noise=args.laser_noise,
        tour_kind=args.tour_kind,
        tour_length_m=default.tour_length_m if length is None else length,
        tour_length_is_minimum=args.min_tour_length is not None,
        mappers=("albot1",),
        max_frames=args.max_frames,
    )


def main(argv: Sequence[str] | None = None) -> int:
    ap = _Parser(prog="python -m albot2d.studies.deletion_rules",
                 description=(__doc__ or "").split("\n\n")[0])  # fmt: skip
    default = RunSpec()
    ap.add_argument("--seed", type=int, default=default.seed, help="office world seed")
    ap.add_argument("--profile", default=default.profile)
    ap.add_argument("--noise", default=default.noise, help="odometry noise preset")
    ap.add_argument(
        "--laser-noise",
        default=default.laser_noise,
        help="laser noise preset (sick_lms200_any_jump: the former model)",
    )
    ap.add_argument("--tour-kind", default=default.tour_kind)
    ap.add_argument(
        "--tour-length",
        type=float,
        metavar="METRES",
        help=f"tour length (default {default.tour_length_m:g})",
    )
    ap.add_argument(
        "--min-tour-length",
        type=float,
        metavar="METRES",
        help="a tour at least METRES long (100: the 282 m loop of the former table)",
    )
    ap.add_argument(
        "--albot1",
        default="albot1",
        metavar="SPEC",
        help="the Albot₁ whose poses are used: albot1 (default) or "
        "albot1[KEY=VALUE,...], e.g. albot1[deletion=paper]; its own map is "
        "the one re-adding is checked against",
    )
    ap.add_argument("--max-frames", type=int, help="cut the run short after this many frames")
    ap.add_argument(
        "--at",
        type=_distances,
        default=(20.0, 60.0, 100.0, 200.0),
        help="the table's stops: the first stop at or past each (metres, "
        "comma-separated); the end is always last",
    )
    ap.add_argument(
        "--surfaces-at",
        type=float,
        default=100.0,
        metavar="METRES",
        help="the stop at or past this whose surface count is shown",
    )
    ap.add_argument("--json", type=Path, metavar="FILE", help="write the whole study here")
    ap.add_argument("--quiet", action="store_true", help="no progress on stderr")  # fmt: skip
    try:
        args = ap.parse_args(argv)
        spec = _spec(args)
        if args.json is not None and not args.json.resolve().parent.is_dir():
            raise InputError(f"--json: no directory {args.json.parent} to write {args.json.name}")
    except InputError as exc:
        print(f"deletion_rules: {exc}", file=sys.stderr)
        return 2

    def progress(name: str) -> None:
        if not args.quiet:
            print(f"deletion_rules: re-adding under {name}", file=sys.stderr)

    try:
        study = deletion_study(spec, albot1=args.albot1, on_rule=progress)
    except InputError as exc:
        print(f"deletion_rules: {exc}", file=sys.stderr)
        return 2
    print(format_table(study, args.at, args.surfaces_at))
    print(f"\nre-adding checked against Albot₁'s own global map ({study.faithful_surfaces:,} "
          f"surfaces compared); {study.cpu_s:.0f} CPU-s")  # fmt: skip
    if args.json is not None:
        import json

        from albot2d.atomic import atomic_write_text
        from albot2d.plainjson import to_plain

        atomic_write_text(args.json, json.dumps(to_plain(study.to_dict()), indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
