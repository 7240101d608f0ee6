"""A run or replay logged to Rerun (``rerun-sdk``, the ``[rerun]`` extra), live or to a file.

``RerunLog`` is driven by the run's own callbacks (``on_start``, ``on_mappers``,
``on_frame``, then ``finish``), so a live viewer follows the run as it is mapped; the
same calls write an ``.rrd`` recording (``--rerun-save``). Two timelines: ``view`` (the
frame index) and ``time`` (seconds since the first frame: simulated time, or the log's).

Entities, all in one 2D frame: the world frame with the truth (each mapper anchored at the
first true pose, as in the exports), else the frame of the first view:

- ``world/walls`` (static): the true walls and clutter outlines; ``world/tour`` the tour's
  waypoints;
- ``world/robot`` (the true pose, an arrow per view) and ``world/true_path`` (the true
  path so far);
- ``scan``: each view's laser hits (at the true pose; on a real log at the estimate of
  the first mapper);
- per mapper ``NAME``: ``mappers/NAME/pose`` and ``mappers/NAME/path`` (its estimate),
  ``mappers/NAME/map`` (its global map, every ``maps_every_m`` of travel and at the end);
- a view-based mapper (Albot1) also ``mappers/NAME/view`` (the current view's surfaces,
  at its estimated pose), ``mappers/NAME/tracked`` (the surfaces it still tracks),
  ``mappers/NAME/route`` and ``mappers/NAME/route/views`` (its route map: the remembered
  views' poses, joined in order) and ``mappers/NAME/map`` when its global map has been
  updated (a view remembered), at most every ``view_maps_every_m`` of travel.

Paths are logged every ``paths_every_m`` of travel (odometer) and at the end, maps as
above: what is logged grows with the distance driven, not with views × map size (a
282 m run remembers a view every 9 cm and keeps 60,000 surfaces in its naive map).
rerun is imported when a ``RerunLog`` is made.
"""

from __future__ import annotations

import os
import socket
import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any
from urllib.parse import urlparse

import numpy as np
from numpy.typing import NDArray

from albot2d.geometry import compose_arrays, transform_points, transform_segments

__all__ = ["DEFAULT_VIEWER_URL", "MISSING_EXTRA", "RerunLog", "viewer_listening"]

DEFAULT_VIEWER_URL = "rerun+http://127.0.0.1:9876/proxy"
MISSING_EXTRA = "--rerun needs the optional extra: pip install 'albot2d[rerun]'"
WALL_COLOR = (40, 40, 40)
TRUE_COLOR = (0, 0, 0)
SCAN_COLOR = (230, 60, 60)
MAPPER_COLORS = ((31, 119, 180), (44, 160, 44), (148, 103, 189), (255, 127, 14),
                 (140, 86, 75), (227, 119, 194))  # fmt: skip

FloatArray = NDArray[np.float64]


def viewer_listening(url: str = DEFAULT_VIEWER_URL, timeout_s: float = 0.3) -> bool:
    """Whether something accepts connections at the viewer URL's host and port."""
    parsed = urlparse(url.replace("rerun+", "", 1))
    host, port = parsed.hostname or "127.0.0.1", parsed.port or 9876
    try:
        with socket.create_connection((host, port), timeout=timeout_s):
            return True
    except OSError:
        return False


def _strips(segments: FloatArray) -> FloatArray:
    return np.asarray(segments, dtype=np.float64).reshape(-1, 2, 2)


class RerunLog:
    """Logs a run to a Rerun recording (see the module docstring).

    ``save``: an ``.rrd`` path; ``live``: stream to a viewer, the one listening at ``url``
    or else a viewer spawned for it (``spawn=False``: connect only).
    """

    def __init__(
        self,
        name: str,
        *,
        save: str | None = None,
        live: bool = False,
        url: str | None = None,
        spawn: bool = True,
        paths_every_m: float = 1.0,
        maps_every_m: float = 10.0,
        view_maps_every_m: float = 0.5,
    ) -> None:
        try:
            import rerun as rr
        except ImportError as exc:
            raise ImportError(MISSING_EXTRA) from exc
        self.rr: Any = rr
        self.rec: Any = rr.RecordingStream("albot2d")
        self.rec.send_recording_name(name)
        sinks: list[Any] = []
        self.save: Path | None = None
        self.partial: Path | None = None
        if save is not None:  # written beside it, renamed into place when the run ends well
            self.save = Path(save)
            fd, tmp = tempfile.mkstemp(prefix=f".{self.save.name}.", suffix=".tmp",
                                       dir=self.save.parent)  # fmt: skip
            mask = os.umask(0o022)
            os.umask(mask)
            os.fchmod(fd, 0o666 & ~mask)  # as open() would make it, not mkstemp's 0600
            os.close(fd)
            self.partial = Path(tmp)
            sinks.append(rr.FileSink(str(self.partial)))
        if live:
            target = url or DEFAULT_VIEWER_URL
            if spawn and url is None and not viewer_listening(target):
                rr.spawn(connect=False)  # a viewer of our own, listening at the default URL
            sinks.append(rr.GrpcSink(target))
        if sinks:
            self.rec.set_sinks(*sinks)
        self.paths_every_m = paths_every_m
        self.maps_every_m = maps_every_m
        self.view_maps_every_m = view_maps_every_m
        self.next_path_m = 0.0
        self.next_map_m = 0.0
        self.next_view_map_m: dict[str, float] = {}
        self.start: FloatArray | None = None
        self.mappers: dict[str, Any] = {}
        self.colors: dict[str, tuple[int, int, int]] = {}
        self.route_lengths: dict[str, int] = {}
        self.view_based: set[str] = set()
        self.views: dict[str, Any] = {}
        self.true_path: list[tuple[float, float]] = []
        self.first_time: float | None = None
        self.rows = 0
        self.scans = 0

    # -- the run's callbacks ------------------------------------------------------------
    def on_start(self, world: Any, tour: Any = None) -> None:
        rr = self.rr
        walls = _strips(world.obstacle_segments)
        self.rec.log("world/walls", rr.LineStrips2D(walls, colors=WALL_COLOR, radii=0.03),
                     static=True)  # fmt: skip
        if tour is not None and len(tour.waypoints):
            self.rec.log("world/tour", rr.LineStrips2D([np.asarray(tour.waypoints)[:, :2]],
                         colors=(180, 180, 180), radii=0.02), static=True)  # fmt: skip

    def on_mappers(self, mappers: Mapping[str, Any]) -> None:
        from albot2d.mapping.protocol import ViewBasedMapper

        self.mappers = dict(mappers)
        for k, (name, mapper) in enumerate(self.mappers.items()):
            self.colors[name] = MAPPER_COLORS[k % len(MAPPER_COLORS)]
            self.route_lengths[name] = 0
            if isinstance(mapper, ViewBasedMapper):
                self.view_based.add(name)
                if hasattr(mapper, "on_view"):
                    self._watch_views(name, mapper)

    def _watch_views(self, name: str, mapper: Any) -> None:
        """Keep the latest view given to a view-based mapper (chaining any hook it has)."""
        previous = mapper.on_view

        def on_view(frame_index: int, view: Any, increment: Any) -> None:
            self.views[name] = view
            if previous is not None:
                previous(frame_index, view, increment)

        mapper.on_view = on_view

    def on_frame(self, frame: Any, travelled_m: float) -> None:
        rr, rec = self.rr, self.rec
        if self.first_time is None:
            self.first_time = float(frame.timestamp)
            if frame.true_pose is not None:
                self.start = frame.true_pose.as_array()
        rec.set_time("view", sequence=int(frame.index))
        rec.set_time("time", duration=float(frame.timestamp) - self.first_time)
        paths_due = travelled_m >= self.next_path_m
        if paths_due:
            self.next_path_m = travelled_m + self.paths_every_m
        maps_due = travelled_m >= self.next_map_m
        if maps_due:
            self.next_map_m = travelled_m + self.maps_every_m
        if frame.true_pose is not None:
            true = frame.true_pose.as_array()
            self.true_path.append((float(true[0]), float(true[1])))
            rec.log("world/robot", self._arrow(true, TRUE_COLOR))
            if paths_due:
                rec.log("world/true_path", rr.LineStrips2D([np.array(self.true_path)],
                                                      colors=TRUE_COLOR, radii=0.02))  # fmt: skip
            hits = frame.world_hits()
        else:
            first = next(iter(self.mappers.values()), None)
            pose = self._anchored_pose(first) if first is not None else np.zeros(3)
            hits = transform_points(pose, frame.scan.points())
        rec.log("scan", rr.Points2D(hits, colors=SCAN_COLOR, radii=0.03))
        self.scans += 1
        for name, mapper in self.mappers.items():
            self._log_mapper(name, mapper, travelled_m, paths_due, maps_due)
        self.rows += 1

    def finish(self, ok: bool = True) -> None:
        """Log every path and map as they end and close the recording; ``ok=False`` (the
        run failed): close it and remove the unfinished file."""
        if not ok:
            self.close(keep=False)
            return
        rr = self.rr
        if self.true_path:
            self.rec.log("world/true_path", rr.LineStrips2D([np.array(self.true_path)],
                                                       colors=TRUE_COLOR, radii=0.02))  # fmt: skip
        for name, mapper in self.mappers.items():
            self._log_path(name, mapper)
            self._log_map(name, mapper)
            if name in self.view_based:
                self._log_route(name, mapper)
        self.close()

    def close(self, keep: bool = True) -> None:
        self.rec.flush()
        self.rec.disconnect()
        if self.partial is not None and self.save is not None:
            if keep:
                os.replace(self.partial, self.save)
            else:
                self.partial.unlink(missing_ok=True)
            self.partial = None

    # -- helpers --------------------------------------------------------------------------
    def _anchor_poses(self, poses: FloatArray) -> FloatArray:
        p = np.asarray(poses, dtype=np.float64).reshape(-1, 3)
        return p if self.start is None or not len(p) else compose_arrays(self.start, p)

    def _anchor_segments(self, segments: FloatArray) -> FloatArray:
        s = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
        return s if self.start is None else transform_segments(self.start, s)

    def _anchored_pose(self, mapper: Any) -> FloatArray:
        return self._anchor_poses(mapper.pose().as_array())[0]

    def _arrow(self, pose: FloatArray, color: tuple[int, int, int]) -> Any:
        x, y, theta = (float(v) for v in pose)
        return self.rr.Arrows2D(origins=[[x, y]], vectors=[[0.6 * np.cos(theta),
                                0.6 * np.sin(theta)]], colors=color, radii=0.04)  # fmt: skip

    def _log_path(self, name: str, mapper: Any) -> None:
        path = self._anchor_poses(mapper.trajectory())
        if len(path):
            self.rec.log(f"mappers/{name}/path", self.rr.LineStrips2D([path[:, :2]],
                         colors=self.colors[name], radii=0.02))  # fmt: skip

    def _log_map(self, name: str, mapper: Any) -> None:
        segments = self._anchor_segments(mapper.global_map().segments)
        self.rec.log(f"mappers/{name}/map", self.rr.LineStrips2D(_strips(segments),
                     colors=self.colors[name], radii=0.03))  # fmt: skip

    def _log_mapper(
        self, name: str, mapper: Any, travelled_m: float, paths_due: bool, maps_due: bool
    ) -> None:
        from albot2d.mapping.albot1 import Albot1

        rr, rec, color = self.rr, self.rec, self.colors[name]
        pose = self._anchored_pose(mapper)
        rec.log(f"mappers/{name}/pose", self._arrow(pose, color))
        if paths_due:
            self._log_path(name, mapper)
        view = self.views.pop(name, None)
        if view is None:  # not a view-based mapper: its map now and then
            if maps_due:
                self._log_map(name, mapper)
            return
        rec.log(f"mappers/{name}/view", rr.LineStrips2D(_strips(transform_segments(pose,
                view.segments)), colors=(255, 160, 0), radii=0.04))  # fmt: skip
        tracked = mapper.tracked if isinstance(mapper, Albot1) else None
        if tracked is not None:
            rec.log(f"mappers/{name}/tracked", rr.LineStrips2D(_strips(transform_segments(pose,
                    tracked.current.segments)), colors=(220, 20, 120), radii=0.05))  # fmt: skip
        route = mapper.route_map()
        due = travelled_m >= self.next_view_map_m.get(name, 0.0)
        if len(route) != self.route_lengths[name] and due:  # views remembered: map changed
            self.next_view_map_m[name] = travelled_m + self.view_maps_every_m
            self._log_route(name, mapper)
            self._log_map(name, mapper)

    def _log_route(self, name: str, mapper: Any) -> None:
        rr, color = self.rr, self.colors[name]
        route = mapper.route_map()
        self.route_lengths[name] = len(route)
        if not len(route):
            return
        poses = self._anchor_poses(np.array([m.pose.as_array() for m in route]))
        self.rec.log(
            f"mappers/{name}/route", rr.LineStrips2D([poses[:, :2]], colors=color, radii=0.015)
        )
        self.rec.log(
            f"mappers/{name}/route/views", rr.Points2D(poses[:, :2], colors=color, radii=0.06)
        )
