"""Running a ``FrontierExplorer`` in a simulator: ``ExploreDrive``, ``explore`` and the
coverage record ``ExplorationResult``.

``ExploreDrive(simulator, profile)`` resets the simulator at the world's start and steps it
(``Simulator.step``, every ``dt_s``) with the explorer's commands until no frontier is
reachable or ``max_time_s`` of simulated time have passed. Its ``frames()`` are the views a
mapper gets, taken as the driving profile says: the first at the start, then one at the
first laser scan after the odometry has moved ``profile.move_step_m`` or turned
``profile.turn_step_deg`` since the last view (turn-only views only with
``view_after_turn``), each carrying the odometry increment since the previous view; the
explorer's true pose goes into each frame's ``true_pose`` for scoring, never to a mapper.
Coverage (the fraction of the reachable floor, ``floor.reachable_floor``, that the laser has
shown, on the explorer's own grid) is recorded at every scan.

``albot2d run --tour explore`` drives this way (the tour kind ``EXPLORE_TOUR``).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from albot2d.control.explorer import ExplorerParams, FrontierExplorer
from albot2d.control.floor import ReachableFloor, reachable_floor
from albot2d.control.knowledge import GridSpec
from albot2d.errors import InputError
from albot2d.frames import Frame
from albot2d.geometry import Pose
from albot2d.sim.commands import VelocityCommand
from albot2d.sim.driving import DrivingProfile, get_profile

if TYPE_CHECKING:
    from albot2d.sim.simulator import Simulator
    from worldgen.world import World

__all__ = [
    "DEFAULT_MAX_TIME_S",
    "EXPLORE_TOUR",
    "ExplorationResult",
    "ExploreDrive",
    "explore",
    "explorer_grid",
    "format_coverage_table",
]

FloatArray = NDArray[np.float64]

#: The tour kind of ``albot2d run`` that explores instead of driving a planned tour.
EXPLORE_TOUR = "explore"
#: How long an exploration may take (simulated seconds) unless told otherwise.
DEFAULT_MAX_TIME_S = 1800.0
# Coverage levels whose first time is reported.
_MILESTONES = (0.5, 0.8, 0.9, 0.95)
# The report's coverage table: one row per this many simulated seconds.
_TABLE_EVERY_S = 60.0


def explorer_grid(world: World, resolution_m: float) -> GridSpec:
    """The explorer's canvas: the world's free space plus a one-metre margin."""
    x0, y0, x1, y1 = world.free_space.bounds
    return GridSpec.covering(x0, y0, x1, y1, resolution_m, margin_m=1.0)


@dataclass(frozen=True, eq=False)
class ExplorationResult:
    """Coverage against time of one exploration.

    ``times_s``/``coverage`` sample the fraction of the reachable floor seen at every scan;
    ``reason`` is ``"explored"`` (no reachable frontier left), ``"time"`` (``max_time_s``
    reached) or ``"stopped"`` (the consumer stopped taking frames).
    """

    times_s: FloatArray
    coverage: FloatArray
    reachable_area_m2: float
    cell_area_m2: float
    reachable_cells: int
    duration_s: float
    travelled_m: float
    collisions: int
    plans: int
    reason: str
    max_time_s: float
    clears: int = 0  # times the explorer forgot its obstacles to get out (FrontierExplorer)

    @property
    def final_coverage(self) -> float:
        return float(self.coverage[-1]) if len(self.coverage) else 0.0

    def coverage_at(self, time_s: float) -> float:
        """The coverage reached by ``time_s`` (the last sample at or before it)."""
        k = int(np.searchsorted(self.times_s, time_s, side="right")) - 1
        return float(self.coverage[k]) if k >= 0 else 0.0

    def time_to(self, fraction: float) -> float | None:
        """The first time the coverage reached ``fraction``, or None if it never did."""
        k = np.flatnonzero(self.coverage >= fraction)
        return float(self.times_s[k[0]]) if len(k) else None

    def table(self, every_s: float = _TABLE_EVERY_S) -> list[dict[str, float]]:
        """Coverage every ``every_s`` simulated seconds up to the end."""
        marks = np.arange(0.0, self.duration_s + every_s, every_s)
        marks = marks[marks <= self.duration_s + 1e-9]
        if len(marks) == 0 or marks[-1] < self.duration_s:
            marks = np.append(marks, self.duration_s)
        return [
            {"time_s": round(float(t), 3), "coverage": round(self.coverage_at(float(t)), 4)}
            for t in marks
        ]

    def to_dict(self) -> dict[str, Any]:
        """report.json's ``exploration`` section."""
        return {
            "reachable_floor_m2": round(self.reachable_area_m2, 3),
            "reachable_cells": self.reachable_cells,
            "cell_area_m2": self.cell_area_m2,
            "final_coverage": round(self.final_coverage, 4),
            "seen_floor_m2": round(
                self.final_coverage * self.reachable_cells * self.cell_area_m2, 3
            ),
            "time_to_coverage_s": {
                f"{m:.2f}": (None if (t := self.time_to(m)) is None else round(t, 3))
                for m in _MILESTONES
            },
            "duration_s": round(self.duration_s, 3),
            "max_time_s": self.max_time_s,
            "ended": self.reason,
            "travelled_m": round(self.travelled_m, 3),
            "collisions": self.collisions,
            "plans": self.plans,
            "clears": self.clears,
            "coverage_every_60s": self.table(),
        }


class ExploreDrive:
    """One exploration of ``simulator``'s world from its start (see the module docstring).

    Iterate ``frames()`` (or call ``run()``), then read ``result``.
    """

    def __init__(
        self,
        simulator: Simulator,
        profile: str | DrivingProfile = "dataset1",
        *,
        params: ExplorerParams | None = None,
        max_time_s: float = DEFAULT_MAX_TIME_S,
        dt_s: float = 0.1,
        start: Pose | None = None,
    ) -> None:
        for name, value in (("max_time_s", max_time_s), ("dt_s", dt_s)):
            if (
                isinstance(value, bool)
                or not isinstance(value, int | float)
                or not (math.isfinite(value) and value > 0)
            ):
                raise InputError(f"ExploreDrive {name} must be a positive number, got {value!r}")
        self.simulator = simulator
        self.world = simulator.world
        self.profile = get_profile(profile)
        self.params = params if params is not None else ExplorerParams()
        self.max_time_s = float(max_time_s)
        self.dt_s = float(dt_s)
        self.start = start if start is not None else self.world.start
        spec = explorer_grid(self.world, self.params.resolution_m)
        self.floor: ReachableFloor = reachable_floor(self.world, spec)
        self.explorer = FrontierExplorer(spec, self.world.robot_radius_m, self.params)
        self._times: list[float] = []
        self._coverage: list[float] = []
        self._seen_cells = 0
        self._travelled = 0.0
        self._collisions = 0
        self._time = 0.0
        self._reason = "stopped"
        self.true_poses: list[Pose] = []

    def _record(self, time_s: float, new_cells: NDArray[np.intp]) -> None:
        if len(new_cells):
            self._seen_cells += int(np.count_nonzero(self.floor.mask.reshape(-1)[new_cells]))
        self._times.append(time_s)
        self._coverage.append(self._seen_cells / max(self.floor.cells, 1))

    def frames(self) -> Iterator[Frame]:
        """The views of the drive (see the module docstring)."""
        sim, explorer, prof = self.simulator, self.explorer, self.profile
        obs = sim.reset(start=self.start)
        assert obs.scan is not None, "the laser fires at reset"
        self._record(obs.time_s, explorer.observe(obs.true_pose, obs.scan))
        self.true_poses.append(obs.true_pose)
        index = 0
        yield Frame(
            index=0, timestamp=obs.time_s, scan=obs.scan, odom_pose=obs.odom_pose,
            odom_increment=Pose(), true_pose=obs.true_pose, collided=False,
            obstacle_poses=obs.obstacle_poses,
        )  # fmt: skip
        last_view_odom = obs.odom_pose
        moved = turned = 0.0
        collided = False
        turn_step = math.radians(prof.turn_step_deg)
        self._reason = "stopped"
        while True:
            if obs.time_s >= self.max_time_s - 1e-9:
                self._reason = "time"
                break
            command = explorer.command(obs.true_pose, obs.time_s)
            if command is None:
                self._reason = "explored"
                break
            before = obs.true_pose
            obs = sim.step(VelocityCommand(*command), self.dt_s)
            self._time = obs.time_s
            self._travelled += before.distance_to(obs.true_pose)
            self.true_poses.append(obs.true_pose)
            if obs.collided:
                self._collisions += 1
                collided = True
            new = explorer.observe(obs.true_pose, obs.scan, obs.collided)
            if obs.scan is not None:
                self._record(obs.time_s, new)
            inc = obs.odom_increment
            moved += math.hypot(inc.x, inc.y)
            turned += abs(inc.theta)
            due = moved >= prof.move_step_m - 1e-9 or (
                prof.view_after_turn and turned >= turn_step - 1e-9
            )
            if due and obs.scan is not None:
                index += 1
                yield Frame(
                    index=index, timestamp=obs.time_s, scan=obs.scan, odom_pose=obs.odom_pose,
                    odom_increment=last_view_odom.between(obs.odom_pose),
                    true_pose=obs.true_pose, collided=collided,
                    obstacle_poses=obs.obstacle_poses,
                )  # fmt: skip
                last_view_odom = obs.odom_pose
                moved = turned = 0.0
                collided = False

    def run(self) -> ExplorationResult:
        """Drive the whole exploration (frames discarded); returns ``result``."""
        for _ in self.frames():
            pass
        return self.result

    @property
    def result(self) -> ExplorationResult:
        """Coverage against time so far (complete once ``frames()`` is exhausted)."""
        return ExplorationResult(
            times_s=np.asarray(self._times, dtype=np.float64),
            coverage=np.asarray(self._coverage, dtype=np.float64),
            reachable_area_m2=self.floor.area_m2,
            cell_area_m2=self.floor.spec.cell_area_m2,
            reachable_cells=self.floor.cells,
            duration_s=self._time,
            travelled_m=self._travelled,
            collisions=self._collisions,
            plans=self.explorer.plans,
            reason=self._reason,
            max_time_s=self.max_time_s,
            clears=self.explorer.clears,
        )


def explore(
    simulator: Simulator,
    *,
    params: ExplorerParams | None = None,
    max_time_s: float = DEFAULT_MAX_TIME_S,
    dt_s: float = 0.1,
) -> ExplorationResult:
    """Explore ``simulator``'s world from its start; coverage against time."""
    return ExploreDrive(simulator, params=params, max_time_s=max_time_s, dt_s=dt_s).run()


def format_coverage_table(exploration: dict[str, Any], every_s: float = 300.0) -> str:
    """report.json's ``exploration`` section as a text table: coverage every ``every_s``
    simulated seconds, the times the milestones were reached, how the run ended."""
    rows = [
        r for r in exploration["coverage_every_60s"]
        if r["time_s"] % every_s < 1e-6 or r is exploration["coverage_every_60s"][-1]
    ]  # fmt: skip
    lines = [
        f"exploration: {exploration['reachable_floor_m2']:.0f} m² of reachable floor; "
        f"ended: {exploration['ended']} after {exploration['duration_s']:.0f} s, "
        f"{exploration['travelled_m']:.0f} m, {exploration['collisions']} collision steps, "
        f"{exploration.get('clears', 0)} clears",
        "  time (min)  " + "  ".join(f"{r['time_s'] / 60.0:5.1f}" for r in rows),
        "  coverage    " + "  ".join(f"{100.0 * r['coverage']:4.0f}%" for r in rows),
    ]
    reached = [
        f"{float(level):.0%} at {t / 60.0:.1f} min"
        if t is not None
        else f"{float(level):.0%} never"
        for level, t in exploration["time_to_coverage_s"].items()
    ]
    lines.append("  reached     " + ", ".join(reached))
    return "\n".join(lines)
