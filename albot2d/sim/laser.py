"""The simulated 2D laser range finder: ``LaserParams`` (geometry), ``LaserNoise``, ``Laser``.

``Laser.scan(pose, rng)`` casts the beams exactly (``albot2d.sim.raycast``) from the laser's
world pose (robot pose ⊕ mount) against the static walls and any moving obstacles, then
applies the noise model, in this fixed order, each step drawing from ``rng`` only when
enabled (so a zero-noise laser consumes no randomness and returns exact ranges):

1. angular jitter — each beam is cast at ``nominal + N(0, angle_jitter_deg)`` but reported
   at its nominal angle;
2. mixed pixels — where two neighbouring beams straddle an occluding edge (their hits lie
   on different, unconnected surfaces: ``RayCaster.same_surface``) and their ranges differ
   by more than ``mixed_pixel_min_jump_m``, with probability ``mixed_pixel_prob`` one of
   the two beams (either, at random) returns a range uniformly between the foreground and
   background. A smooth wall seen at a grazing angle has no edge, however far apart its
   neighbouring ranges are (``mixed_pixel_edges="any_jump"`` keeps albot2d's former model,
   which blended there too);
3. Gaussian range noise — ``N(0, range_sigma_m + range_sigma_per_m * range)``;
4. quantisation to multiples of ``range_resolution_m`` (0 = off);
5. validity — a beam is valid when it hit something and its range lies in
   ``[min_range_m, max_range_m)``;
6. dropouts — each valid beam independently returns nothing with ``dropout_prob``.

Invalid beams report ``max_range_m`` (as CARMEN logs report no-return readings).

Steps 2–6 run as one compiled call (``laser_numba``) when numba
imports, on the same draws, with the same ranges bit for bit; ``noise_backend`` chooses.
The default mount is the robot's rotation centre (``mount_x_m = 0``); a Pioneer-style
front mount is ``mount_x_m = 0.16``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from albot2d.compiled import compiled_kernel
from albot2d.errors import InputError
from albot2d.frames import Scan, beam_angles
from albot2d.geometry import Pose
from albot2d.sim.raycast import BeamFan, RayCaster
from albot2d.validation import check_finite, check_in_range, check_non_negative

if TYPE_CHECKING:
    from worldgen.world import World

__all__ = ["LASER_NOISE_PRESETS", "Laser", "LaserNoise", "LaserParams", "laser_noise_preset"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class LaserParams:
    """Beam geometry and mount of a SICK LMS-like laser (defaults: 180°, 181 beams, 30 m).

    ``n_beams`` beams spread evenly over ``fov_deg`` with both ends included (181 → 1°,
    361 → 0.5°); a full 360° sweep leaves out the duplicate end beam. ``mount_*`` is the
    laser's pose in the robot frame.
    """

    fov_deg: float = 180.0
    n_beams: int = 181
    max_range_m: float = 30.0
    min_range_m: float = 0.05
    mount_x_m: float = 0.0
    mount_y_m: float = 0.0
    mount_yaw_deg: float = 0.0

    def __post_init__(self) -> None:
        check_in_range(self, "fov_deg", 1e-6, 360.0)
        if isinstance(self.n_beams, bool) or not isinstance(self.n_beams, int):
            raise InputError(f"LaserParams.n_beams must be an integer, got {self.n_beams!r}")
        if self.n_beams < 2:
            raise InputError(f"LaserParams.n_beams must be >= 2, got {self.n_beams!r}")
        check_in_range(self, "max_range_m", 1e-6, 1e6)
        check_non_negative(self, "min_range_m")
        if self.min_range_m >= self.max_range_m:
            raise InputError(
                f"LaserParams.min_range_m must be < max_range_m ({self.max_range_m!r}), "
                f"got {self.min_range_m!r}"
            )
        for name in ("mount_x_m", "mount_y_m", "mount_yaw_deg"):
            check_finite(self, name)

    @classmethod
    def sick_lms200(cls, *, n_beams: int = 181, max_range_m: float = 80.0) -> LaserParams:
        """SICK LMS200: 180°, 181 (1°) or 361 (0.5°) beams, 80 m long-range mode."""
        return cls(n_beams=n_beams, max_range_m=max_range_m)

    @property
    def mount_pose(self) -> Pose:
        return Pose(self.mount_x_m, self.mount_y_m, math.radians(self.mount_yaw_deg))

    def beam_angles(self) -> FloatArray:
        """Nominal beam angles (radians, laser frame, right to left)."""
        fov = math.radians(self.fov_deg)
        full_circle = self.fov_deg >= 360.0
        return beam_angles(self.n_beams, fov, inclusive=not full_circle)


@dataclass(frozen=True)
class LaserNoise:
    """Noise model parameters (see the module docstring); every one can be zero.

    The defaults are plausible SICK LMS200 values (``sick_lms200()``), not a calibration:
    1 cm resolution, about 5 mm + 0.1 % of range sigma, rare dropouts, mixed pixels at
    edges, and no angular jitter (the LMS angle encoder is precise). ``LaserNoise.zero()``
    gives exact ranges.
    """

    range_sigma_m: float = 0.005
    range_sigma_per_m: float = 0.001
    angle_jitter_deg: float = 0.0
    dropout_prob: float = 0.001
    range_resolution_m: float = 0.01
    mixed_pixel_prob: float = 0.3
    mixed_pixel_min_jump_m: float = 0.2
    mixed_pixel_edges: Literal["occluding", "any_jump"] = "occluding"

    def __post_init__(self) -> None:
        check_non_negative(
            self,
            "range_sigma_m",
            "range_sigma_per_m",
            "angle_jitter_deg",
            "range_resolution_m",
            "mixed_pixel_min_jump_m",
        )
        check_in_range(self, "dropout_prob", 0.0, 1.0)
        check_in_range(self, "mixed_pixel_prob", 0.0, 1.0)
        if self.mixed_pixel_edges not in ("occluding", "any_jump"):
            raise InputError(
                "LaserNoise.mixed_pixel_edges must be occluding or any_jump, "
                f"got {self.mixed_pixel_edges!r}"
            )

    @classmethod
    def zero(cls) -> LaserNoise:
        """No noise at all: ranges are the exact distances."""
        return cls(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)

    @classmethod
    def sick_lms200(cls) -> LaserNoise:
        """Plausible SICK LMS200 noise (1 cm resolution, ~5 mm + 0.1 % sigma)."""
        return cls()

    @classmethod
    def sick_lms200_any_jump(cls) -> LaserNoise:
        """``sick_lms200`` with albot2d's former mixed-pixel model (a blend at any range jump,
        smooth grazing walls included), to repeat numbers measured before the fix."""
        return cls(mixed_pixel_edges="any_jump")

    @property
    def is_zero(self) -> bool:
        return (
            self.range_sigma_m == 0.0
            and self.range_sigma_per_m == 0.0
            and self.angle_jitter_deg == 0.0
            and self.dropout_prob == 0.0
            and self.range_resolution_m == 0.0
            and self.mixed_pixel_prob == 0.0
        )


#: The laser noise presets by name (``--laser-noise``, ``RunSpec.laser_noise``).
LASER_NOISE_PRESETS: dict[str, Callable[[], LaserNoise]] = {
    "sick_lms200": LaserNoise.sick_lms200,
    "zero": LaserNoise.zero,
    "sick_lms200_any_jump": LaserNoise.sick_lms200_any_jump,
}


def laser_noise_preset(name: str) -> LaserNoise:
    """The named laser noise preset; unknown names raise InputError listing the valid ones."""
    try:
        return LASER_NOISE_PRESETS[name]()
    except KeyError:
        raise InputError(
            f"unknown laser noise {name!r}; valid: {', '.join(LASER_NOISE_PRESETS)}"
        ) from None


class Laser:
    """A laser mounted on a robot, seeing ``static_segments`` plus per-scan extra segments.

    ``static_segments`` is an ``(N, 4)`` array (e.g. ``World.obstacle_segments``) or a
    prebuilt ``RayCaster`` to share one index between lasers.
    """

    def __init__(
        self,
        static_segments: ArrayLike | RayCaster,
        params: LaserParams | None = None,
        noise: LaserNoise | None = None,
        *,
        noise_backend: str = "auto",
    ) -> None:
        if noise_backend not in ("auto", "numpy", "numba"):
            raise InputError(f"noise_backend must be auto, numpy or numba, got {noise_backend!r}")
        self.params = params if params is not None else LaserParams()
        self.noise = noise if noise is not None else LaserNoise()
        if isinstance(static_segments, RayCaster):
            self.caster = static_segments
        else:
            self.caster = RayCaster(static_segments)
        self.angles: FloatArray = self.params.beam_angles()
        self.angles.flags.writeable = False
        self._fan = BeamFan.from_angles(self.angles)
        self._mount = self.params.mount_pose
        # The name, not the kernel: a Laser pickles small and loads numba where it runs.
        compiled = noise_backend != "numpy" and _noise_kernel() is not None
        if noise_backend == "numba" and not compiled:
            raise InputError("noise_backend='numba' needs numba (off under ALBOT2D_KERNELS=numpy)")
        self.noise_backend = "numba" if compiled else "numpy"

    @classmethod
    def for_world(
        cls, world: World, params: LaserParams | None = None, noise: LaserNoise | None = None
    ) -> Laser:
        """A laser seeing a ``worldgen.World``'s walls and clutter (``obstacle_segments``)."""
        return cls(world.obstacle_segments, params, noise)

    @property
    def n_beams(self) -> int:
        return len(self.angles)

    def laser_pose(self, robot_pose: Pose) -> Pose:
        """The laser's world pose for a robot at ``robot_pose``."""
        return robot_pose.compose(self._mount)

    def true_ranges(
        self, robot_pose: Pose, *, extra_segments: ArrayLike | None = None
    ) -> FloatArray:
        """Exact ranges at the nominal beam angles; ``inf`` where nothing is within range."""
        lp = self.laser_pose(robot_pose)
        return self.caster.cast(
            (lp.x, lp.y),
            self._fan,
            self.params.max_range_m,
            heading=lp.theta,
            extra_segments=extra_segments,
        )

    def scan(
        self,
        pose: Pose,
        rng: np.random.Generator,
        *,
        timestamp: float = 0.0,
        extra_segments: ArrayLike | None = None,
    ) -> Scan:
        """One noisy sweep from a robot at world ``pose``; see the module docstring."""
        p, nz = self.params, self.noise
        lp = self.laser_pose(pose)
        fan = self._fan
        if nz.angle_jitter_deg > 0.0:
            fan = fan.jittered(rng.normal(0.0, math.radians(nz.angle_jitter_deg), self.n_beams))
        r = self.caster.cast(
            (lp.x, lp.y), fan, p.max_range_m, heading=lp.theta, extra_segments=extra_segments
        )
        hit = r <= p.max_range_m
        np.minimum(r, p.max_range_m, out=r)  # no-return beams stay invalid whatever happens
        edges = _NO_EDGES
        if nz.mixed_pixel_prob > 0.0:
            edges = self._mixing_edges(r, hit, lp, fan, extra_segments)
        if self.noise_backend == "numba":
            ranges, valid = self._compiled_noise(r, hit, edges, rng)
        else:
            ranges, valid = self._numpy_noise(r, hit, edges, rng)
        # The noise made ``ranges`` and ``valid`` fresh; the angles are read-only.
        return Scan.adopt(ranges, self.angles, valid, p.max_range_m, float(timestamp), self._mount)

    def _mixing_edges(
        self,
        r: FloatArray,
        hit: NDArray[np.bool_],
        lp: Pose,
        fan: BeamFan,
        extra_segments: ArrayLike | None,
    ) -> NDArray[np.bool_]:
        """``(n - 1,)``: whether beams ``i`` and ``i + 1`` can return a mixed pixel (see the
        module docstring), from the exact ranges ``r`` of the beams as cast."""
        nz = self.noise
        if nz.mixed_pixel_edges == "any_jump":
            edges = np.abs(r[1:] - r[:-1]) > nz.mixed_pixel_min_jump_m
            edges &= hit[1:]
            edges &= hit[:-1]
            return edges
        return self.caster.depth_edges(
            (lp.x, lp.y), fan.angles + lp.theta, r, hit, nz.mixed_pixel_min_jump_m,
            extra_segments=extra_segments,
        )  # fmt: skip

    def _compiled_noise(
        self,
        r: FloatArray,
        hit: NDArray[np.bool_],
        edges: NDArray[np.bool_],
        rng: np.random.Generator,
    ) -> tuple[FloatArray, NDArray[np.bool_]]:
        """Steps 2–6 in one compiled call on exactly the numpy path's draws, in its order."""
        p, nz, n = self.params, self.noise, self.n_beams
        mixed = rng.random((3, n - 1)) if nz.mixed_pixel_prob > 0.0 else _NO_DRAWS_2D
        noisy = nz.range_sigma_m > 0.0 or nz.range_sigma_per_m > 0.0
        normal = rng.standard_normal(n) if noisy else _NO_DRAWS
        dropout = rng.random(n) if nz.dropout_prob > 0.0 else _NO_DRAWS
        res = nz.range_resolution_m
        kernel = _noise_kernel()
        assert kernel is not None  # checked in __init__
        return kernel(
            r, hit, nz.mixed_pixel_prob, edges, mixed, nz.range_sigma_m,
            nz.range_sigma_per_m, normal, 1.0 / res if res > 0.0 else 0.0, res,
            p.min_range_m, p.max_range_m, nz.dropout_prob, dropout,
        )  # fmt: skip

    def _numpy_noise(
        self,
        r: FloatArray,
        hit: NDArray[np.bool_],
        edges: NDArray[np.bool_],
        rng: np.random.Generator,
    ) -> tuple[FloatArray, NDArray[np.bool_]]:
        p, nz = self.params, self.noise
        if nz.mixed_pixel_prob > 0.0:
            _mix_pixels(r, edges, nz, rng)
        if nz.range_sigma_m > 0.0 or nz.range_sigma_per_m > 0.0:
            sigma = nz.range_sigma_per_m * r
            sigma += nz.range_sigma_m
            sigma *= rng.standard_normal(self.n_beams)
            r += sigma
        if nz.range_resolution_m > 0.0:
            r *= 1.0 / nz.range_resolution_m
            np.rint(r, out=r)
            r *= nz.range_resolution_m
        valid = hit & (r >= p.min_range_m) & (r < p.max_range_m)
        if nz.dropout_prob > 0.0:
            valid &= rng.random(self.n_beams) >= nz.dropout_prob
        return np.where(valid, r, p.max_range_m), valid


_NO_DRAWS = np.zeros(0)
_NO_EDGES = np.zeros(0, dtype=np.bool_)
_NO_DRAWS_2D = np.zeros((3, 0))


def _noise_kernel() -> Callable[..., tuple[FloatArray, NDArray[np.bool_]]] | None:
    """``laser_numba.apply_noise`` when numba imports, else None (the numpy path)."""
    return compiled_kernel("albot2d.sim.laser_numba", "apply_noise")


def _mix_pixels(
    r: FloatArray, edges: NDArray[np.bool_], nz: LaserNoise, rng: np.random.Generator
) -> None:
    """Blend one beam at each edge (``Laser._mixing_edges``) between the foreground and
    background (in place)."""
    n = len(r) - 1
    happens, side, fraction = rng.random((3, n))
    jump = happens < nz.mixed_pixel_prob
    jump &= edges
    at = np.flatnonzero(jump)
    if len(at) == 0:
        return
    left, right = r[at], r[at + 1]
    near = np.minimum(left, right)
    blended = near + fraction[at] * (np.maximum(left, right) - near)
    r[at + (side[at] < 0.5)] = blended
