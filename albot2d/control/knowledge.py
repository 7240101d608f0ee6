"""What the laser has shown: ``GridSpec`` (a raster over the world) and ``KnowledgeGrid``.

Each scan is taken in as the fan it swept (an inverse sensor model, every cell of the fan's
bounding box tested at once with numpy): cells inside it become ``FREE`` and count as
*seen*; the cell a valid return ended in becomes ``OCCUPIED``. Only valid returns are used
(an invalid beam, a dropout or no return, says nothing about where it went), and only up to
``sensing_range_m``: a real operator does not call floor seen 30 m down a corridor.
Each cell keeps log-odds evidence (``HIT_LOG_ODDS`` per return in it, ``PASS_LOG_ODDS`` per
fan covering it, clamped): a mixed-pixel return in mid-air is cleared by the next few
scans, a wall hit scan after scan stays. A cell is occupied while its evidence is positive.
``mark_footprint`` makes the cells under the robot free without counting them as seen (the
robot stands there; it has not looked).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from albot2d.compiled import compiled_kernel
from albot2d.frames import Scan
from albot2d.geometry import Pose
from albot2d.validation import check_positive

__all__ = [
    "FREE",
    "HIT_LOG_ODDS",
    "OCCUPIED",
    "PASS_LOG_ODDS",
    "UNKNOWN",
    "GridSpec",
    "KnowledgeGrid",
    "fan_cells",
]

FloatArray = NDArray[np.float64]
UNKNOWN = np.int8(0)
FREE = np.int8(1)
OCCUPIED = np.int8(2)
#: Log-odds evidence per return ending in a cell / per fan covering it, and the clamp.
HIT_LOG_ODDS = 0.9
PASS_LOG_ODDS = -0.4
_EVIDENCE_RANGE = (-2.0, 3.5)


@dataclass(frozen=True)
class GridSpec:
    """A raster of ``ny`` × ``nx`` square cells of ``resolution_m``; cell (0, 0)'s lower-left
    corner at (``origin_x_m``, ``origin_y_m``). Arrays over it are indexed ``[iy, ix]``."""

    origin_x_m: float
    origin_y_m: float
    resolution_m: float
    nx: int
    ny: int

    def __post_init__(self) -> None:
        check_positive(self, "resolution_m", "nx", "ny")

    @classmethod
    def covering(cls, min_x: float, min_y: float, max_x: float, max_y: float,
                 resolution_m: float, margin_m: float = 0.0) -> GridSpec:  # fmt: skip
        """The smallest grid of ``resolution_m`` cells covering the box plus ``margin_m``."""
        x0, y0 = min_x - margin_m, min_y - margin_m
        nx = max(1, math.ceil((max_x + margin_m - x0) / resolution_m))
        ny = max(1, math.ceil((max_y + margin_m - y0) / resolution_m))
        return cls(x0, y0, resolution_m, nx, ny)

    @property
    def shape(self) -> tuple[int, int]:
        return (self.ny, self.nx)

    @property
    def cell_area_m2(self) -> float:
        return self.resolution_m**2

    def cell_of(self, x: float, y: float) -> tuple[int, int]:
        """The ``(iy, ix)`` cell containing (x, y), clipped to the grid."""
        ix = int(np.clip(math.floor((x - self.origin_x_m) / self.resolution_m), 0, self.nx - 1))
        iy = int(np.clip(math.floor((y - self.origin_y_m) / self.resolution_m), 0, self.ny - 1))
        return iy, ix

    def cells_of(
        self, points: FloatArray
    ) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.bool_]]:
        """``(iy, ix, inside)`` of ``(N, 2)`` points; outside points get index 0."""
        ix = np.floor((points[:, 0] - self.origin_x_m) / self.resolution_m).astype(np.intp)
        iy = np.floor((points[:, 1] - self.origin_y_m) / self.resolution_m).astype(np.intp)
        inside = (ix >= 0) & (ix < self.nx) & (iy >= 0) & (iy < self.ny)
        return np.where(inside, iy, 0), np.where(inside, ix, 0), inside

    def centres(self) -> tuple[FloatArray, FloatArray]:
        """Cell-centre coordinates ``(X, Y)``, each of shape ``(ny, nx)``."""
        xs = self.origin_x_m + (np.arange(self.nx) + 0.5) * self.resolution_m
        ys = self.origin_y_m + (np.arange(self.ny) + 0.5) * self.resolution_m
        return np.meshgrid(xs, ys)

    def centre_of(self, iy: int, ix: int) -> tuple[float, float]:
        r = self.resolution_m
        return self.origin_x_m + (ix + 0.5) * r, self.origin_y_m + (iy + 0.5) * r


def fan_cells(
    laser_x: float,
    laser_y: float,
    laser_theta: float,
    angles: FloatArray,
    reach: FloatArray,
    origin_x_m: float,
    origin_y_m: float,
    resolution_m: float,
    ix0: int,
    ix1: int,
    iy0: int,
    iy1: int,
    nx: int,
    margin_m: float,
) -> NDArray[np.intp]:
    """The flat indices (row-major, ``nx`` columns) of the cells of the window
    ``[iy0, iy1) × [ix0, ix1)`` whose centre lies inside the fan a scan swept: between two
    neighbouring beams (``angles`` ascending, in the laser's frame at ``laser_theta``) and
    nearer the laser than both their ``reach`` less ``margin_m``. The numpy reference;
    ``knowledge_numba.fan_cells`` is the compiled kernel, tested equal to it."""
    r = resolution_m
    dx = (origin_x_m + (np.arange(ix0, ix1) + 0.5) * r - laser_x)[None, :]
    dy = (origin_y_m + (np.arange(iy0, iy1) + 0.5) * r - laser_y)[:, None]
    rho = np.hypot(dx, dy)
    phi = np.arctan2(dy, dx) - laser_theta
    phi = (phi - angles[0] + math.pi) % (2.0 * math.pi) - math.pi + angles[0]
    j = np.searchsorted(angles, phi, side="right") - 1
    inside = (j >= 0) & (j < len(angles) - 1)
    jc = np.clip(j, 0, len(angles) - 2)
    limit = np.minimum(reach[jc], reach[jc + 1])
    fan = inside & (rho < limit - margin_m)
    wy, wx = np.nonzero(fan)
    return ((wy + iy0) * nx + (wx + ix0)).astype(np.intp)


class KnowledgeGrid:
    """Free / occupied / unknown cells and the cells seen, built from scans (see module)."""

    def __init__(self, spec: GridSpec, *, sensing_range_m: float = 10.0) -> None:
        if not (math.isfinite(sensing_range_m) and sensing_range_m > 0):
            raise ValueError(f"sensing_range_m must be a positive number, got {sensing_range_m!r}")
        self.spec = spec
        self.sensing_range_m = float(sensing_range_m)
        self.evidence = np.zeros(spec.shape, dtype=np.float32)
        self.known = np.zeros(spec.shape, dtype=bool)
        self.seen = np.zeros(spec.shape, dtype=bool)
        # A fan covers a cell only when the whole cell lies before the returns, so the
        # cell a return ends in is never also counted as passed by the same scan.
        self._pass_margin_m = math.sqrt(0.5) * spec.resolution_m

    def integrate(self, pose: Pose, scan: Scan) -> NDArray[np.intp]:
        """Take in ``scan`` taken at robot pose ``pose``; returns the flat indices of the
        cells seen for the first time.

        A cell is seen when its centre lies inside the fan the scan swept: between two
        neighbouring beams, nearer the laser than both their returns (capped at
        ``sensing_range_m``); an invalid beam counts as a return at zero, so nothing is
        seen beside it. Every cell of the fan's bounding box is tested at once.
        """
        spec = self.spec
        laser = pose.compose(scan.laser_pose)
        angles = np.asarray(scan.angles)
        reach = np.where(scan.valid, np.minimum(scan.ranges, self.sensing_range_m), 0.0)
        if len(reach) < 2 or not reach.any():
            return np.zeros(0, dtype=np.intp)
        world = angles + laser.theta
        ex = laser.x + reach * np.cos(world)
        ey = laser.y + reach * np.sin(world)
        r = spec.resolution_m
        ix0 = max(math.floor((min(ex.min(), laser.x) - spec.origin_x_m) / r), 0)
        ix1 = min(math.floor((max(ex.max(), laser.x) - spec.origin_x_m) / r) + 1, spec.nx)
        iy0 = max(math.floor((min(ey.min(), laser.y) - spec.origin_y_m) / r), 0)
        iy1 = min(math.floor((max(ey.max(), laser.y) - spec.origin_y_m) / r) + 1, spec.ny)
        new = np.zeros(0, dtype=np.intp)
        if ix1 > ix0 and iy1 > iy0:
            window = (spec.origin_x_m, spec.origin_y_m, r, ix0, ix1, iy0, iy1, spec.nx)
            kernel = compiled_kernel("albot2d.control.knowledge_numba", "fan_cells")
            fan = kernel if kernel is not None else fan_cells
            flat = fan(laser.x, laser.y, laser.theta, angles, reach, *window,
                       self._pass_margin_m)  # fmt: skip
            seen = self.seen.reshape(-1)
            new = flat[~seen[flat]]
            seen[flat] = True
            self.known.reshape(-1)[flat] = True
            evidence = self.evidence.reshape(-1)
            evidence[flat] = np.maximum(evidence[flat] + PASS_LOG_ODDS, _EVIDENCE_RANGE[0])
        hit = scan.valid & (scan.ranges < self.sensing_range_m)
        if hit.any():
            hy, hx, hin = spec.cells_of(np.column_stack([ex[hit], ey[hit]]))
            cells = np.unique(hy[hin] * spec.nx + hx[hin])
            evidence = self.evidence.reshape(-1)
            evidence[cells] = np.minimum(evidence[cells] + HIT_LOG_ODDS, _EVIDENCE_RANGE[1])
            self.known.reshape(-1)[cells] = True
        return new

    def forget_obstacles(self) -> None:
        """Drop all evidence of obstacles (positive log-odds back to 0): the walls the laser
        shows next come back with its next scans, a stray return does not. What was seen
        stays seen. A planner's recovery when its grid has walled it in."""
        np.minimum(self.evidence, 0.0, out=self.evidence)

    def mark_footprint(self, pose: Pose, radius_m: float) -> None:
        """Cells whose centre lies under the robot's disc become free (unless occupied)."""
        r = self.spec.resolution_m
        k = math.ceil(radius_m / r) + 1
        cy, cx = self.spec.cell_of(pose.x, pose.y)
        y0, y1 = max(cy - k, 0), min(cy + k + 1, self.spec.ny)
        x0, x1 = max(cx - k, 0), min(cx + k + 1, self.spec.nx)
        xs = self.spec.origin_x_m + (np.arange(x0, x1) + 0.5) * r
        ys = self.spec.origin_y_m + (np.arange(y0, y1) + 0.5) * r
        inside = (xs[None, :] - pose.x) ** 2 + (ys[:, None] - pose.y) ** 2 <= radius_m**2
        known = self.known[y0:y1, x0:x1]
        evidence = self.evidence[y0:y1, x0:x1]
        evidence[inside & ~known] = _EVIDENCE_RANGE[0]
        known |= inside

    @property
    def state(self) -> NDArray[np.int8]:
        """``UNKNOWN`` / ``FREE`` / ``OCCUPIED`` per cell."""
        out = np.where(self.evidence > 0.0, OCCUPIED, FREE).astype(np.int8)
        out[~self.known] = UNKNOWN
        return out

    @property
    def free(self) -> NDArray[np.bool_]:
        return self.known & (self.evidence <= 0.0)

    @property
    def occupied(self) -> NDArray[np.bool_]:
        return self.evidence > 0.0

    @property
    def unknown(self) -> NDArray[np.bool_]:
        return ~self.known
