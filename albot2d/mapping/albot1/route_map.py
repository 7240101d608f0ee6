"""Albot1's route map: the list of remembered views with each view's pose in its predecessor.

The chain is always connected: every local map after the first has a pose in the
previous one (by triangulation or path integration), so composing the chain gives
every local map's pose in the first map's frame.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from albot2d.geometry import Pose, compose_arrays
from albot2d.perception.surfaces import Surfaces

__all__ = ["LocalMap", "Method", "RouteMap"]

Method = Literal["start", "triangulation", "path_integration"]


@dataclass(frozen=True, eq=False)
class LocalMap:
    """One remembered view.

    - ``map_id``: 0, 1, 2… in the order remembered.
    - ``frame_index``: index of the frame whose view this is.
    - ``view``: all surfaces of the view, in the view's own frame.
    - ``pose_in_previous``: the viewpoint's pose in the previous local map (identity for
      the first), found by ``method``.
    - ``pose``: the viewpoint's pose in the first local map (composed chain).
    - ``tracked``: how many tracked surfaces were left when it was localised.
    """

    map_id: int
    frame_index: int
    view: Surfaces
    pose_in_previous: Pose
    method: Method
    pose: Pose
    tracked: int = 0
    timestamp: float = 0.0

    def __repr__(self) -> str:
        return (
            f"LocalMap(map_id={self.map_id}, frame_index={self.frame_index}, "
            f"method={self.method!r}, pose={self.pose!r}, tracked={self.tracked}, "
            f"timestamp={self.timestamp:.6g}, view={self.view!r})"
        )


@dataclass(eq=False)
class RouteMap:
    """The list of local maps; append-only."""

    maps: list[LocalMap] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.maps)

    def __repr__(self) -> str:
        methods = [m.method for m in self.maps]
        counts = ", ".join(f"{methods.count(k)} {k}" for k in dict.fromkeys(methods))
        return f"RouteMap({len(self.maps)} local maps{': ' + counts if counts else ''})"

    def __iter__(self) -> Iterator[LocalMap]:
        return iter(self.maps)

    def __getitem__(self, i: int) -> LocalMap:
        return self.maps[i]

    def append(
        self,
        frame_index: int,
        view: Surfaces,
        pose_in_previous: Pose,
        method: Method,
        *,
        tracked: int = 0,
        timestamp: float = 0.0,
    ) -> LocalMap:
        pose = self.maps[-1].pose @ pose_in_previous if self.maps else pose_in_previous
        entry = LocalMap(
            len(self.maps), frame_index, view, pose_in_previous, method, pose, tracked, timestamp
        )
        self.maps.append(entry)
        return entry

    def relative_poses(self) -> NDArray[np.float64]:
        """``(L, 3)`` pose of each local map in its predecessor (row 0: identity/origin)."""
        return np.array([m.pose_in_previous.as_array() for m in self.maps]).reshape(-1, 3)

    def compose_chain(self) -> NDArray[np.float64]:
        """``(L, 3)`` pose of each local map in the first map's frame, composed afresh."""
        rel = self.relative_poses()
        out = np.empty_like(rel)
        acc = np.zeros(3)
        for i, r in enumerate(rel):
            acc = r if i == 0 else compose_arrays(acc, r)
            out[i] = acc
        return out

    def methods(self) -> list[Method]:
        return [m.method for m in self.maps]
