"""Albot1's error budget: each route-map link's error against the truth, by how it was made.

A link is one local map's pose in its predecessor (``LocalMap.pose_in_previous``); its
error is that estimate against the true relative pose of the two viewpoints. Composing
the links is all Albot1 does to know where an older local map lies, so the drift of its
egocentric map over a window of travel is exactly the composition of the links' errors
inside the window. This module records, for every link, how it was localised and what
each alternative would have given:

- ``kind``: ``triangulation``; ``pi_no_tracked`` (no tracked surface left: the paper's
  "move using PI"); ``pi_no_endpoint`` (tracked surfaces, but none has an end precisely
  located in both views); ``pi_gated`` (affordances, all farther from path integration than
  the per-step gate); ``pi_surface_heading`` (path-integration position, heading from the
  tracked surfaces' directions: ``heading_fallback_surfaces``); ``start``.
- for every link, path integration's own error (the odometry since the previous local
  map); for triangulations, how many affordances there were, passed the gate and survived
  heuristic 1, the error with the chosen affordance's own heading (``heading="selected"``),
  the position error the chosen endpoint pair leaves when the heading is exact (the
  endpoints' own error), and the best single affordance's position error (an oracle: how
  much a better choice could gain).

``window_budget`` splits the relative-pose error accumulated over a window of travel into
what the links' headings and positions contribute, and by link kind, by composing
counterfactual chains in which only those errors are kept (the rest set to the truth).

Run from the command line (small runs; see ``--help``)::

    python -m albot2d.studies.link_errors                       # the default run
    python -m albot2d.studies.link_errors --profile start_stop --noise pioneer3dx \
        --tour-kind circuit
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from albot2d.frames import Frame
from albot2d.geometry import Pose, compose_arrays, wrap_angle
from albot2d.mapping.albot1.mapper import Albot1, Albot1Params, Localisation
from albot2d.mapping.albot1.triangulation import (
    gate_limits,
    outlier_kept,
    pi_consistent,
    pose_affordances,
    triangulate,
)

__all__ = [
    "KINDS",
    "LinkError",
    "LinkRecorder",
    "kind_summary",
    "link_errors",
    "record_run",
    "recording_albot1",
    "window_budget",
]

KINDS = (
    "start",
    "triangulation",
    "pi_no_tracked",
    "pi_no_endpoint",
    "pi_gated",
    "pi_surface_heading",
)
FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class _Localisation:
    """What one call of the localisation saw (before the link is added)."""

    kind: str
    tracked: int
    affordances: int
    consistent: int
    kept: int
    steps: int
    pi_pose: FloatArray
    selected_pose: FloatArray | None  # the chosen affordance with its own heading
    chosen_points: tuple[FloatArray, FloatArray] | None  # (local, current) endpoint pair
    affordance_poses: FloatArray  # the gated affordances (K, 3)


class LinkRecorder:
    """Records, for each link Albot1 makes, how it was localised: an ``on_localise`` hook.

    Albot1 decides everything itself; the record is computed beside it with the public
    triangulation functions (the same gate and outlier heuristic the mapper uses).
    """

    def __init__(self, params: Albot1Params, pi_gate: tuple[float, float]) -> None:
        self.params = params
        self.pi_gate = pi_gate
        self.localisations: list[_Localisation] = []

    def __call__(self, event: Localisation) -> None:
        self.localisations.append(self._describe(event))

    def _describe(self, event: Localisation) -> _Localisation:
        tracked, pi_pose, steps = event.tracked, event.path_integration, event.steps
        tparams = self.params.triangulation
        pi = pi_pose.as_array()
        if len(tracked) == 0:
            return _Localisation(
                "pi_no_tracked", 0, 0, 0, 0, steps, pi, None, None, np.zeros((0, 3))
            )
        aff = pose_affordances(tracked.local, tracked.current, pi_pose.theta, tparams)
        gate_m, gate_deg = gate_limits(tparams, self.pi_gate)
        ok = pi_consistent(aff.poses, pi_pose, steps, gate_m, gate_deg)
        poses = aff.poses[ok]
        kept = len(poses)
        if tparams.use_outlier_heuristic and kept > 2:
            kept = int(outlier_kept(poses).sum())
        if event.method == "triangulation":
            selected_params = _replace(tparams, heading="selected")
            sel = triangulate(
                tracked.local, tracked.current, pi_pose, selected_params, steps=steps,
                gate=self.pi_gate,
            )  # fmt: skip
            if sel is None:  # the same affordances gave the mapper its pose
                raise RuntimeError("triangulation with heading='selected' found no pose")
            sel_arr = sel.as_array()
            i = int(
                np.argmin(
                    np.hypot(*(poses[:, :2] - sel_arr[:2]).T)
                    + np.abs(wrap_angle(poses[:, 2] - sel_arr[2]))
                )
            )
            idx = np.flatnonzero(ok)[i]
            pair = (aff.local_points[idx], aff.current_points[idx])
            return _Localisation(
                "triangulation", len(tracked), len(aff.poses), int(ok.sum()), kept, steps, pi,
                sel_arr, pair, poses,
            )  # fmt: skip
        if abs(float(wrap_angle(event.pose.theta - pi_pose.theta))) > 0.0:
            kind = "pi_surface_heading"
        elif len(aff.poses) == 0:
            kind = "pi_no_endpoint"
        else:
            kind = "pi_gated"
        return _Localisation(
            kind, len(tracked), len(aff.poses), int(ok.sum()), 0, steps, pi, None, None, poses
        )


def recording_albot1(params: Albot1Params | None = None) -> tuple[Albot1, LinkRecorder]:
    """An Albot1 and the ``LinkRecorder`` attached to its ``on_localise`` hook."""
    mapper = Albot1(params)
    recorder = LinkRecorder(mapper.params, mapper.pi_gate)
    mapper.on_localise = recorder
    return mapper, recorder


def _replace(params: Any, **changes: Any) -> Any:
    import dataclasses

    return dataclasses.replace(params, **changes)


@dataclass(frozen=True, slots=True)
class LinkError:
    """One link's error against the truth (metres, degrees; position in the previous local
    map's frame; ``nan`` where not applicable)."""

    map_id: int
    frame_index: int
    travelled_m: float
    kind: str
    tracked: int
    affordances: int
    consistent: int
    kept: int
    steps: int
    true_step_m: float
    heading_err_deg: float
    position_err_m: float
    dx_m: float
    dy_m: float
    pi_heading_err_deg: float
    pi_position_err_m: float
    selected_heading_err_deg: float
    endpoint_position_err_m: float
    best_affordance_position_err_m: float


def _rel_error(est: FloatArray, true: FloatArray) -> tuple[float, float, float]:
    return (
        float(est[0] - true[0]),
        float(est[1] - true[1]),
        math.degrees(float(wrap_angle(est[2] - true[2]))),
    )


def link_errors(
    mapper: Albot1, recorder: LinkRecorder, true_poses: FloatArray, travelled_m: FloatArray
) -> list[LinkError]:
    """Every link of ``mapper``'s route map against the truth, with how ``recorder`` saw it
    made; ``true_poses`` and ``travelled_m`` are indexed by frame index."""
    maps = mapper.route.maps
    if len(recorder.localisations) != len(maps) - 1:
        raise ValueError(
            f"{len(recorder.localisations)} localisations recorded for {len(maps)} local maps"
        )
    out: list[LinkError] = []
    nan = float("nan")
    for i, lm in enumerate(maps):
        if i == 0:
            out.append(LinkError(0, lm.frame_index, float(travelled_m[lm.frame_index]), "start",
                                 0, 0, 0, 0, 0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, nan, nan,
                                 nan))  # fmt: skip
            continue
        loc = recorder.localisations[i - 1]
        prev = Pose.from_array(true_poses[maps[i - 1].frame_index])
        true_rel = prev.between(Pose.from_array(true_poses[lm.frame_index])).as_array()
        dx, dy, dth = _rel_error(lm.pose_in_previous.as_array(), true_rel)
        pdx, pdy, pdth = _rel_error(loc.pi_pose, true_rel)
        sel_h = end_p = best_p = nan
        if loc.selected_pose is not None and loc.chosen_points is not None:
            sel_h = _rel_error(loc.selected_pose, true_rel)[2]
            local_pt, cur_pt = loc.chosen_points
            c, s = math.cos(true_rel[2]), math.sin(true_rel[2])
            at_true = local_pt - np.array([c * cur_pt[0] - s * cur_pt[1],
                                           s * cur_pt[0] + c * cur_pt[1]])  # fmt: skip
            end_p = float(np.hypot(*(at_true - true_rel[:2])))
            if len(loc.affordance_poses):
                best_p = float(np.hypot(*(loc.affordance_poses[:, :2] - true_rel[:2]).T).min())
        out.append(
            LinkError(
                lm.map_id,
                lm.frame_index,
                float(travelled_m[lm.frame_index]),
                loc.kind,
                loc.tracked,
                loc.affordances,
                loc.consistent,
                loc.kept,
                loc.steps,
                float(np.hypot(*true_rel[:2])),
                dth,
                math.hypot(dx, dy),
                dx,
                dy,
                pdth,
                math.hypot(pdx, pdy),
                sel_h,
                end_p,
                best_p,
            )
        )
    return out


def kind_summary(links: Sequence[LinkError]) -> dict[str, dict[str, float]]:
    """Per kind (and per triangulation by affordances kept): count, mean signed / mean
    absolute heading error, mean position error, and path integration's on the same links."""
    groups: dict[str, list[LinkError]] = {}
    for link in links:
        if link.kind == "start":
            continue
        groups.setdefault(link.kind, []).append(link)
        if link.kind == "triangulation":
            groups.setdefault(f"triangulation kept={min(link.kept, 3)}", []).append(link)
    out: dict[str, dict[str, float]] = {}
    for name, group in groups.items():
        h = np.array([g.heading_err_deg for g in group])
        ph = np.array([g.pi_heading_err_deg for g in group])
        row = {
            "links": float(len(group)),
            "heading_mean_deg": float(h.mean()),
            "heading_abs_deg": float(np.abs(h).mean()),
            "heading_sum_deg": float(h.sum()),
            "position_mean_m": float(np.mean([g.position_err_m for g in group])),
            "pi_heading_abs_deg": float(np.abs(ph).mean()),
            "pi_heading_sum_deg": float(ph.sum()),
            "pi_position_mean_m": float(np.mean([g.pi_position_err_m for g in group])),
        }
        if name.startswith("triangulation"):
            sel = np.array([g.selected_heading_err_deg for g in group])
            row["selected_heading_abs_deg"] = float(np.abs(sel).mean())
            row["endpoint_position_mean_m"] = float(
                np.mean([g.endpoint_position_err_m for g in group])
            )
            row["best_affordance_position_mean_m"] = float(
                np.nanmean([g.best_affordance_position_err_m for g in group])
            )
        out[name] = row
    return out


def _chain(links: FloatArray) -> FloatArray:
    out = np.empty_like(links)
    acc = np.zeros(3)
    for i, r in enumerate(links):
        acc = compose_arrays(acc, r)
        out[i] = acc
    return out


def window_budget(
    mapper: Albot1,
    links: Sequence[LinkError],
    true_poses: FloatArray,
    *,
    end_m: float,
    window_m: float = 30.0,
) -> dict[str, dict[str, float]]:
    """The error of the last local map's pose relative to the first one within the window
    of travel ``(end_m − window_m, end_m]`` (heading °, position m), with all links as
    estimated (``all``), with only the links' headings or only their positions estimated
    (``all: headings only`` / ``all: positions only``), and with only the links of one kind
    carrying their error."""
    maps = mapper.route.maps
    inside = [i for i, link in enumerate(links) if end_m - window_m < link.travelled_m <= end_m]
    if len(inside) < 2:
        return {}
    first, last = inside[0], inside[-1]
    est = np.array([maps[i].pose_in_previous.as_array() for i in range(first + 1, last + 1)])
    true = np.array(
        [
            Pose.from_array(true_poses[maps[i - 1].frame_index])
            .between(Pose.from_array(true_poses[maps[i].frame_index]))
            .as_array()
            for i in range(first + 1, last + 1)
        ]
    )
    kinds = [links[i].kind for i in range(first + 1, last + 1)]
    truth_end = _chain(true)[-1]

    def error(mask: NDArray[np.bool_], columns: slice = slice(0, 3)) -> dict[str, float]:
        links = true.copy()
        links[mask, columns] = est[mask, columns]
        end = _chain(links)[-1]
        return {
            "links": float(mask.sum()),
            "heading_deg": math.degrees(float(wrap_angle(end[2] - truth_end[2]))),
            "position_m": float(np.hypot(*(end[:2] - truth_end[:2]))),
        }

    every = np.ones(len(kinds), bool)
    out = {
        "all": error(every),
        "all: headings only": error(every, slice(2, 3)),
        "all: positions only": error(every, slice(0, 2)),
    }
    for kind in sorted(set(kinds)):
        out[kind] = error(np.array([k == kind for k in kinds]))
    return out


# -- command line -------------------------------------------------------------------


def record_run(
    spec: Any, params: Albot1Params | None = None, *, max_frames: int | None = None
) -> tuple[Albot1, LinkRecorder, FloatArray, FloatArray]:
    """Simulate ``spec`` (a ``RunSpec``) and feed its frames to a recording Albot1;
    returns the mapper, its recorder, the true poses and the odometer (metres) per frame
    index."""
    from albot2d.evaluation.run.setup import build_run

    setup = build_run(spec)
    mapper, recorder = recording_albot1(params)
    truth: list[FloatArray] = []
    travelled: list[float] = []
    odo = 0.0
    frames: Iterable[Frame] = setup.simulator.drive(setup.tour, setup.profile)
    for frame in frames:
        if max_frames is not None and len(truth) >= max_frames:
            break
        if frame.true_pose is None or frame.index != len(truth):
            raise ValueError(f"frame {frame.index}: no truth or out of order")
        odo += math.hypot(frame.odom_increment.x, frame.odom_increment.y)
        truth.append(frame.true_pose.as_array())
        travelled.append(odo)
        mapper.observe(frame)
    return mapper, recorder, np.array(truth).reshape(-1, 3), np.array(travelled)


def _parse_value(text: str) -> Any:
    for cast in (int, float):
        try:
            return cast(text)
        except ValueError:
            pass
    return {"true": True, "false": False}.get(text, text)


def _with_overrides(params: Albot1Params, items: Sequence[str]) -> Albot1Params:
    """``KEY=VALUE`` or ``GROUP.KEY=VALUE`` (e.g. ``triangulation.position_endpoint=…``)."""
    import dataclasses

    for item in items:
        key, eq, text = item.partition("=")
        if not eq:
            raise ValueError(f"--param {item!r}: give KEY=VALUE")
        group, _, field_name = key.rpartition(".")
        value = _parse_value(text)
        if group:
            inner = dataclasses.replace(getattr(params, group), **{field_name: value})
            params = dataclasses.replace(params, **{group: inner})
        else:
            params = dataclasses.replace(params, **{field_name: value})
    return params


def _format(summary: dict[str, dict[str, float]]) -> str:
    cols = ["links", "heading_mean_deg", "heading_abs_deg", "heading_sum_deg",
            "position_mean_m", "pi_heading_abs_deg", "pi_heading_sum_deg",
            "pi_position_mean_m", "selected_heading_abs_deg", "endpoint_position_mean_m",
            "best_affordance_position_mean_m"]  # fmt: skip
    lines = ["kind".ljust(22) + " ".join(c[:14].rjust(14) for c in cols)]
    for name, row in sorted(summary.items()):
        cells = [f"{row[c]:14.3f}" if c in row else " " * 13 + "-" for c in cols]
        lines.append(name.ljust(22) + " ".join(cells))
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--seeds", type=int, default=1, help="pool the link table over seeds SEED..SEED+N-1"
    )
    parser.add_argument("--profile", default="dataset1")
    parser.add_argument("--noise", default="typical")
    parser.add_argument("--tour-kind", default="loop")
    parser.add_argument("--tour-length", type=float, default=100.0)
    parser.add_argument("--preset", default="paper")
    parser.add_argument(
        "--param",
        action="append",
        default=[],
        help="Albot1Params override: KEY=VALUE or GROUP.KEY=VALUE",
    )
    parser.add_argument(
        "--windows", type=float, nargs="*", default=[100.0], help="window ends (first seed)"
    )
    parser.add_argument("--max-frames", type=int, default=None)
    args = parser.parse_args(argv)
    from albot2d.errors import InputError
    from albot2d.evaluation.run.setup import RunSpec

    try:
        specs = [
            RunSpec(
                seed=seed,
                profile=args.profile,
                noise=args.noise,
                tour_kind=args.tour_kind,
                tour_length_m=args.tour_length,
                mappers=("albot1",),
            )
            for seed in range(args.seed, args.seed + max(args.seeds, 1))
        ]
        params = _with_overrides(Albot1Params.preset(args.preset), args.param)
    except (InputError, ValueError, TypeError, AttributeError) as exc:
        print(f"link_errors: {exc}")
        return 2
    pooled: list[LinkError] = []
    views = metres = 0.0
    budgets = []
    for i, spec in enumerate(specs):
        mapper, recorder, truth, travelled = record_run(spec, params, max_frames=args.max_frames)
        links = link_errors(mapper, recorder, truth, travelled)
        pooled += links
        views += len(truth)
        metres += float(travelled[-1])
        if i == 0:
            budgets = [
                (end, window_budget(mapper, links, truth, end_m=end)) for end in args.windows
            ]
    print(f"{len(specs)} run(s): {views:.0f} views, {len(pooled)} local maps, {metres:.0f} m")
    print(_format(kind_summary(pooled)))
    for end, budget in budgets:
        print(f"30 m window ending at {end:.0f} m (seed {args.seed}):")
        for kind, row in budget.items():
            print(f"  {kind:22s} links {row['links']:5.0f}  heading {row['heading_deg']:+7.2f}°"
                  f"  position {row['position_m']:6.2f} m")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
