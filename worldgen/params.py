"""Frozen, validated parameter dataclasses for each procedural world kind.

Every field is named with its unit; ``__post_init__`` rejects NaN, negative, inverted
ranges and sizes too small for the kind, naming the field and the value. Fields that
multiply the work of generating or simulating a world are capped by named maxima
(:data:`MAX_WORLD_SIZE_M`, :data:`MAX_DYNAMIC_OBSTACLES`, ...): generation time grows
faster than the area (a 200 m world takes about 1.5 s, a 1000 m one minutes).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from albot2d import limits as _limits
from albot2d.errors import InputError
from albot2d.validation import (
    check_at_most,
    check_finite,
    check_in_range,
    check_non_negative,
    check_positive,
)

__all__ = [
    "MAX_CLUTTER_PER_10M2",
    "MAX_DYNAMIC_OBSTACLES",
    "MAX_PART_COUNT",
    "MAX_ROBOT_RADIUS_M",
    "MAX_WORLD_SIZE_M",
    "CommonParams",
    "CorridorsParams",
    "Fig6Params",
    "MixedParams",
    "OfficeParams",
    "OpenParams",
    "RoomsParams",
    "passage_width_m",
]

#: Largest world width or height (metres) a generator accepts.
MAX_WORLD_SIZE_M = _limits.MAX_WORLD_SIZE_M
#: Most moving obstacles a world may hold (generated or read from a file).
MAX_DYNAMIC_OBSTACLES = _limits.MAX_DYNAMIC_OBSTACLES
#: Densest clutter a generator places (items per 10 m² of floor).
MAX_CLUTTER_PER_10M2 = 5.0
#: Most hall parts, partition walls or open areas a generator lays out.
MAX_PART_COUNT = 50
#: Largest robot radius (metres) a world may be made for.
MAX_ROBOT_RADIUS_M = 5.0

# A doorway or gap must let the robot's disc through with its node clearance on both sides.
_GAP_SLACK_M = 0.02
_APPROACH_EXTRA_M = 0.15
_LANE_EXTRA_M = 0.10


def passage_width_m(robot_radius_m: float, clearance_margin_m: float) -> float:
    """The narrowest gap a roadmap node can sit in: twice the node clearance plus slack."""
    return 2.0 * (robot_radius_m + clearance_margin_m) + _GAP_SLACK_M


def _check_count(obj: object, name: str) -> None:
    value = getattr(obj, name)
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise InputError(f"{type(obj).__name__}.{name} must be an integer >= 0, got {value!r}")


def _check_count_at_most(obj: object, name: str, maximum: int) -> None:
    _check_count(obj, name)
    if getattr(obj, name) > maximum:
        raise InputError(
            f"{type(obj).__name__}.{name} must be <= {maximum} (a cap on the work), "
            f"got {getattr(obj, name)!r}"
        )


def _check_order(obj: object, low: str, high: str) -> None:
    if getattr(obj, low) > getattr(obj, high):
        raise InputError(
            f"{type(obj).__name__}.{low} ({getattr(obj, low)!r}) must be <= "
            f"{high} ({getattr(obj, high)!r})"
        )


def _check_ranges(obj: object, *pairs: tuple[str, str]) -> None:
    """Each ``(low, high)`` pair of fields: both positive, low <= high."""
    for low, high in pairs:
        check_positive(obj, low, high)
        _check_order(obj, low, high)


def _check_at_least(obj: object, name: str, minimum: float, why: str) -> None:
    value = check_finite(obj, name)
    if value < minimum:
        raise InputError(
            f"{type(obj).__name__}.{name} must be >= {minimum:.2f} m {why}, got {value!r}"
        )


@dataclass(frozen=True)
class CommonParams:
    """Fields every kind shares: size, robot, clutter, moving obstacles."""

    width_m: float = 40.0
    height_m: float = 40.0
    robot_radius_m: float = 0.25
    clearance_margin_m: float = 0.10
    wall_thickness_m: float = 0.15
    clutter_per_10m2: float = 0.3
    dynamic_obstacles: int = 0

    min_size_m = 10.0  # class constant, overridden per kind

    def __post_init__(self) -> None:
        check_positive(self, "width_m", "height_m", "robot_radius_m", "wall_thickness_m")
        check_non_negative(self, "clearance_margin_m", "clutter_per_10m2")
        check_in_range(self, "wall_thickness_m", 0.05, 1.0)
        _check_count_at_most(self, "dynamic_obstacles", MAX_DYNAMIC_OBSTACLES)
        check_at_most(self, "robot_radius_m", MAX_ROBOT_RADIUS_M)
        check_at_most(self, "clearance_margin_m", MAX_ROBOT_RADIUS_M)
        check_at_most(self, "clutter_per_10m2", MAX_CLUTTER_PER_10M2, "a cap on the work")
        for spec in dataclasses.fields(self):  # no length may exceed the largest world
            if spec.name.endswith("_m"):
                check_at_most(self, spec.name, MAX_WORLD_SIZE_M, "a cap on the work")
        kind = type(self).__name__.removesuffix("Params").lower()
        for name in ("width_m", "height_m"):
            _check_at_least(self, name, self.min_size_m, f"for {kind} worlds")

    @property
    def passage_m(self) -> float:
        return passage_width_m(self.robot_radius_m, self.clearance_margin_m)

    @property
    def node_clearance_m(self) -> float:
        """Clearance every roadmap node keeps: robot radius plus margin."""
        return self.robot_radius_m + self.clearance_margin_m

    @property
    def approach_m(self) -> float:
        """How far in front of a door its approach points (roadmap nodes) sit."""
        return self.node_clearance_m + _APPROACH_EXTRA_M

    @property
    def lane_half_width_m(self) -> float:
        """Half width of the clutter-free lanes that carry roadmap links through rooms."""
        return self.node_clearance_m + _LANE_EXTRA_M


@dataclass(frozen=True)
class _DoorParams(CommonParams):
    door_width_min_m: float = 0.8
    door_width_max_m: float = 1.2

    def __post_init__(self) -> None:
        super().__post_init__()
        _check_ranges(self, ("door_width_min_m", "door_width_max_m"))
        _check_at_least(self, "door_width_min_m", self.passage_m, "to let the robot through")


@dataclass(frozen=True)
class CorridorsParams(CommonParams):
    """A grid-like corridor network with junctions, corners, dead ends and loops."""

    corridor_width_min_m: float = 1.5
    corridor_width_max_m: float = 3.0
    junction_spacing_min_m: float = 6.0
    junction_spacing_max_m: float = 14.0
    prune_fraction: float = 0.35
    extra_link_fraction: float = 0.2
    clutter_per_10m2: float = 0.05

    min_size_m = 11.0

    def __post_init__(self) -> None:
        super().__post_init__()
        _check_ranges(self, ("corridor_width_min_m", "corridor_width_max_m"))
        _check_at_least(self, "corridor_width_min_m", self.passage_m, "to let the robot through")
        _check_ranges(self, ("junction_spacing_min_m", "junction_spacing_max_m"))
        _check_at_least(
            self,
            "junction_spacing_min_m",
            self.corridor_width_max_m + 2.0,
            "(corridor_width_max_m + 2 m, so parallel corridors stay apart)",
        )
        check_in_range(self, "prune_fraction", 0.0, 0.9)
        check_in_range(self, "extra_link_fraction", 0.0, 1.0)
        need = self.junction_spacing_min_m + self.corridor_width_max_m + 2.0
        for name in ("width_m", "height_m"):
            _check_at_least(self, name, need, "(two junction rows are needed for a loop)")


@dataclass(frozen=True)
class RoomsParams(_DoorParams):
    """Rooms of varied sizes (binary space partition) joined by doorways."""

    room_size_min_m: float = 3.0
    room_size_max_m: float = 9.0
    extra_door_fraction: float = 0.3

    min_size_m = 6.5

    def __post_init__(self) -> None:
        super().__post_init__()
        _check_ranges(self, ("room_size_min_m", "room_size_max_m"))
        _check_at_least(
            self,
            "room_size_min_m",
            self.door_width_max_m + self.wall_thickness_m + 1.0,
            "(a door and its jambs must fit in the smallest wall)",
        )
        check_in_range(self, "extra_door_fraction", 0.0, 1.0)
        two_rooms = 2.0 * self.room_size_min_m + self.wall_thickness_m
        _check_at_least(self, "width_m", two_rooms, "(two rooms must fit side by side)")


@dataclass(frozen=True)
class OpenParams(CommonParams):
    """Large halls with irregular outlines, pillars and furniture."""

    hall_parts: int = 4
    chamfer_fraction: float = 0.4
    partition_walls: int = 2
    pillar_spacing_m: float = 8.0
    pillar_size_m: float = 0.5
    wall_thickness_m: float = 0.2
    clutter_per_10m2: float = 0.2

    min_size_m = 10.0

    def __post_init__(self) -> None:
        super().__post_init__()
        _check_count_at_most(self, "hall_parts", MAX_PART_COUNT)
        if self.hall_parts < 1:
            raise InputError(f"OpenParams.hall_parts must be >= 1, got {self.hall_parts!r}")
        _check_count_at_most(self, "partition_walls", MAX_PART_COUNT)
        check_in_range(self, "chamfer_fraction", 0.0, 1.0)
        check_non_negative(self, "pillar_spacing_m")
        check_in_range(self, "pillar_size_m", 0.1, 2.0)
        if 0.0 < self.pillar_spacing_m < self.pillar_size_m + 2.0 * self.passage_m:
            raise InputError(
                f"OpenParams.pillar_spacing_m must be 0 (no pillars) or >= "
                f"{self.pillar_size_m + 2.0 * self.passage_m:.2f} m, got {self.pillar_spacing_m!r}"
            )


@dataclass(frozen=True)
class OfficeParams(_DoorParams):
    """A corridor ring with rooms on both sides, cross corridors and an open area."""

    width_m: float = 60.0
    height_m: float = 40.0
    corridor_width_min_m: float = 1.8
    corridor_width_max_m: float = 2.4
    room_depth_min_m: float = 4.0
    room_depth_max_m: float = 6.5
    room_width_min_m: float = 3.0
    room_width_max_m: float = 6.0
    block_length_max_m: float = 40.0
    open_areas: int = 1
    extra_door_fraction: float = 0.15

    min_size_m = 24.0

    def __post_init__(self) -> None:
        super().__post_init__()
        _check_ranges(self, ("corridor_width_min_m", "corridor_width_max_m"))
        _check_at_least(self, "corridor_width_min_m", self.passage_m, "to let the robot through")
        _check_ranges(
            self, ("room_depth_min_m", "room_depth_max_m"), ("room_width_min_m", "room_width_max_m")
        )
        small = self.door_width_max_m + self.wall_thickness_m + 1.0
        _check_at_least(self, "room_width_min_m", small, "(a door must fit in a room wall)")
        _check_at_least(self, "room_depth_min_m", small, "(a door must fit in a room wall)")
        _check_at_least(self, "block_length_max_m", 2.0 * self.room_width_max_m, "(two rooms)")
        _check_count_at_most(self, "open_areas", MAX_PART_COUNT)
        check_in_range(self, "extra_door_fraction", 0.0, 1.0)
        ring = 2.0 * (self.room_depth_max_m + self.corridor_width_max_m) + 2.0 * small
        for name in ("width_m", "height_m"):
            _check_at_least(self, name, ring, "(two room bands, a corridor ring and a core)")


@dataclass(frozen=True)
class MixedParams(_DoorParams):
    """Regions of corridors, rooms and open halls joined by a corridor spine."""

    width_m: float = 60.0
    height_m: float = 40.0
    regions: int = 3
    corridor_width_m: float = 2.0
    clutter_per_10m2: float = 0.2

    min_size_m = 32.0

    def __post_init__(self) -> None:
        super().__post_init__()
        _check_count(self, "regions")
        if not 2 <= self.regions <= 4:
            raise InputError(f"MixedParams.regions must be in [2, 4], got {self.regions!r}")
        check_in_range(self, "corridor_width_m", 1.5, 3.0)


@dataclass(frozen=True)
class Fig6Params(_DoorParams):
    """The paper's Fig. 6 building: a corridor ring with a cross corridor, rooms and a hall."""

    width_m: float = 42.0
    height_m: float = 30.0
    corridor_width_min_m: float = 1.8
    corridor_width_max_m: float = 2.4
    room_depth_min_m: float = 4.0
    room_depth_max_m: float = 6.0
    room_width_min_m: float = 3.0
    room_width_max_m: float = 5.5
    hall_depth_min_m: float = 8.0
    hall_depth_max_m: float = 11.0
    cross_offset_min_m: float = 5.5
    cross_offset_max_m: float = 7.0

    min_size_m = 30.0

    def __post_init__(self) -> None:
        super().__post_init__()
        _check_ranges(
            self,
            ("corridor_width_min_m", "corridor_width_max_m"),
            ("room_depth_min_m", "room_depth_max_m"),
            ("room_width_min_m", "room_width_max_m"),
            ("hall_depth_min_m", "hall_depth_max_m"),
            ("cross_offset_min_m", "cross_offset_max_m"),
        )
        _check_at_least(self, "corridor_width_min_m", self.passage_m, "to let the robot through")
        small = self.door_width_max_m + self.wall_thickness_m + 1.0
        _check_at_least(self, "room_width_min_m", small, "(a door must fit in a room wall)")
        _check_at_least(
            self,
            "cross_offset_min_m",
            self.corridor_width_max_m + small,
            "(a room between the left and the cross corridor)",
        )
        ring_w = 2.0 * self.room_depth_max_m + self.cross_offset_max_m + 2.0 * small + 6.0
        ring_h = self.room_depth_max_m + self.hall_depth_max_m + 2.0 * small + 4.0
        _check_at_least(self, "width_m", ring_w, "(room bands, the ring and the cross corridor)")
        _check_at_least(self, "height_m", ring_h, "(room band, hall, the ring and two rooms)")
