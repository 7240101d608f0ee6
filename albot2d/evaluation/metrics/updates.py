"""Moves per global-map update by region kind (the paper's Fig. 14).

Fig. 14 of Yeap et al. counts, for a start–stop run, "the number of move/turn
instructions executed before an update is required" and contrasts a corridor (updates
"after at most 2 moves") with a more open area ("after at least 2 moves"). Here every
frame of a start–stop run is one instruction (a move or a turn, see
``albot2d.sim.driving``); an *update* is a frame at which the mapper remembered at least
one view (for Albot1: ``StepRecord.remembered`` not empty; the first view, remembered
without any instruction, is not an update). Each update is labelled with the region kind
(``worldgen.regions``) of the robot's true position at that frame, where Fig. 14 puts its
green marker, and counts the instructions since the previous update (or the start).

``updates_by_region`` takes plain arrays so it works for any mapper that says per frame
whether it remembered a view; ``albot1_update_flags`` reads those flags from Albot1.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from albot2d.errors import InputError

__all__ = [
    "albot1_update_flags",
    "region_labels",
    "summarise_counts",
    "update_counts",
    "updates_by_region",
    "updates_section",
]

# A frame whose true position moved less than this since the previous one was a turn.
_MOVE_EPS_M = 1e-6


def albot1_update_flags(steps: Sequence[Any], frame_indices: ArrayLike) -> np.ndarray:
    """Per trace row: whether Albot1 remembered a view at that row's frame.

    ``steps`` are Albot1's ``StepRecord``s (``mapper.steps``); ``frame_indices`` the trace's
    frame indices. Rows without a step (frames the mapper did not see) are False.
    """
    rows = {int(f): k for k, f in enumerate(np.asarray(frame_indices).tolist())}
    flags = np.zeros(len(rows), dtype=bool)
    for step in steps:
        row = rows.get(int(step.frame_index))
        if row is not None and step.remembered:
            flags[row] = True
    return flags


def region_labels(world: Any, true_xy: ArrayLike) -> np.ndarray:
    """The region kind at each true position (``worldgen.regions.region_kind_at``, whose
    isovists are computed in blocks of points: bounded memory)."""
    from worldgen.regions import region_kind_at

    return region_kind_at(world, true_xy)


def _summary(counts: list[int]) -> dict[str, float | int]:
    arr = np.asarray(counts, dtype=float)
    return {
        "mean": float(arr.mean()),
        "median": float(np.median(arr)),
        "max": int(arr.max()),
        "share_at_most_2": float(np.mean(arr <= 2)),
        "share_at_least_2": float(np.mean(arr >= 2)),
    }


def update_counts(
    true_xy: ArrayLike, updated: ArrayLike, regions: ArrayLike
) -> tuple[dict[str, list[int]], dict[str, list[int]]]:
    """(instructions, moves) before each update, as lists per region kind.

    ``true_xy`` ``(N, 2)`` true positions per frame, ``updated`` ``(N,)`` whether the mapper
    remembered a view at that frame, ``regions`` ``(N,)`` region kind per frame. Only the
    labels of update rows are read, so on long runs label just those (the others may be
    empty strings): labelling costs ~1 ms per point on an office world.
    """
    xy = np.asarray(true_xy, dtype=np.float64).reshape(-1, 2)
    flags = np.asarray(updated, dtype=bool).reshape(-1)
    kinds = np.asarray(regions).reshape(-1)
    if not (len(xy) == len(flags) == len(kinds)):
        raise InputError(
            f"updates_by_region: {len(xy)} positions, {len(flags)} flags and {len(kinds)} "
            "region labels; give one of each per frame"
        )
    moved = np.r_[False, np.hypot(*np.diff(xy, axis=0).T) > _MOVE_EPS_M]
    instructions: dict[str, list[int]] = {}
    moves: dict[str, list[int]] = {}
    last = 0
    for row in np.flatnonzero(flags):
        if row == 0:
            continue  # the first view: remembered before any instruction
        kind = str(kinds[row])
        instructions.setdefault(kind, []).append(int(row - last))
        moves.setdefault(kind, []).append(int(moved[last + 1 : row + 1].sum()))
        last = int(row)
    return instructions, moves


def summarise_counts(
    instructions: dict[str, list[int]], moves: dict[str, list[int]]
) -> dict[str, dict[str, Any]]:
    """``{kind: {"updates", "instructions_per_update", "moves_per_update"}}`` plus
    ``"all"`` pooling every kind; each summary has mean, median, max and the shares of
    updates after at most / at least 2. Kinds without an update are left out."""
    out: dict[str, dict[str, Any]] = {}
    for kind in sorted(instructions):
        out[kind] = {
            "updates": len(instructions[kind]),
            "instructions_per_update": _summary(instructions[kind]),
            "moves_per_update": _summary(moves[kind]),
        }
    if instructions:
        every_i = [n for kind in instructions for n in instructions[kind]]
        every_m = [n for kind in moves for n in moves[kind]]
        out["all"] = {
            "updates": len(every_i),
            "instructions_per_update": _summary(every_i),
            "moves_per_update": _summary(every_m),
        }
    return out


def updates_by_region(
    true_xy: ArrayLike, updated: ArrayLike, regions: ArrayLike
) -> dict[str, dict[str, Any]]:
    """Instructions (and moves) per update, by region kind; see the module docstring and
    ``update_counts`` for the arguments, ``summarise_counts`` for the result."""
    return summarise_counts(*update_counts(true_xy, updated, regions))


def updates_section(world: Any, trace: Any, mapper: Any) -> dict[str, dict[str, Any]] | None:
    """report.json's ``updates_by_region`` for a view-based mapper with per-frame step
    records (Albot1) in a simulated run; None otherwise. Only update rows are labelled."""
    steps = getattr(mapper, "steps", None)
    if world is None or trace.true_poses is None or not isinstance(steps, list):
        return None
    flags = albot1_update_flags(steps, trace.frame_indices)
    xy = trace.true_poses[:, :2]
    labels = np.full(len(flags), "", dtype=object)
    rows = np.flatnonzero(flags)
    if len(rows):
        labels[rows] = region_labels(world, xy[rows])
    return updates_by_region(xy, flags, labels)
