"""How the robot is driven along a tour: ``DrivingProfile`` presets and ``TourController``.

The controller reproduces the paper's way of moving, linear motion "turn α then move δ":
at each waypoint it turns towards the next one, then drives straight to it, splitting
turns and moves into equal steps no larger than the profile's ``turn_step_deg`` and
``move_step_m``. The robot records a view after each step (``view_after_turn=False``:
only after moves). Presets (Yeap et al.'s datasets):

- ``dataset1``: a view every 10 cm or 1° (the paper's 1330-view run).
- ``dataset2``: dataset1 with an extra 10 cm / 1° added to each odometry step in the
  step's own direction (the true motion is unchanged; see ``albot2d.sim.odometry``). The
  literal "+1°" reading would report every 1° right-turn step as no turn at all, so a
  right turn would vanish from the odometry; ``induced_along_motion=False`` selects it.
- ``dataset3``: a view every 1 m or 10° (the 217-view run).
- ``start_stop``: the paper's start–stop driving (Experiment 1, Fig. 14): every turn
  instruction and every move instruction ends with a stop and a view (Fig. 14 counts
  "move/turn instructions"). Turns above 60° are split into equal steps of at most 60°,
  each with a view, as the original code's autonomous mode does (so a U-turn is three
  60° steps with views, never one 180° step); turns under 10° get no view of their own
  (the original code makes only turns > 10° separate turn-only views). Waypoints the
  route passes nearly straight through (within 5 cm) are driven through without
  stopping, so moves span several roadmap legs and are about 3 m ("each move is on
  average about 3 m"); a longer straight is cut into equal moves of at most 3 m.
- ``start_stop_v1``: the earlier reading, kept for comparison: each turn is merged with
  the following move of up to 3 m (one view per move, none after turns), a U-turn is one
  180° step, and every roadmap waypoint is a stop.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from albot2d.errors import InputError
from albot2d.geometry import Pose
from albot2d.sim.commands import VelocityCommand
from albot2d.sim.odometry import StepKind
from albot2d.validation import check_finite, check_non_negative, check_positive, check_positive_int

__all__ = [
    "PROFILES",
    "DrivingProfile",
    "Instruction",
    "Step",
    "TourController",
    "get_profile",
    "merge_straight",
]

# Splitting tolerance: a turn of exactly k·turn_step (within float noise) takes k steps.
_SPLIT_SLACK = 1e-9


@dataclass(frozen=True)
class DrivingProfile:
    """How a tour is driven and when views are recorded.

    - ``move_step_m`` / ``turn_step_deg``: the largest move / turn between two steps.
    - ``view_after_turn``: record a view after turn steps too (else only after moves).
    - ``induced_step_m`` / ``induced_step_deg``: odometry error added per move / turn step;
      ``induced_along_motion``: add it in the step's direction (right turns get -1°)
      instead of literally (+1°, counter-clockwise, on every turn step).
    - ``speed_m_s`` / ``turn_rate_deg_s``: nominal speeds, which set the timestamps.
    - ``stop_pause_s``: time the robot stands still at each view.
    - ``heading_tolerance_deg`` / ``waypoint_tolerance_m``: smaller turns are skipped;
      a waypoint this close counts as reached.
    - ``max_blocked_steps``: after this many blocked moves in a row (an obstacle in the
      way) the controller gives up the waypoint and heads for the next.
    - ``turn_view_min_deg``: with ``view_after_turn``, a turn step smaller than this gets
      no view of its own (its motion goes into the next view); 0: every turn step does.
    - ``merge_offset_m``: drive straight through a waypoint when leaving it out moves the
      path by at most this much (each kept leg stays within this distance of every
      waypoint it skips), so a move can span several collinear roadmap legs; 0: stop at
      every waypoint.
    """

    name: str
    move_step_m: float
    turn_step_deg: float
    view_after_turn: bool = True
    induced_step_m: float = 0.0
    induced_step_deg: float = 0.0
    induced_along_motion: bool = False
    speed_m_s: float = 0.3
    turn_rate_deg_s: float = 30.0
    stop_pause_s: float = 0.0
    heading_tolerance_deg: float = 1e-6
    waypoint_tolerance_m: float = 1e-6
    max_blocked_steps: int = 30
    turn_view_min_deg: float = 0.0
    merge_offset_m: float = 0.0

    def __post_init__(self) -> None:
        check_positive(
            self,
            "move_step_m",
            "turn_step_deg",
            "speed_m_s",
            "turn_rate_deg_s",
            "heading_tolerance_deg",
            "waypoint_tolerance_m",
        )
        check_non_negative(self, "stop_pause_s", "turn_view_min_deg", "merge_offset_m")
        check_finite(self, "induced_step_m")
        check_finite(self, "induced_step_deg")
        check_positive_int(self, "max_blocked_steps")
        for name in ("view_after_turn", "induced_along_motion"):
            if not isinstance(getattr(self, name), bool):
                raise InputError(
                    f"DrivingProfile.{name} must be true or false, got {getattr(self, name)!r}"
                )

    def step_duration_s(self, kind: StepKind, amount: float) -> float:
        """Seconds a step of ``amount`` (m or rad) takes at the nominal speeds."""
        if kind == "turn":
            return abs(amount) / math.radians(self.turn_rate_deg_s)
        return abs(amount) / self.speed_m_s

    def command(self, kind: StepKind, amount: float) -> tuple[VelocityCommand, float]:
        """The velocity command and its duration (s) that turn or move by ``amount`` (rad
        or m) at the profile's nominal speeds."""
        duration = self.step_duration_s(kind, amount)
        if kind == "turn":
            rate = math.copysign(math.radians(self.turn_rate_deg_s), amount)
            return VelocityCommand(0.0, rate), duration
        return VelocityCommand(math.copysign(self.speed_m_s, amount), 0.0), duration


_DATASET1 = DrivingProfile("dataset1", move_step_m=0.10, turn_step_deg=1.0)

PROFILES: dict[str, DrivingProfile] = {
    "dataset1": _DATASET1,
    "dataset2": dataclasses.replace(
        _DATASET1,
        name="dataset2",
        induced_step_m=0.10,
        induced_step_deg=1.0,
        induced_along_motion=True,
    ),
    "dataset3": DrivingProfile("dataset3", move_step_m=1.0, turn_step_deg=10.0),
    "start_stop": DrivingProfile(
        "start_stop",
        move_step_m=3.0,
        turn_step_deg=60.0,
        view_after_turn=True,
        stop_pause_s=1.0,
        turn_view_min_deg=10.0,
        merge_offset_m=0.05,
    ),
    "start_stop_v1": DrivingProfile(
        "start_stop_v1",
        move_step_m=3.0,
        turn_step_deg=180.0,
        view_after_turn=False,
        stop_pause_s=1.0,
    ),
}


def get_profile(profile: str | DrivingProfile) -> DrivingProfile:
    """A preset by name (or a profile passed through); unknown names list the valid ones."""
    if isinstance(profile, DrivingProfile):
        return profile
    try:
        return PROFILES[profile]
    except (KeyError, TypeError):
        raise InputError(
            f"unknown driving profile {profile!r}; valid: {', '.join(PROFILES)}"
        ) from None


def merge_straight(waypoints: np.ndarray, max_offset_m: float) -> np.ndarray:
    """``waypoints`` without those the path passes (nearly) straight through.

    Greedy from the first waypoint: a leg is extended to the next waypoint while every
    waypoint it would skip lies within ``max_offset_m`` of the extended leg (a segment, so
    a turn-back, whose apex lies beyond the segment's end, is always kept). The first and
    last waypoints are kept; ``max_offset_m == 0`` returns the waypoints unchanged.
    """
    if max_offset_m <= 0.0 or len(waypoints) <= 2:
        return waypoints
    kept = [0]
    anchor = 0
    j = 1
    while j < len(waypoints) - 1:
        if _within(
            waypoints[anchor], waypoints[j + 1], waypoints[anchor + 1 : j + 1], max_offset_m
        ):
            j += 1
            continue
        kept.append(j)
        anchor = j
        j += 1
    kept.append(len(waypoints) - 1)
    return waypoints[kept]


def _within(a: np.ndarray, b: np.ndarray, points: np.ndarray, tol: float) -> bool:
    """Whether every point lies within ``tol`` of the segment a–b."""
    ab = b - a
    denom = float(ab @ ab)
    t = np.zeros(len(points)) if denom == 0.0 else np.clip((points - a) @ ab / denom, 0.0, 1.0)
    nearest = a + t[:, None] * ab
    return bool(np.all(np.hypot(*(points - nearest).T) <= tol))


class Step(NamedTuple):
    """One command: turn by ``amount`` rad or move by ``amount`` m; ``view``: record a frame."""

    kind: StepKind
    amount: float
    view: bool
    waypoint: int


class Instruction(NamedTuple):
    """A ``Step`` as a velocity command held for ``dt_s`` seconds."""

    step: Step
    command: VelocityCommand
    dt_s: float


class TourController:
    """Closed-loop turn-then-move driving through ``waypoints`` (from the true pose).

    Call ``next_instruction(pose)`` for the next velocity command, how long to hold it
    and whether to take a view after it (None when the tour is done), execute it
    (``Simulator.step``'s physics) and ``report(step, collided)``. ``next_step`` gives
    the same as a turn or move amount.
    """

    def __init__(self, waypoints: ArrayLike, profile: str | DrivingProfile) -> None:
        self.profile = get_profile(profile)
        wp = np.asarray(waypoints, dtype=np.float64)
        if wp.ndim != 2 or wp.shape[1] != 2 or not np.isfinite(wp).all():
            raise InputError(f"tour waypoints must be a finite (K, 2) array, got shape {wp.shape}")
        self.waypoints = merge_straight(wp, self.profile.merge_offset_m)
        self.index = 0
        self._blocked = 0
        self._turn_step = math.radians(self.profile.turn_step_deg)
        self._heading_tol = math.radians(self.profile.heading_tolerance_deg)
        self._turn_view_min = math.radians(self.profile.turn_view_min_deg)

    @property
    def done(self) -> bool:
        return self.index >= len(self.waypoints)

    def next_step(self, pose: Pose) -> Step | None:
        p = self.profile
        while self.index < len(self.waypoints):
            tx, ty = self.waypoints[self.index].tolist()
            dx, dy = tx - pose.x, ty - pose.y
            dist = math.hypot(dx, dy)
            if dist <= p.waypoint_tolerance_m or self._blocked >= p.max_blocked_steps:
                self.index += 1
                self._blocked = 0
                continue
            bearing = math.atan2(dy, dx) - pose.theta
            bearing = (bearing + math.pi) % (2.0 * math.pi) - math.pi
            if abs(bearing) > self._heading_tol:
                n = max(1, math.ceil(abs(bearing) / self._turn_step - _SPLIT_SLACK))
                view = p.view_after_turn and abs(bearing / n) >= self._turn_view_min
                return Step("turn", bearing / n, view, self.index)
            n = max(1, math.ceil(dist / p.move_step_m - _SPLIT_SLACK))
            return Step("move", dist / n, True, self.index)
        return None

    def next_instruction(self, pose: Pose) -> Instruction | None:
        step = self.next_step(pose)
        if step is None:
            return None
        command, dt_s = self.profile.command(step.kind, step.amount)
        return Instruction(step, command, dt_s)

    def report(self, step: Step, collided: bool) -> None:
        """Tell the controller whether ``step`` was blocked (only moves can be)."""
        if step.kind == "move":
            self._blocked = self._blocked + 1 if collided else 0
