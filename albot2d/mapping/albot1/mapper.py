"""The Albot1 view-based mapper: algorithms #2–#4 of the paper (main loop, update-maps, PI).

Per frame: extract the view's surfaces, track the current local map's surfaces into it
(RTSV), and when fewer than ``min_tracked`` (4) remain, remember a view as the next local
map, localised in the current one by triangulation from tracked surfaces or, with none,
by path integration; each remembered view is added to the route map and to the global
map (algorithm #5).

The paper's Use-Vc flow, restated consistently (``../shared/spec/albot1-reading.md``):
Use-Vc holds exactly when V(c-1) is already the current local map.

- Not Use-Vc: remember V(c-1), triangulated from the surfaces tracked at c-1 (there were
  ≥ 4). Re-track its surfaces into V(c). If still fewer than 4, also remember V(c).
- Use-Vc: remember V(c), triangulated from its 1–3 tracked surfaces, or by path
  integration when none are left (algorithm #4: in featureless stretches every view is
  remembered by path integration until one keeps ≥ 4 tracked surfaces).

Between local maps the robot's pose in the current local map is path integration of the
odometry increments since the map's origin; a frame's global pose is the composed chain
pose of its local map ⊕ that offset.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Literal, NamedTuple

import numpy as np
from numpy.typing import NDArray

from albot2d.errors import InputError
from albot2d.frames import Frame
from albot2d.geometry import Pose, compose_arrays, wrap_angle
from albot2d.mapping.albot1.global_map import GlobalMap, GlobalMapParams, MapSnapshot, UpdateReport
from albot2d.mapping.albot1.route_map import LocalMap, Method, RouteMap
from albot2d.mapping.albot1.triangulation import (
    TriangulationParams,
    heading_from_directions,
    triangulate,
)
from albot2d.mapping.protocol import MapperCounts, StageTimer
from albot2d.perception import (
    ExtractionParams,
    TrackedSurfaces,
    TrackingParams,
    extract_surfaces,
    rtsv,
    start_tracking,
    trackable_mask,
)
from albot2d.perception.surfaces import Surfaces, transform_segments_fast
from albot2d.validation import check_positive, check_positive_int

__all__ = [
    "PAPER_LITERAL",
    "PRESETS",
    "Albot1",
    "Albot1Params",
    "Localisation",
    "StepRecord",
    "UpdateSummary",
]


class StepRecord(NamedTuple):
    """What the main loop decided at one view (kept per view; a few bytes each).

    - ``tracked``: tracked surfaces left after RTSV against the current local map;
    - ``use_vc``: whether V(c-1) was already the current local map (the Use-Vc switch);
    - ``remembered``: frame indices of the views remembered at this step, in order;
    - ``methods``: how each of those was localised.
    """

    frame_index: int
    tracked: int
    use_vc: bool
    remembered: tuple[int, ...]
    methods: tuple[Method, ...]


class Localisation(NamedTuple):
    """One view localised in the current local map, as ``Albot1.on_localise`` sees it.

    ``tracked`` are the surfaces tracked into the view, ``path_integration`` the pose
    odometry gives since the local map's origin (after ``steps`` odometry steps), ``pose``
    and ``method`` what the mapper decided (algorithm #2 line 6 or algorithm #4 line 1).
    """

    tracked: TrackedSurfaces
    path_integration: Pose
    steps: int
    pose: Pose
    method: Method


class UpdateSummary(NamedTuple):
    """What one global-map update deleted (kept per update; the figures of transience).

    ``oldest_affected`` is the oldest map whose surfaces the view touched (-1: none); an
    update whose oldest affected map is far back in the route is a *revisit*.
    """

    map_id: int
    frame_index: int
    deleted_current: int
    deleted_older: int
    oldest_affected: int


@dataclass(frozen=True, slots=True)
class Albot1Params:
    """All of Albot1's parameters; defaults are the paper's values where it gives them.

    - ``min_tracked``: a new local map is remembered when fewer than this many tracked
      surfaces remain (paper: four; the authors' code: three).
    - ``localise_every_view``: between updates, triangulate every view in the current
      local map too (the authors' start–stop programs), keeping the odometric pose when the
      result is more than ``odometry_fallback_m`` / ``odometry_fallback_deg`` away from it;
      off (the paper): views between updates are placed by path integration.
    - ``heading_fallback_surfaces``: a view whose tracked surfaces afford no position (none
      has an end precisely located in both views, e.g. side walls whose ends were seen at
      grazing angles) takes its position from path integration and, when at least this
      many tracked surfaces agree on it, its heading from their directions (a direction
      needs no corner: ``triangulation.heading_from_directions``); 0: path integration's
      heading too (the paper's "move using PI").
    - ``move_using_pi``: what follows a view remembered by path integration because no
      tracked surface was left. ``"restated"`` (default; ``albot1-reading.md``): that view
      becomes the local map and the main loop goes on (the next view is tracked against
      it, triangulated from 1–3 tracked surfaces, or path-integrated again with none).
      ``"as_written"``: algorithm #4 as the paper writes it. A view remembered with no
      tracked surface left is placed by path integration (line 6 has nothing to
      triangulate from); algorithm #2's line 8 then tests S_t, which update-maps
      (algorithm #3, line 2) has just set to that view's *trackable* surfaces, so the
      robot shifts to PI mode only when the view has none ("when no trackable surfaces
      are in view", the paper's Fig. 15 and Results); with some, tracking resumes from
      it (line 11). In PI mode every following view is remembered by path integration
      too, without tracking, until one has more than three (``min_tracked - 1``)
      trackable surfaces; that view is remembered (by path integration, line 8) and
      tracking resumes from it. ``"on_lost_tracking"``: as ``"as_written"``, but PI mode
      starts whenever no *tracked* surface is left (S_t read as RTSV's result), even in a
      view with trackable surfaces (albot2d's earlier ``as_written``; measured in
      ``docs/albot1.md``).

    ``Albot1Params.preset("default")`` (the defaults; ``"paper"`` is the same, its older
    name), ``preset("paper_literal")`` (the paper's text wherever it speaks, see
    ``PAPER_LITERAL``) and ``preset("original")`` (the
    authors' C++ code where it differs from the paper: key-endpoint matching with a fitness
    floor, no 3° viewing-angle test, update at < 3, heuristic 2 by fitness with the chosen
    surface's own heading and its position from the tracked surface's key end, every
    view localised with the odometry fallback, and the code's global-map deletion rule)
    select consistent sets; ``preset("start_stop")`` is the paper with
    ``heading_fallback_surfaces=1``, the reading for start–stop driving (moves of
    ~3 m, whose odometric heading is less precise than one tracked wall's direction);
    keyword overrides apply on top.
    """

    extraction: ExtractionParams = field(default_factory=ExtractionParams)
    tracking: TrackingParams = field(default_factory=TrackingParams)
    triangulation: TriangulationParams = field(default_factory=TriangulationParams)
    global_map: GlobalMapParams = field(default_factory=GlobalMapParams)
    min_tracked: int = 4
    localise_every_view: bool = False
    heading_fallback_surfaces: int = 0
    odometry_fallback_m: float = 0.40
    odometry_fallback_deg: float = 5.0
    move_using_pi: Literal["restated", "as_written", "on_lost_tracking"] = "restated"

    def __post_init__(self) -> None:
        check_positive_int(self, "min_tracked")
        if self.move_using_pi not in ("restated", "as_written", "on_lost_tracking"):
            raise InputError(
                "Albot1Params.move_using_pi must be restated, as_written or on_lost_tracking, "
                f"got {self.move_using_pi!r}"
            )
        check_positive(self, "odometry_fallback_m", "odometry_fallback_deg")
        if not isinstance(self.localise_every_view, bool):
            raise InputError(
                "Albot1Params.localise_every_view must be true or false, "
                f"got {self.localise_every_view!r}"
            )
        value = self.heading_fallback_surfaces
        if isinstance(value, bool) or not isinstance(value, int) or value < 0:
            raise InputError(
                f"Albot1Params.heading_fallback_surfaces must be an integer >= 0, got {value!r}"
            )

    @classmethod
    def preset(cls, name: str, **overrides: Any) -> Albot1Params:
        """One of ``PRESETS`` (see the class doc), with field overrides."""
        if name in ("default", "paper"):
            base = cls()
        elif name == "paper_literal":
            base = cls(
                extraction=ExtractionParams(
                    max_endpoint_gap_m=math.inf, continuation_distance_m=0.0
                ),
                triangulation=TriangulationParams(
                    max_pi_deviation_m=math.inf,
                    max_pi_deviation_deg=math.inf,
                    position_endpoint="current_real",
                ),
                move_using_pi="as_written",
            )
        elif name == "original":
            base = cls(
                tracking=TrackingParams(
                    min_view_angle_deg=0.0,
                    match_endpoint="key",
                    match_order="fitness",
                    fitness_floor=80.0,
                ),
                triangulation=TriangulationParams(
                    choose="fitness", heading="selected", position_endpoint="local_key"
                ),
                global_map=GlobalMapParams.preset("original"),
                min_tracked=3,
                localise_every_view=True,
            )
        elif name == "start_stop":
            base = cls(heading_fallback_surfaces=1)
        else:
            raise InputError(f"unknown Albot1 preset {name!r}; valid: {', '.join(PRESETS)}")
        return dataclasses.replace(base, **overrides)


#: ``Albot1Params.preset`` names (``"paper"`` is the old name of ``"default"``).
PRESETS = ("default", "paper_literal", "original", "start_stop", "paper")

#: What ``preset("paper_literal")`` changes from the defaults, and the paper's words for it.
PAPER_LITERAL: dict[str, str] = {
    "triangulation.max_pi_deviation_m=inf, triangulation.max_pi_deviation_deg=inf": (
        "no gate against the path-integration estimate: heuristic 1 rules out affordances "
        "only by their spread about the mean, heuristic 2 picks the one nearest path "
        "integration (the paper's two heuristics, nothing else)"
    ),
    "triangulation.position_endpoint=current_real, extraction.max_endpoint_gap_m=inf": (
        "a tracked surface affords the point of its occluding (unoccluded) endpoint in the "
        "current view: RTSV's candidates are trackable (criterion 3: at least one endpoint "
        "not occluded), so every tracked surface affords a point; the paper has no "
        "'uncertain endpoint' flag"
    ),
    "extraction.continuation_distance_m=0": (
        "an endpoint is occluded only where something nearer hides what lies beyond it "
        "(criterion 3: 'at least one endpoint that has not been occluded'); a wall thinning "
        "out at a grazing angle, its next beam farther along its own line, is not occluded "
        "(albot2d's own refinement, off here; the authors' code also counts the nearer end "
        "across any gap as real)"
    ),
    "move_using_pi=as_written": (
        "algorithm #4 as written: a view with no tracked surface left is placed by path "
        "integration; when it has no trackable surface either (line 8 tests S_t as "
        "update-maps sets it), every following view is remembered by path integration "
        "until one has more than three trackable surfaces"
    ),
}


class _ViewState(NamedTuple):
    """The previous view: what is needed to remember it one frame late (a tuple: one is
    made per view, and a frozen dataclass's constructor costs several times more)."""

    frame_index: int
    timestamp: float
    view: Surfaces
    pose_in_map: Pose
    tracked: TrackedSurfaces
    steps_in_map: int = 0


class Albot1:
    """Albot1 (the paper's robot) as a mapper; see the module docstring.

    Hooks, for checks and studies that watch the mapper without changing it:
    ``on_update`` is called with each global-map ``UpdateReport`` (e.g. to check invariants);
    ``on_view`` with each view as given, before it is processed (frame index, surfaces,
    odometry increment), so a check can recount tracking from the views themselves;
    ``on_localise`` with each ``Localisation`` of a view that becomes a local map.
    """

    name = "albot1"

    def __init__(
        self,
        params: Albot1Params | None = None,
        *,
        on_update: Callable[[UpdateReport, LocalMap], None] | None = None,
        on_view: Callable[[int, Surfaces, Pose], None] | None = None,
        on_localise: Callable[[Localisation], None] | None = None,
    ) -> None:
        self.params = params or Albot1Params()
        self.on_localise = on_localise
        self.route = RouteMap()
        self.map = GlobalMap(self.params.global_map)
        self.timer = StageTimer()
        self.on_update = on_update
        self.on_view = on_view
        self.last_update: UpdateReport | None = None
        self._tracked: TrackedSurfaces | None = None
        self._prev: _ViewState | None = None
        self._use_vc = False  # the paper's Use-V(c) switch
        self._pi_mode = False  # inside algorithm #4's loop (move_using_pi="as_written")
        self._next_surface_id = 0
        self._frame_maps: list[int] = []
        self._frame_offsets: list[NDArray[np.float64]] = []
        self._views = self._triangulations = self._path_integrations = 0
        self._surface_headings = 0  # path integrations whose heading came from surfaces
        self.steps: list[StepRecord] = []
        self.update_log: list[UpdateSummary] = []

    # -- the protocol -------------------------------------------------------------
    def observe(self, frame: Frame) -> None:
        with self.timer.stage("extraction"):
            view = extract_surfaces(frame.scan, self.params.extraction)
        self.observe_perceived(frame, view)

    def perception(self) -> ExtractionParams:
        return self.params.extraction

    def observe_perceived(self, frame: Frame, view: Surfaces) -> None:
        self.observe_view(frame.index, frame.timestamp, view, frame.odom_increment)

    def pose(self) -> Pose:
        if not self._frame_maps:
            return Pose()
        return self.route[self._frame_maps[-1]].pose @ Pose.from_array(self._frame_offsets[-1])

    def global_map(self, at_update: int | None = None) -> MapSnapshot:
        return self.map.snapshot(at_update)

    def route_map(self) -> RouteMap:
        return self.route

    def trajectory(self) -> NDArray[np.float64]:
        if not self._frame_maps:
            return np.zeros((0, 3))
        chain = np.array([m.pose.as_array() for m in self.route])
        return compose_arrays(chain[np.asarray(self._frame_maps)], np.asarray(self._frame_offsets))

    def counts(self) -> MapperCounts:
        return MapperCounts(
            self._views, len(self.route), self._triangulations, self._path_integrations
        )

    def timings_ms(self) -> dict[str, float]:
        return self.timer.mean_ms_per(self._views)

    @property
    def tracked(self) -> TrackedSurfaces | None:
        """The surfaces still tracked after the latest view (their ids, their geometry in
        the current local map's frame and in that view's); ``None`` before the first view."""
        return self._tracked

    # -- algorithm #2 (main loop), #3 (update-maps), #4 (move-using-PI) --------------
    def observe_view(
        self, frame_index: int, timestamp: float, view: Surfaces, increment: Pose
    ) -> None:
        """Process one view whose surfaces are already extracted (the main loop's body)."""
        if self.on_view is not None:
            self.on_view(frame_index, view, increment)
        self._views += 1
        n_maps = len(self.route)
        prev = self._prev
        if prev is None or self._tracked is None:
            # Algorithm #2, initialisation: the first view starts the route map and M_G.
            self._update_maps(frame_index, timestamp, view, Pose(), "start", tracked=0)
            self.steps.append(StepRecord(frame_index, 0, False, (frame_index,), ("start",)))
            return
        use_vc = self._use_vc
        tracked_after = self._main_loop_step(frame_index, timestamp, view, increment, prev)
        if len(self.route) == n_maps:  # most views remember none
            self.steps.append(StepRecord(frame_index, tracked_after, use_vc, (), ()))
            return
        new = self.route.maps[n_maps:]
        self.steps.append(
            StepRecord(
                frame_index,
                tracked_after,
                use_vc,
                tuple(m.frame_index for m in new),
                tuple(m.method for m in new),
            )
        )

    def _main_loop_step(
        self,
        frame_index: int,
        timestamp: float,
        view: Surfaces,
        increment: Pose,
        prev: _ViewState,
    ) -> int:
        """Algorithm #2, lines 3–16, for the new view V(c); returns |S_t| after line 4."""
        assert self._tracked is not None
        need = self.params.min_tracked
        tparams = self.params.tracking
        pi_pose = prev.pose_in_map @ increment
        steps = prev.steps_in_map + 1
        if self._pi_mode:
            return self._move_using_pi_step(frame_index, timestamp, view, pi_pose)
        # Line 4: S_t ← RTSV(V_c, S_t, α, δ).
        with self.timer.stage("tracking"):
            tracked, _ = rtsv(self._tracked, view, increment, tparams)
        tracked_after = len(tracked)
        if len(tracked) >= need:
            # Line 5 does not fire: go on with views (lines 15–16).
            if self.params.localise_every_view:
                with self.timer.stage("localization"):
                    pi_pose = self._localise_between_updates(tracked, pi_pose, steps)
            self._keep_tracking(frame_index, timestamp, view, pi_pose, tracked, steps)
            return tracked_after

        if not self._use_vc:
            # Lines 6–7 with Use-V(c) false: triangulate V(c-1) from the surfaces tracked
            # at c-1 (there were >= 4) and remember it.
            with self.timer.stage("localization"):
                pose_prev, method = self.localise(prev.tracked, prev.pose_in_map, prev.steps_in_map)
            self._update_maps(
                prev.frame_index,
                prev.timestamp,
                prev.view,
                pose_prev,
                method,
                tracked=len(prev.tracked),
                replaces_last_frame=True,
            )
            assert self._tracked is not None  # set by _update_maps
            # Line 12 (goto 4): re-track V(c-1)'s surfaces into V(c).
            with self.timer.stage("tracking"):
                tracked, _ = rtsv(self._tracked, view, increment, tparams)
            pi_pose = increment
            steps = 1
            if len(tracked) >= need:
                self._keep_tracking(frame_index, timestamp, view, pi_pose, tracked, steps)
                return tracked_after

        # Lines 6–11 with Use-V(c) true (V(c-1) is already the current local map): remember
        # V(c) itself, triangulated from its 1–3 tracked surfaces, or, with none left, by
        # path integration (line 9: algorithm #4).
        with self.timer.stage("localization"):
            pose_c, method = self.localise(tracked, pi_pose, steps)
        self._update_maps(frame_index, timestamp, view, pose_c, method, tracked=len(tracked))
        rule = self.params.move_using_pi
        if rule == "as_written":
            # Line 8 tests S_t after line 7: update-maps (algorithm #3, line 2) has set it to
            # the trackable surfaces of the view just remembered, so algorithm #4 starts only
            # when that view has none ("when no trackable surfaces are in view"); with some,
            # line 11 goes on tracking from it.
            self._pi_mode = len(self._tracked) == 0
        elif rule == "on_lost_tracking":
            self._pi_mode = len(tracked) == 0  # S_t read as RTSV's result (line 4)
        return tracked_after

    def _move_using_pi_step(
        self, frame_index: int, timestamp: float, view: Surfaces, pi_pose: Pose
    ) -> int:
        """Algorithm #4, lines 2–10, for one view: S_t ← the view's trackable surfaces
        (line 5, no RTSV); the view is remembered by path integration (line 2 of the next
        round, or line 8 when it has more than three trackable surfaces, which ends the
        loop: "return ; to move using view navigation"). Returns |S_t|."""
        if self.on_localise is not None:
            empty = TrackedSurfaces.empty()
            self.on_localise(Localisation(empty, pi_pose, 1, pi_pose, "path_integration"))
        with self.timer.stage("tracking"):
            trackable = int(np.count_nonzero(trackable_mask(view, self.params.tracking)))
        self._update_maps(frame_index, timestamp, view, pi_pose, "path_integration", tracked=0)
        if trackable >= self.params.min_tracked:
            self._pi_mode = False
        return trackable

    def _keep_tracking(
        self,
        frame_index: int,
        timestamp: float,
        view: Surfaces,
        pose: Pose,
        tracked: TrackedSurfaces,
        steps: int,
    ) -> None:
        """Algorithm #2, lines 15–16: Use-V(c) ← false, V(c-1) ← V(c), next view."""
        self._tracked = tracked
        self._prev = _ViewState(frame_index, timestamp, view, pose, tracked, steps)
        self._use_vc = False
        self._place_frame(len(self.route) - 1, pose, replaces_last_frame=False)

    def _localise_between_updates(
        self, tracked: TrackedSurfaces, odometric: Pose, steps: int
    ) -> Pose:
        """The authors' per-view localisation (not in the paper): triangulate, but keep the
        odometric pose when the result is farther from it than the fallback thresholds."""
        pose = triangulate(
            tracked.local, tracked.current, odometric, self.params.triangulation, steps=steps,
            gate=self.pi_gate,
        )  # fmt: skip
        if pose is None:
            return odometric
        far = math.hypot(pose.x - odometric.x, pose.y - odometric.y)
        turn = abs(float(wrap_angle(pose.theta - odometric.theta)))
        if far > self.params.odometry_fallback_m or turn > math.radians(
            self.params.odometry_fallback_deg
        ):
            return odometric
        return pose

    def localise(self, tracked: TrackedSurfaces, pi_pose: Pose, steps: int) -> tuple[Pose, Method]:
        """Algorithm #2 line 6 (triangulate from the tracked surfaces) or, when none affords
        a pose, algorithm #4 line 1 (the pose reached by path integration); tells
        ``on_localise``."""
        pose, method = self._triangulate_or_move_using_pi(tracked, pi_pose, steps)
        if self.on_localise is not None:
            self.on_localise(Localisation(tracked, pi_pose, steps, pose, method))
        return pose, method

    def _triangulate_or_move_using_pi(
        self, tracked: TrackedSurfaces, pi_pose: Pose, steps: int
    ) -> tuple[Pose, Method]:
        if len(tracked):
            pose = triangulate(
                tracked.local, tracked.current, pi_pose, self.params.triangulation,
                steps=steps, gate=self.pi_gate,
            )  # fmt: skip
            if pose is not None:
                return pose, "triangulation"
            if self.params.heading_fallback_surfaces > 0:
                heading = heading_from_directions(
                    tracked.local, tracked.current, pi_pose, self.params.triangulation,
                    steps=steps, gate=self.pi_gate,
                    min_agreeing=self.params.heading_fallback_surfaces,
                )  # fmt: skip
                if heading is not None:
                    self._surface_headings += 1
                    return Pose(pi_pose.x, pi_pose.y, heading), "path_integration"
        return pi_pose, "path_integration"

    @property
    def pi_gate(self) -> tuple[float, float]:
        """Affordances farther from path integration than RTSV's own recognition thresholds
        per step are dropped (``TriangulationParams.max_pi_deviation_*``; ``None`` there
        means these)."""
        t = self.params.tracking
        return t.match_distance_m, t.match_angle_deg

    def _update_maps(
        self,
        frame_index: int,
        timestamp: float,
        view: Surfaces,
        pose_in_previous: Pose,
        method: Method,
        *,
        tracked: int,
        replaces_last_frame: bool = False,
    ) -> None:
        """Algorithm #3 (update-maps): add the view to the route map (line 1), start tracking
        its trackable surfaces (line 2), and add it to the global map (lines 3–4: algorithm
        #5, update-global-map)."""
        lm = self.route.append(
            frame_index, view, pose_in_previous, method, tracked=tracked, timestamp=timestamp
        )
        if method == "triangulation":
            self._triangulations += 1
        elif method == "path_integration":
            self._path_integrations += 1
        with self.timer.stage("global_map"):
            segs = transform_segments_fast(lm.pose, view.segments)
            report = self.map.add_view(segs, lm.map_id, lm.pose)
        self.last_update = report
        self.update_log.append(
            UpdateSummary(
                lm.map_id,
                frame_index,
                report.deleted_current,
                report.deleted_older,
                min(report.affected_maps, default=-1),
            )
        )
        if self.on_update is not None:
            self.on_update(report, lm)
        with self.timer.stage("tracking"):
            self._tracked = start_tracking(view, self.params.tracking, self._next_surface_id)
        self._next_surface_id += len(self._tracked)
        self._prev = _ViewState(frame_index, timestamp, view, Pose(), self._tracked)
        # Algorithm #2 line 11 / #4 line 12: the next update, if any, uses V(c).
        self._use_vc = True
        self._place_frame(lm.map_id, Pose(), replaces_last_frame=replaces_last_frame)

    def _place_frame(self, map_id: int, pose_in_map: Pose, *, replaces_last_frame: bool) -> None:
        """Record a frame's place for ``trajectory()``: its local map and pose in it. A view
        remembered one frame late (V(c-1)) replaces that frame's earlier placement."""
        if replaces_last_frame and self._frame_maps:
            self._frame_maps[-1] = map_id
            self._frame_offsets[-1] = pose_in_map.as_array()
        else:
            self._frame_maps.append(map_id)
            self._frame_offsets.append(pose_in_map.as_array())
