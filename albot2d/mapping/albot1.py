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

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from albot2d.frames import Frame
from albot2d.geometry import Pose, compose_arrays, transform_segments
from albot2d.mapping.global_map import GlobalMap, GlobalMapParams, MapSnapshot, UpdateReport
from albot2d.mapping.protocol import MapperCounts, StageTimer
from albot2d.mapping.route_map import LocalMap, Method, RouteMap
from albot2d.mapping.triangulation import TriangulationParams, triangulate
from albot2d.perception import (
    ExtractionParams,
    TrackedSurfaces,
    TrackingParams,
    extract_surfaces,
    rtsv,
    start_tracking,
)
from albot2d.perception.surfaces import Surfaces
from albot2d.validation import check_positive_int

__all__ = ["Albot1", "Albot1Params", "StepRecord"]


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


@dataclass(frozen=True, slots=True)
class Albot1Params:
    """All of Albot1's parameters; defaults are the paper's values where it gives them.

    ``min_tracked``: a new local map is remembered when fewer than this many tracked
    surfaces remain (paper: four).
    """

    extraction: ExtractionParams = field(default_factory=ExtractionParams)
    tracking: TrackingParams = field(default_factory=TrackingParams)
    triangulation: TriangulationParams = field(default_factory=TriangulationParams)
    global_map: GlobalMapParams = field(default_factory=GlobalMapParams)
    min_tracked: int = 4

    def __post_init__(self) -> None:
        check_positive_int(self, "min_tracked")


@dataclass(frozen=True, eq=False)
class _ViewState:
    """The previous view: what is needed to remember it one frame late."""

    frame_index: int
    timestamp: float
    view: Surfaces
    pose_in_map: Pose
    tracked: TrackedSurfaces
    steps_in_map: int = 0


class Albot1:
    """Albot1 (the paper's robot) as a mapper; see the module docstring.

    ``on_update`` is called with each global-map ``UpdateReport`` (e.g. to check invariants).
    """

    name = "albot1"

    def __init__(
        self,
        params: Albot1Params | None = None,
        *,
        on_update: Callable[[UpdateReport, LocalMap], None] | None = None,
    ) -> None:
        self.params = params or Albot1Params()
        self.route = RouteMap()
        self.map = GlobalMap(self.params.global_map)
        self.timer = StageTimer()
        self.on_update = on_update
        self.last_update: UpdateReport | None = None
        self._tracked: TrackedSurfaces | None = None
        self._prev: _ViewState | None = None
        self._prev_is_map = False
        self._next_surface_id = 0
        self._frame_maps: list[int] = []
        self._frame_offsets: list[NDArray[np.float64]] = []
        self._views = self._triangulations = self._path_integrations = 0
        self.steps: list[StepRecord] = []

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

    # -- algorithms #2-#4 ----------------------------------------------------------
    def observe_view(
        self, frame_index: int, timestamp: float, view: Surfaces, increment: Pose
    ) -> None:
        """Process one view whose surfaces are already extracted (the main loop's body)."""
        self._views += 1
        n_maps = len(self.route)
        prev = self._prev
        if prev is None or self._tracked is None:
            self._remember(frame_index, timestamp, view, Pose(), "start", tracked=0)
            self.steps.append(StepRecord(frame_index, 0, False, (frame_index,), ("start",)))
            return
        use_vc = self._prev_is_map
        tracked_after = self._step(frame_index, timestamp, view, increment, prev)
        new = self.route.maps[n_maps:]
        self.steps.append(
            StepRecord(
                frame_index, tracked_after, use_vc,
                tuple(m.frame_index for m in new), tuple(m.method for m in new),
            )
        )

    def _step(
        self, frame_index: int, timestamp: float, view: Surfaces, increment: Pose,
        prev: _ViewState,
    ) -> int:
        """One pass of the main loop; returns the tracked count after the first RTSV."""
        assert self._tracked is not None
        need = self.params.min_tracked
        tparams = self.params.tracking
        pi_pose = prev.pose_in_map @ increment
        steps = prev.steps_in_map + 1
        with self.timer.stage("tracking"):
            tracked, _ = rtsv(self._tracked, view, increment, tparams)
        tracked_after = len(tracked)
        if len(tracked) >= need:
            self._continue(frame_index, timestamp, view, pi_pose, tracked, steps)
            return tracked_after

        if not self._prev_is_map:
            # Remember V(c-1): it still had >= 4 tracked surfaces to triangulate from.
            with self.timer.stage("localization"):
                pose_prev, method = self._localise(
                    prev.tracked, prev.pose_in_map, prev.steps_in_map
                )
            self._remember(
                prev.frame_index, prev.timestamp, prev.view, pose_prev, method,
                tracked=len(prev.tracked), replaces_last_frame=True,
            )
            assert self._tracked is not None  # set by _remember
            with self.timer.stage("tracking"):
                tracked, _ = rtsv(self._tracked, view, increment, tparams)
            pi_pose = increment
            steps = 1
            if len(tracked) >= need:
                self._continue(frame_index, timestamp, view, pi_pose, tracked, steps)
                return tracked_after

        # Use-Vc: V(c-1) is the current local map, so remember V(c) itself.
        with self.timer.stage("localization"):
            pose_c, method = self._localise(tracked, pi_pose, steps)
        self._remember(frame_index, timestamp, view, pose_c, method, tracked=len(tracked))
        return tracked_after

    def _continue(
        self, frame_index: int, timestamp: float, view: Surfaces, pose: Pose,
        tracked: TrackedSurfaces, steps: int,
    ) -> None:
        self._tracked = tracked
        self._prev = _ViewState(frame_index, timestamp, view, pose, tracked, steps)
        self._prev_is_map = False
        self._frame_maps.append(len(self.route) - 1)
        self._frame_offsets.append(pose.as_array())

    def _localise(
        self, tracked: TrackedSurfaces, pi_pose: Pose, steps: int
    ) -> tuple[Pose, Method]:
        """Triangulate from tracked surfaces; fall back to path integration (algorithm #4)."""
        if len(tracked):
            pose = triangulate(
                tracked.local, tracked.current, pi_pose, self.params.triangulation, steps=steps
            )
            if pose is not None:
                return pose, "triangulation"
        return pi_pose, "path_integration"

    def _remember(
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
        """Algorithm #3 (update-maps): add the view to the route map and the global map,
        and start tracking its trackable surfaces."""
        lm = self.route.append(
            frame_index, view, pose_in_previous, method, tracked=tracked, timestamp=timestamp
        )
        if method == "triangulation":
            self._triangulations += 1
        elif method == "path_integration":
            self._path_integrations += 1
        with self.timer.stage("global_map"):
            segs = transform_segments(lm.pose.as_array(), view.segments)
            report = self.map.add_view(segs, lm.map_id, lm.pose)
        self.last_update = report
        if self.on_update is not None:
            self.on_update(report, lm)
        with self.timer.stage("tracking"):
            self._tracked = start_tracking(view, self.params.tracking, self._next_surface_id)
        self._next_surface_id += len(self._tracked)
        self._prev = _ViewState(frame_index, timestamp, view, Pose(), self._tracked)
        self._prev_is_map = True
        if replaces_last_frame and self._frame_maps:
            self._frame_maps[-1] = lm.map_id
            self._frame_offsets[-1] = np.zeros(3)
        else:
            self._frame_maps.append(lm.map_id)
            self._frame_offsets.append(np.zeros(3))
