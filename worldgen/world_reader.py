"""Checks a parsed world-file document field by field and builds the ``World`` (for ``io.load``).

A wall that repeats another exactly is refused (many copies of one wall are the same world
with far more work); arrays in ``params``/``features`` have at most ``MAX_ARRAY_DIMENSIONS``
dimensions of ``MAX_ARRAY_ITEMS``. Every error is an ``InputError`` naming the source
file, the field path (``walls[17]``,
``free_space.holes[2]``) and the offending value. The format itself is described in
``worldgen.io``. Every number must be finite. With ``validate`` (the default, and what every
command uses) every coordinate and size must also lie within ±``COORDINATE_LIMIT_M`` (1e6 m)
and the world as a whole must be drivable (``worldgen.world_checks``: walls, start disc,
roadmap, moving obstacles, with named limits); ``validate=False`` reads any finite world
exactly as written, for format-level round trips.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import shapely

from albot2d.errors import InputError
from albot2d.geometry import Pose
from albot2d.limits import MAX_ARRAY_DIMENSIONS, MAX_ARRAY_ITEMS
from albot2d.validation import COORDINATE_LIMIT_M
from worldgen.world import DynamicObstacle, Roadmap, World
from worldgen.world_checks import world_problem

__all__ = ["ARRAY_DTYPES", "FORMAT_NAME", "FORMAT_VERSION", "TYPE_TAG", "WorldReader"]

FORMAT_NAME = "albot2d-world"
FORMAT_VERSION = 1
TYPE_TAG = "__type__"
_WORLD_KEYS = frozenset(
    [
        "format",
        "version",
        "kind",
        "seed",
        "robot_radius_m",
        "bounds",
        "start",
        "walls",
        "clutter",
        "free_space",
        "roadmap",
        "dynamic_obstacles",
        "params",
        "features",
    ]
)
_OBSTACLE_KEYS = frozenset({"kind", "shape", "pose", "path", "speed_m_s", "mass_kg"})
_OBSTACLE_KINDS = ("box", "person")
_INT_FLOAT_LIMIT = 1e300  # larger integers may not convert to a float64
ARRAY_DTYPES = frozenset(
    [
        "bool",
        "int8",
        "int16",
        "int32",
        "int64",
        "uint8",
        "uint16",
        "uint32",
        "uint64",
        "float16",
        "float32",
        "float64",
    ]
)


def _type_name(value: Any) -> str:
    return {dict: "an object", list: "a list", str: "a string", bool: "a boolean"}.get(
        type(value), "null" if value is None else "a number"
    )


def _short(value: Any, limit: int = 60) -> str:
    """``repr(value)`` cut to ``limit`` characters (a 5000-digit integer stays one short line)."""
    if type(value) is int and abs(value) > 10**40:
        return f"an integer of {len(str(abs(value)))} digits"
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _repeated_walls(walls: np.ndarray) -> tuple[int, int, int] | None:
    """``(k, j, n)``: wall ``k`` is the first that repeats an earlier wall ``j`` exactly
    (either direction), and ``n`` walls repeat one; ``None`` when no wall does.

    A repeated wall adds nothing to a world but work (hundreds of thousands of copies of
    one wall fill the raycast grid); no generated world has one.
    """
    if len(walls) < 2:
        return None
    x_flip = walls[:, 0] > walls[:, 2]
    flip = x_flip | ((walls[:, 0] == walls[:, 2]) & (walls[:, 1] > walls[:, 3]))
    canonical = np.where(flip[:, None], walls[:, [2, 3, 0, 1]], walls) + 0.0  # -0.0 → 0.0
    _, first, inverse = np.unique(canonical, axis=0, return_index=True, return_inverse=True)
    if len(first) == len(walls):
        return None
    owner = first[inverse.reshape(-1)]
    repeats = np.flatnonzero(owner != np.arange(len(walls)))
    k = int(repeats[0])
    return k, int(owner[k]), len(repeats)


class WorldReader:
    """Checks a parsed JSON document field by field; every error names ``source`` and the field."""

    def __init__(self, source: str, *, validate: bool = True) -> None:
        self.source = source
        self.validate = validate
        self.limit = COORDINATE_LIMIT_M if validate else math.inf

    def fail(self, message: str) -> InputError:
        return InputError(f"{self.source}: {message}")

    def obj(self, value: Any, field: str, keys: frozenset[str]) -> dict[str, Any]:
        if not isinstance(value, dict):
            raise self.fail(f"{field} must be an object, got {_type_name(value)}")
        missing = sorted(keys - value.keys())
        if missing:
            raise self.fail(f"{field} is missing {', '.join(missing)}")
        unknown = sorted(value.keys() - keys)
        if unknown:
            raise self.fail(f"{field} has unknown key(s) {', '.join(unknown)}")
        return value

    def number(self, value: Any, field: str, limit: float | None = None) -> float:
        """A finite number within ±``limit`` (default: the coordinate limit, if validating)."""
        limit = self.limit if limit is None else limit
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.fail(f"{field} must be a number, got {_short(value)}")
        try:
            number = float(value)
        except OverflowError:
            number = math.inf
        if not math.isfinite(number):
            raise self.fail(f"{field} must be finite, got {_short(value)}")
        if abs(number) > limit:
            raise self.fail(f"{field} is {_short(value)}, outside the limit of ±{limit:g}")
        return number

    def numbers(self, value: Any, field: str, count: int, what: str) -> list[float]:
        if not isinstance(value, list):
            raise self.fail(
                f"{field} must be a list of {count} numbers {what}, got {_short(value)}"
            )
        if len(value) != count:
            raise self.fail(f"{field} has {len(value)} numbers, expected {count} {what}")
        return [self.number(v, f"{field}[{i}]") for i, v in enumerate(value)]

    def rows(self, value: Any, field: str, cols: int, what: str) -> np.ndarray:
        """An ``(N, cols)`` float64 array from a list of rows, each row checked."""
        if not isinstance(value, list):
            raise self.fail(f"{field} must be a list of {what} rows, got {_type_name(value)}")
        for i, row in enumerate(value):
            if not isinstance(row, list) or len(row) != cols:
                got = f"{len(row)} numbers" if isinstance(row, list) else repr(row)
                raise self.fail(f"{field}[{i}] has {got}, expected {cols} {what}")
            for x in row:
                if type(x) is not float and type(x) is not int:
                    raise self.fail(f"{field}[{i}] must hold numbers, got {_short(x)}")
                if type(x) is int and abs(x) > min(self.limit, _INT_FLOAT_LIMIT):
                    limit = min(self.limit, _INT_FLOAT_LIMIT)
                    raise self.fail(
                        f"{field}[{i}] holds {_short(x)}, outside the limit of ±{limit:g}"
                    )
        arr = np.array(value, dtype=np.float64).reshape(-1, cols)
        bad = ~np.isfinite(arr)
        if bad.any():
            i = int(np.argwhere(bad)[0][0])
            raise self.fail(f"{field}[{i}] has a non-finite number: {_short(value[i])}")
        big = np.abs(arr) > self.limit
        if big.any():
            i = int(np.argwhere(big)[0][0])
            raise self.fail(
                f"{field}[{i}] is {_short(value[i])}, outside the limit of ±{self.limit:g}"
            )
        return arr

    def ring(self, value: Any, field: str) -> np.ndarray:
        arr = self.rows(value, field, 2, "[x, y]")
        if len({(x, y) for x, y in arr.tolist()}) < 3:
            raise self.fail(f"{field} needs at least 3 distinct points, got {len(arr)} points")
        return arr

    def polygon(self, value: Any, field: str) -> shapely.Polygon:
        if isinstance(value, list):
            raise self.fail(f"{field} must be one polygon (exterior + holes), got a list")
        doc = self.obj(value, field, frozenset({"exterior", "holes"}))
        exterior = self.ring(doc["exterior"], f"{field}.exterior")
        if not isinstance(doc["holes"], list):
            raise self.fail(f"{field}.holes must be a list of rings, got {_short(doc['holes'])}")
        holes = [self.ring(h, f"{field}.holes[{i}]") for i, h in enumerate(doc["holes"])]
        poly = shapely.Polygon(exterior, holes)
        if not poly.is_valid:
            reason = shapely.is_valid_reason(poly)
            raise self.fail(f"{field} is not one valid polygon: {reason}")
        return poly

    def world(self, doc: Any) -> World:
        if not isinstance(doc, dict):
            raise self.fail(f"expected a JSON object, got {_type_name(doc)}")
        if "format" not in doc:
            raise self.fail(f'not an albot2d world file (no "format": "{FORMAT_NAME}")')
        if doc["format"] != FORMAT_NAME:
            raise self.fail(f"format is {_short(doc['format'])}, expected {FORMAT_NAME!r}")
        version = doc.get("version")
        if type(version) is not int or version != FORMAT_VERSION:
            raise self.fail(
                f"version is {_short(version)}; this albot2d reads version {FORMAT_VERSION}"
            )
        doc = self.obj(doc, "the world", _WORLD_KEYS)
        kind = doc["kind"]
        if not isinstance(kind, str) or not kind:
            raise self.fail(f"kind must be a non-empty string, got {_short(kind)}")
        seed = doc["seed"]
        if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int) or seed < 0):
            raise self.fail(f"seed must be a non-negative integer or null, got {_short(seed)}")
        radius = self.number(doc["robot_radius_m"], "robot_radius_m")
        if radius <= 0.0:
            raise self.fail(f"robot_radius_m must be > 0, got {_short(radius)}")
        bounds = self.numbers(doc["bounds"], "bounds", 4, "[xmin, ymin, xmax, ymax]")
        if not (bounds[0] < bounds[2] and bounds[1] < bounds[3]):
            raise self.fail(f"bounds {bounds} need xmin < xmax and ymin < ymax")
        start = Pose(*self.numbers(doc["start"], "start", 3, "[x, y, theta]"))
        walls = self.rows(doc["walls"], "walls", 4, "[x1, y1, x2, y2]")
        repeat = _repeated_walls(walls) if self.validate else None
        if repeat is not None:
            k, j, n = repeat
            raise self.fail(
                f"walls[{k}] repeats walls[{j}] exactly ({n} walls repeat another); "
                "remove the repeats"
            )
        if not isinstance(doc["clutter"], list):
            raise self.fail(f"clutter must be a list of polygons, got {_type_name(doc['clutter'])}")
        clutter = [self.polygon(p, f"clutter[{i}]") for i, p in enumerate(doc["clutter"])]
        free_space = self.polygon(doc["free_space"], "free_space")
        if not free_space.covers(shapely.Point(start.x, start.y)):
            raise self.fail(f"start ({_short(start.x)}, {_short(start.y)}) is outside free_space")
        obstacles = doc["dynamic_obstacles"]
        if not isinstance(obstacles, list):
            raise self.fail(f"dynamic_obstacles must be a list, got {_type_name(obstacles)}")
        world = World(
            walls=walls,
            clutter=tuple(clutter),
            free_space=free_space,
            bounds=(bounds[0], bounds[1], bounds[2], bounds[3]),
            start=start,
            roadmap=self.roadmap(doc["roadmap"]),
            kind=kind,
            seed=seed,
            params=self.mapping(doc["params"], "params"),
            dynamic_obstacles=tuple(
                self.obstacle(ob, f"dynamic_obstacles[{i}]") for i, ob in enumerate(obstacles)
            ),
            features=self.mapping(doc["features"], "features"),
            robot_radius_m=radius,
        )
        problem = world_problem(world) if self.validate else None
        if problem is not None:
            raise self.fail(problem)
        return world

    def roadmap(self, value: Any) -> Roadmap:
        doc = self.obj(value, "roadmap", frozenset({"nodes", "edges"}))
        nodes = self.rows(doc["nodes"], "roadmap.nodes", 2, "[x, y]")
        edges = doc["edges"]
        if not isinstance(edges, list):
            raise self.fail(f"roadmap.edges must be a list of [i, j], got {_type_name(edges)}")
        for k, edge in enumerate(edges):
            field = f"roadmap.edges[{k}]"
            if not isinstance(edge, list) or len(edge) != 2:
                raise self.fail(f"{field} must be [i, j], got {_short(edge)}")
            for index in edge:
                if type(index) is not int:
                    raise self.fail(f"{field} must hold integer node indices, got {_short(edge)}")
                if not 0 <= index < len(nodes):
                    raise self.fail(
                        f"{field} node index {index} out of range (roadmap has {len(nodes)} nodes)"
                    )
            if edge[0] == edge[1]:
                raise self.fail(f"{field} joins node {edge[0]} to itself")
        return Roadmap(nodes=nodes, edges=np.array(edges, dtype=np.int64).reshape(-1, 2))

    def obstacle(self, value: Any, field: str) -> DynamicObstacle:
        doc = self.obj(value, field, _OBSTACLE_KEYS)
        if doc["kind"] not in _OBSTACLE_KINDS:
            raise self.fail(
                f"{field}.kind must be one of {_OBSTACLE_KINDS}, got {_short(doc['kind'])}"
            )
        speed = self.number(doc["speed_m_s"], f"{field}.speed_m_s", math.inf)
        mass = self.number(doc["mass_kg"], f"{field}.mass_kg", math.inf)
        if speed < 0.0:
            raise self.fail(f"{field}.speed_m_s must be >= 0, got {_short(speed)}")
        if mass <= 0.0:
            raise self.fail(f"{field}.mass_kg must be > 0, got {_short(mass)}")
        shape = self.ring(doc["shape"], f"{field}.shape")
        pose = Pose(*self.numbers(doc["pose"], f"{field}.pose", 3, "[x, y, theta]"))
        path = self.rows(doc["path"], f"{field}.path", 2, "[x, y]")
        try:
            return DynamicObstacle(
                kind=doc["kind"], shape=shape, pose=pose, path=path, speed_m_s=speed,
                mass_kg=mass,
            )  # fmt: skip
        except InputError as exc:  # the obstacle's own checks, placed in the file
            text = str(exc)
            named = text.replace("DynamicObstacle.", f"{field}.")
            raise self.fail(named if named != text else f"{field}: {text}") from None

    def mapping(self, value: Any, field: str) -> dict[str, Any]:
        if not isinstance(value, dict) or TYPE_TAG in value:
            raise self.fail(f"{field} must be an object, got {_type_name(value)}")
        return self.value(value, field)

    def value(self, value: Any, field: str) -> Any:
        if isinstance(value, float):
            return self.number(value, field, math.inf)
        if isinstance(value, list):
            return [self.value(v, f"{field}[{i}]") for i, v in enumerate(value)]
        if isinstance(value, dict):
            if TYPE_TAG in value:
                return self.tagged(value, field)
            return {k: self.value(v, f"{field}.{k}") for k, v in value.items()}
        return value  # None, bool, int, str

    def tagged(self, value: dict[str, Any], field: str) -> Any:
        tag = value[TYPE_TAG]
        if tag == "ndarray":
            return self.ndarray(value, field)
        if tag == "Pose":
            doc = self.obj(value, field, frozenset({TYPE_TAG, "xytheta"}))
            return Pose(*self.numbers(doc["xytheta"], f"{field}.xytheta", 3, "[x, y, theta]"))
        if tag == "Polygon":
            doc = self.obj(value, field, frozenset({TYPE_TAG, "exterior", "holes"}))
            return self.polygon({k: doc[k] for k in ("exterior", "holes")}, field)
        if tag == "MultiPolygon":
            doc = self.obj(value, field, frozenset({TYPE_TAG, "polygons"}))
            parts = doc["polygons"]
            if not isinstance(parts, list):
                raise self.fail(f"{field}.polygons must be a list, got {_type_name(parts)}")
            return shapely.MultiPolygon(
                [self.polygon(p, f"{field}.polygons[{i}]") for i, p in enumerate(parts)]
            )
        if tag in ("LineString", "Point"):
            doc = self.obj(value, field, frozenset({TYPE_TAG, "coords"}))
            coords = self.rows(doc["coords"], f"{field}.coords", 2, "[x, y]")
            if len(coords) != (1 if tag == "Point" else max(2, len(coords))):
                raise self.fail(f"{field}.coords has {len(coords)} points, too few or many")
            return shapely.LineString(coords) if tag == "LineString" else shapely.Point(coords[0])
        raise self.fail(f"{field} has unknown {TYPE_TAG} {tag!r}")

    def ndarray(self, value: dict[str, Any], field: str) -> np.ndarray:
        doc = self.obj(value, field, frozenset({TYPE_TAG, "dtype", "shape", "data"}))
        name, shape, data = doc["dtype"], doc["shape"], doc["data"]
        dtype = np.dtype(name) if isinstance(name, str) and name in ARRAY_DTYPES else None
        if dtype is None:
            raise self.fail(
                f"{field}.dtype must be one of {sorted(ARRAY_DTYPES)}, got {_short(name)}"
            )
        if not isinstance(shape, list) or not all(type(n) is int and n >= 0 for n in shape):
            raise self.fail(f"{field}.shape must be a list of sizes, got {_short(shape)}")
        if len(shape) > MAX_ARRAY_DIMENSIONS or math.prod(n for n in shape if n) > MAX_ARRAY_ITEMS:
            raise self.fail(
                f"{field}.shape {_short(shape)} is beyond the limits of {MAX_ARRAY_DIMENSIONS} "
                f"dimensions of at most {MAX_ARRAY_ITEMS} items (MAX_ARRAY_DIMENSIONS, "
                "MAX_ARRAY_ITEMS)"
            )
        if not isinstance(data, list) or len(data) != math.prod(shape):
            got = f"{len(data)} items" if isinstance(data, list) else _type_name(data)
            raise self.fail(f"{field}.data has {got}, shape {shape} needs {math.prod(shape)}")
        allowed = (bool,) if dtype.kind == "b" else (int,) if dtype.kind in "iu" else (int, float)
        for i, x in enumerate(data):
            if type(x) not in allowed:
                raise self.fail(f"{field}.data[{i}] is {_short(x)}, not a {dtype.name} value")
            if type(x) is float:
                self.number(x, f"{field}.data[{i}]", math.inf)
        try:
            return np.array(data, dtype=dtype).reshape(shape)
        except OverflowError as exc:
            raise self.fail(f"{field}.data does not fit {dtype.name}: {exc}") from exc
