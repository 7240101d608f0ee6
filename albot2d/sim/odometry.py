"""Wheel odometry: ``OdometryNoise`` (the error model), ``Odometry`` (integration), presets.

Error is generated where it physically arises: along the true motion, never per read.
``Odometry`` integrates the true motion on a fixed grid along the path, like a wheel
encoder's ticks: every ``resolution_m`` of distance driven and every ``resolution_deg`` of
turn is one cell, and each cell gets its own error. However the motion is cut into
``update`` calls (one 3 m move, three hundred 1 cm moves, the simulator's physics ticks),
the same true path crosses the same cells and draws the same error; only a read that ends
inside a cell sees that cell's error in proportion (the random walk interpolated linearly
between grid points). So the distribution of the reported error over a path does not
depend on how often odometry is read (``tests/test_odometry.py`` tests it over 400 seeds).

1. Random error: a random walk whose variance grows linearly with distance and angle.
   Over a path of ``d`` metres and ``a`` radians turned the heading error has variance
   ``alpha1² a + alpha2² d`` (rad²) and the distance error ``alpha3² d + alpha4² a`` (m²);
   position error then grows from the heading error as the integration carries it (the
   lateral error of a straight of length d has variance ``alpha2² d³ / 3``). Each grid cell
   draws two standard normals (heading, distance), scaled by ``alpha·sqrt(cell)``.
2. Systematic error, as Stage's ``odom_error`` (x/y and theta scale errors): the distance
   is scaled by ``1 + distance_scale_error``, every turn by ``1 + turn_scale_error`` (a
   wrong wheel base: the dominant error of differential-drive odometry), and the heading
   drifts by ``heading_drift_deg_per_m`` (unequal wheel radii), applied per cell too.
3. The induced error of the paper's dataset 2 is per instruction, as the paper defines it:
   ``Odometry.induce`` adds ``induced_step_m`` to a move instruction's distance and
   ``induced_step_deg`` to a turn instruction's angle (``Simulator.drive`` calls it at the
   end of each instruction; the velocity interface ``Simulator.step`` has no instructions
   and never adds it).

Units: the alphas keep their meaning per metre and per radian. The earlier per-read model
(``perturb_increment``, kept to compare) gave a read of ``d`` metres a standard deviation
``alpha·d``; the random walk gives a path of ``d`` metres ``alpha·sqrt(d)`` (d in m, or rad
for turns). Both agree for a read of exactly 1 m or 1 rad, so an alpha is "the 1σ error
after 1 m driven (or 1 rad turned)": ``alpha1`` rad/√rad, ``alpha2`` rad/√m, ``alpha3``
m/√m, ``alpha4`` m/√rad. What changed is the scaling with length: the old model's error
over a path of n reads of d/n each was ``alpha·d/sqrt(n)`` (it shrank as reads got more
frequent: 1.26° of heading spread for a 3 m straight read once against 0.24° read as
thirty 10 cm steps); now it is ``alpha·sqrt(d)`` whatever n is.

With every parameter zero the reported increment *is* the true one, and the odometry
pose is composed exactly as the true pose is, so both are bit-for-bit equal.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from albot2d.errors import InputError
from albot2d.geometry import Pose, add_angle
from albot2d.validation import check_finite, check_in_range, check_non_negative

__all__ = [
    "NOISE_PRESETS",
    "Odometry",
    "OdometryNoise",
    "OdometryReading",
    "StepKind",
    "heading_variance_rad2",
    "noise_preset",
    "perturb_increment",
]

StepKind = Literal["move", "turn", "other"]
FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class OdometryNoise:
    """Odometry error parameters (all zero: perfect odometry). See the module docstring.

    - ``alpha1`` rad of heading error after 1 rad turned (rad/√rad), ``alpha2`` rad after
      1 m driven (rad/√m), ``alpha3`` m of distance error after 1 m driven (m/√m),
      ``alpha4`` m after 1 rad turned (m/√rad): standard deviations of a random walk.
    - ``distance_scale_error``: reported distance = true × (1 + this), e.g. 0.02.
    - ``turn_scale_error``: reported turn = true turn × (1 + this), e.g. 0.02.
    - ``heading_drift_deg_per_m``: reported heading gains this much per metre driven.
    - ``induced_step_m`` / ``induced_step_deg``: added to each move / turn step (dataset 2);
      positive: longer moves, counter-clockwise turns. ``induced_along_motion`` instead
      adds them in the direction of each step (backward moves longer, right turns larger).
      Per instruction (``Odometry.induce``), so only ``Simulator.drive`` applies them.
    - ``resolution_m`` / ``resolution_deg``: the grid along the path on which error is
      generated (the encoder's "tick"; see the module docstring). Smaller is finer and
      slower; the error's statistics at whole cells do not depend on it.
    """

    alpha1: float = 0.0
    alpha2: float = 0.0
    alpha3: float = 0.0
    alpha4: float = 0.0
    distance_scale_error: float = 0.0
    heading_drift_deg_per_m: float = 0.0
    turn_scale_error: float = 0.0
    induced_step_m: float = 0.0
    induced_step_deg: float = 0.0
    induced_along_motion: bool = False
    resolution_m: float = 0.01
    resolution_deg: float = 1.0

    def __post_init__(self) -> None:
        check_non_negative(self, "alpha1", "alpha2", "alpha3", "alpha4")
        check_in_range(self, "resolution_m", 1e-4, 1.0)
        check_in_range(self, "resolution_deg", 1e-3, 90.0)
        for name in (
            "distance_scale_error",
            "heading_drift_deg_per_m",
            "induced_step_m",
            "induced_step_deg",
        ):
            check_finite(self, name)
        check_finite(self, "turn_scale_error")
        if self.turn_scale_error <= -1.0:
            raise InputError(
                f"OdometryNoise.turn_scale_error must be > -1, got {self.turn_scale_error!r}"
            )
        if self.distance_scale_error <= -1.0:
            raise InputError(
                "OdometryNoise.distance_scale_error must be > -1, "
                f"got {self.distance_scale_error!r}"
            )
        if not isinstance(self.induced_along_motion, bool):
            raise InputError(
                f"OdometryNoise.induced_along_motion must be true or false, "
                f"got {self.induced_along_motion!r}"
            )

    @property
    def is_random(self) -> bool:
        return any((self.alpha1, self.alpha2, self.alpha3, self.alpha4))

    @property
    def is_biased(self) -> bool:
        return bool(
            self.distance_scale_error or self.heading_drift_deg_per_m or self.turn_scale_error
        )

    @property
    def is_zero(self) -> bool:
        return not (
            self.is_random or self.is_biased or self.induced_step_m or self.induced_step_deg
        )


NOISE_PRESETS: dict[str, OdometryNoise] = {
    "none": OdometryNoise(),
    "low": OdometryNoise(alpha1=0.01, alpha2=0.002, alpha3=0.01, alpha4=0.001),
    # A round-number middle setting: a few percent of random error, a 2 % wheel base error
    # on turns and a small drift (no single source; "pioneer3dx" is the derived preset).
    "typical": OdometryNoise(
        alpha1=0.05,
        alpha2=0.01,
        alpha3=0.03,
        alpha4=0.005,
        distance_scale_error=0.01,
        heading_drift_deg_per_m=0.1,
        turn_scale_error=0.02,
    ),
    "high": OdometryNoise(
        alpha1=0.1,
        alpha2=0.05,
        alpha3=0.1,
        alpha4=0.02,
        distance_scale_error=0.03,
        heading_drift_deg_per_m=0.5,
        turn_scale_error=0.05,
    ),
    "pioneer3dx": OdometryNoise(
        alpha1=0.01,
        alpha2=0.005,
        alpha3=0.01,
        alpha4=0.001,
        distance_scale_error=0.01,
        heading_drift_deg_per_m=0.15,
        turn_scale_error=0.01,
    ),
}
"""Odometry noise presets. ``none``/``low``/``typical``/``high`` are round numbers spanning
a plausible range (no single source). ``pioneer3dx`` is an ActivMedia/MobileRobots Pioneer
3-DX (the paper's robot class: a differential drive, 195 mm wheels, ~0.33 m between the
wheels' contact lines) on a hard office floor, uncalibrated, derived as follows:

- Systematic errors. Borenstein & Feng, "Measurement and correction of systematic
  odometry errors in mobile robots", IEEE Trans. Robotics and Automation 12(6):869-880,
  1996 (UMBmark): the two dominant systematic errors of a differential drive are the
  uncertain effective wheelbase (a turn-scale error) and unequal wheel diameters (a
  heading drift while driving straight); their calibration cuts the systematic error by
  at least an order of magnitude, so an uncalibrated robot's errors are of the order of
  a percent. ``turn_scale_error = 0.01`` (the wheelbase 1 % off);
  ``heading_drift_deg_per_m = 0.15`` is a wheel-diameter ratio E_d = 1.001 on the
  P3-DX's ~0.33 m wheelbase (0.001 / 0.33 m = 3.0e-3 rad/m = 0.17°/m); E_d = 1.001 is
  an assumption (a 0.1 % mismatch, the order UMBmark calibrations correct), not a
  measured P3-DX value; ``distance_scale_error = 0.01``. Of all the numbers here this one
  matters most: over a 200 m office circuit it alone is 30° of heading.
- Cross-check against the maker's own statement. Pioneer 3 Operations Manual
  (MobileRobots Inc., 2006, "Position integration"): "you can rely on the dead-reckoning
  ability of the robot for just a short range - on the order of several meters and one or
  two revolutions, depending on the surface. Carpets tend to be worse than hard floors."
  With 1 % turn scale and 1 % random turn error (``alpha1``), one to two revolutions give a
  heading error of about 4-10° (bias plus 1σ), i.e. where registration visibly degrades.
- Same order as Player/Stage's simulated Pioneer (Stage position model, default
  ``odom_error [0.03 0.03 0.00 0.05]``: per-robot scale errors drawn uniformly within ±1.5 %
  on x/y and ±2.5 % on turns).
- Random (non-systematic) error: ``alpha1 = 0.01`` rad/√rad, ``alpha2 = 0.005`` rad/√m,
  ``alpha3 = 0.01`` m/√m, ``alpha4 = 0.001`` m/√rad: an assumption (no source found gives
  a P3-DX number): 1σ after 1 rad turned or 1 m driven of the same size as the
  systematic error over that same 1 rad or 1 m, for a hard floor. In the random-walk
  units the numbers keep that meaning (they are the 1σ at exactly 1 m / 1 rad); over
  longer paths the random part grows as the square root and the systematic part
  linearly, so the systematic errors dominate long runs, as UMBmark found. Re-derived
  in these units: one revolution gives 3.6° of bias (``turn_scale_error``) and
  ``0.01·sqrt(2π)`` = 1.4° of 1σ spread, two revolutions 7.2° and 2.0°: bias plus 1σ
  5.0-9.2°, inside the manual's "one or two revolutions" (4-10°) as before. 10 m
  straight: 1.5° of heading drift plus ``0.005·sqrt(10)`` = 0.9° spread; 0.10 m of
  distance bias plus 0.03 m spread (``docs/odometry.md`` tabulates every preset,
  ``python -m albot2d.sim.odometry_table``).

No published table gives these exact numbers for one P3-DX; they were fixed from the
sources above before any Albot1 run and are not tuned to its results. The homing
sensitivity over ``low``/``typical``/``high`` (``albot2d.studies.sensitivity``) is the
honest answer to how much they matter.
"""


def noise_preset(name: str) -> OdometryNoise:
    """The named odometry noise preset; unknown names raise InputError listing the valid ones."""
    try:
        return NOISE_PRESETS[name]
    except KeyError:
        raise InputError(
            f"unknown odometry noise preset {name!r}; valid: {', '.join(NOISE_PRESETS)}"
        ) from None


def _infer_kind(increment: Pose) -> StepKind:
    if increment.x == 0.0 and increment.y == 0.0 and increment.theta != 0.0:
        return "turn"
    if increment.y == 0.0 and increment.theta == 0.0 and increment.x != 0.0:
        return "move"
    return "other"


def _decompose(increment: Pose) -> tuple[float, float, float]:
    """(rot1, trans, rot2) with trans signed: negative when the motion is backwards."""
    trans = math.hypot(increment.x, increment.y)
    if trans == 0.0:
        return 0.0, 0.0, increment.theta
    rot1 = math.atan2(increment.y, increment.x)
    if abs(rot1) > 0.5 * math.pi:
        rot1 = add_angle(rot1, math.pi)
        trans = -trans
    return rot1, trans, add_angle(increment.theta, -rot1)


def perturb_increment(
    increment: Pose,
    noise: OdometryNoise,
    rng: np.random.Generator | None,
    kind: StepKind | None = None,
) -> Pose:
    """The per-read model albot2d used before ``Odometry``'s random walk, kept to compare:
    the increment reported for the true ``increment`` read in one piece, with noise of
    standard deviation ``alpha·length`` drawn once per read (Thrun, Burgard & Fox,
    *Probabilistic Robotics* (2005), sample_motion_model_odometry: rot1 / trans / rot2, each
    ``σ_rot1 = α1|rot1| + α2|trans|``, ``σ_trans = α3|trans| + α4(|rot1| + |rot2|)``,
    ``σ_rot2 = α1|rot2| + α2|trans|``), then the systematic and induced errors. Its error
    depends on how often odometry is read (see the module docstring); the simulator does
    not use it.

    ``rng`` is needed only when ``noise.is_random``; it then draws exactly three normals.
    ``kind`` (default: inferred — a pure turn or a pure forward/backward move) selects
    which induced error applies.
    """
    kind = _infer_kind(increment) if kind is None else kind
    induced_m = noise.induced_step_m if kind == "move" else 0.0
    induced_rad = math.radians(noise.induced_step_deg) if kind == "turn" else 0.0
    if not (noise.is_random or noise.is_biased):
        return _induce_exact(increment, noise, induced_m, induced_rad)
    rot1, trans, rot2 = _decompose(increment)
    if noise.is_random:
        if rng is None:
            raise ValueError("perturb_increment: random odometry noise needs an rng")
        a_rot1, a_trans, a_rot2 = abs(rot1), abs(trans), abs(rot2)
        # Three standard normals scaled by each part's sigma (in Python floats: the same
        # products as numpy's, without two small arrays per step).
        n_rot1, n_trans, n_rot2 = rng.standard_normal(3).tolist()
        rot1 += n_rot1 * (noise.alpha1 * a_rot1 + noise.alpha2 * a_trans)
        trans += n_trans * (noise.alpha3 * a_trans + noise.alpha4 * (a_rot1 + a_rot2))
        rot2 += n_rot2 * (noise.alpha1 * a_rot2 + noise.alpha2 * a_trans)
    rot1 *= 1.0 + noise.turn_scale_error
    rot2 *= 1.0 + noise.turn_scale_error
    rot2 += math.radians(noise.heading_drift_deg_per_m) * abs(trans)
    trans *= 1.0 + noise.distance_scale_error
    if induced_m:
        trans += math.copysign(induced_m, trans) if noise.induced_along_motion else induced_m
    if induced_rad:
        turn = rot1 + rot2
        rot2 += math.copysign(induced_rad, turn) if noise.induced_along_motion else induced_rad
    return Pose(trans * math.cos(rot1), trans * math.sin(rot1), add_angle(rot1, rot2))


def _induce_exact(
    increment: Pose, noise: OdometryNoise, induced_m: float, induced_rad: float
) -> Pose:
    """Only the induced error: exact arithmetic for pure moves and turns."""
    if induced_m:
        x, y = increment.x, increment.y
        if noise.induced_along_motion and x < 0.0:
            induced_m = -induced_m
        if y == 0.0:
            return Pose(x + induced_m, 0.0, increment.theta)
        signed_length = math.copysign(math.hypot(x, y), x)
        scale = (signed_length + induced_m) / signed_length
        return Pose(x * scale, y * scale, increment.theta)
    if induced_rad:
        if noise.induced_along_motion and increment.theta < 0.0:
            induced_rad = -induced_rad
        return Pose(increment.x, increment.y, add_angle(increment.theta, induced_rad))
    return increment


class OdometryReading(NamedTuple):
    """One odometry report: the increment (previous odometry frame) and the new pose."""

    increment: Pose
    pose: Pose

    @property
    def turn_rad(self) -> float:
        return self.increment.theta

    @property
    def distance_m(self) -> float:
        return math.hypot(self.increment.x, self.increment.y)


# A cell with less than this fraction of itself left counts as used up (float noise in the
# cut points must not start a new cell, and draw, a hair early or late).
_CELL_SLACK = 1e-9
# Standard normals drawn from the rng at a time (the order of use is the order of draws).
_NORMALS_BLOCK = 256
_PI = math.pi
_TWO_PI = 2.0 * math.pi


class Odometry:
    """Integrates the true motion into the odometry pose on a fixed grid along the path
    (see the module docstring): ``update(true_increment)`` after each bit of true motion,
    ``induce(kind, amount)`` at the end of an instruction (dataset 2's induced error).
    """

    def __init__(
        self,
        noise: OdometryNoise | None = None,
        rng: np.random.Generator | None = None,
        start: Pose | None = None,
    ) -> None:
        self.noise = n = noise if noise is not None else OdometryNoise()
        if n.is_random and rng is None:
            raise ValueError("Odometry: random noise needs an rng")
        self.rng = rng
        self.pose = start if start is not None else Pose()
        self._exact = not (n.is_random or n.is_biased)
        self._res_m = n.resolution_m
        self._res_rad = math.radians(n.resolution_deg)
        # Per unit of motion inside a cell: the random walk's slope (alpha / sqrt(cell))
        # times the cell's normal, so a whole cell has standard deviation alpha·sqrt(cell).
        self._head_per_m = n.alpha2 / math.sqrt(self._res_m)
        self._dist_per_m = n.alpha3 / math.sqrt(self._res_m)
        self._head_per_rad = n.alpha1 / math.sqrt(self._res_rad)
        self._dist_per_rad = n.alpha4 / math.sqrt(self._res_rad)
        self._drift_per_m = math.radians(n.heading_drift_deg_per_m)
        self._dist_scale = 1.0 + n.distance_scale_error
        self._turn_scale = 1.0 + n.turn_scale_error
        self._move_left = 0.0  # metres left in the current distance cell
        self._move_z = (0.0, 0.0)  # its (heading, distance) normals
        self._turn_left = 0.0  # radians left in the current angle cell
        self._turn_z = (0.0, 0.0)
        self._normals: list[float] = []
        self._next_normal = 0

    def update(self, true_increment: Pose) -> OdometryReading:
        """Integrate the true motion ``true_increment`` (in the robot frame where it
        began) and report the increment odometry saw; the pose is ``self.pose``.

        The motion is taken as turn, straight, turn (Thrun et al.'s rot1, trans, rot2:
        exact for pure moves and turns, the chord for a short arc); backwards motion is
        a reverse drive, not a half turn.
        """
        before = self.pose
        if self._exact:
            self.pose = before.compose(true_increment)
            return OdometryReading(true_increment, self.pose)
        rot1, trans, rot2 = _decompose(true_increment)
        pose = before
        if rot1:
            pose = self._turn(pose, rot1)
        if trans:
            pose = self._move(pose, trans)
        if rot2:
            pose = self._turn(pose, rot2)
        self.pose = pose
        return OdometryReading(before.between(pose), pose)

    def induce(self, kind: StepKind, amount: float) -> Pose | None:
        """Dataset 2's induced error for an instruction of ``kind`` that moved or turned by
        ``amount`` (m or rad; its sign gives the direction when ``induced_along_motion``).
        Returns the increment added to the odometry pose (None: none)."""
        n = self.noise
        if kind == "move" and n.induced_step_m:
            step = (
                math.copysign(n.induced_step_m, amount)
                if n.induced_along_motion
                else (n.induced_step_m)
            )
            added = Pose(step, 0.0, 0.0)
        elif kind == "turn" and n.induced_step_deg:
            rad = math.radians(n.induced_step_deg)
            step = math.copysign(rad, amount) if n.induced_along_motion else rad
            added = Pose(0.0, 0.0, step)
        else:
            return None
        self.pose = self.pose.compose(added)
        return added

    def _normal_pair(self) -> tuple[float, float]:
        if self.rng is None:
            return 0.0, 0.0
        k = self._next_normal
        if k + 2 > len(self._normals):
            self._normals = self.rng.standard_normal(_NORMALS_BLOCK).tolist()
            k = 0
        self._next_normal = k + 2
        return self._normals[k], self._normals[k + 1]

    def _move(self, pose: Pose, trans: float) -> Pose:
        # Cell by cell in plain floats, the same arithmetic as ``pose.compose(Pose(distance,
        # 0, heading))`` per piece (wrap included): one Pose at the end, as this loop runs
        # once per centimetre driven.
        x, y, theta = pose.x, pose.y, pose.theta
        sign = 1.0 if trans > 0.0 else -1.0
        remaining = abs(trans)
        res, slack = self._res_m, _CELL_SLACK * self._res_m
        scale, drift = self._dist_scale, self._drift_per_m
        dist_per_m, head_per_m = self._dist_per_m, self._head_per_m
        left, (z_head, z_dist) = self._move_left, self._move_z
        while remaining > 0.0:
            if left <= slack:
                left = res
                z_head, z_dist = self._normal_pair()
            piece = remaining if remaining <= left + slack else left
            distance = sign * piece * (scale + dist_per_m * z_dist)
            x += math.cos(theta) * distance
            y += math.sin(theta) * distance
            theta = (theta + piece * (drift + head_per_m * z_head) + _PI) % _TWO_PI - _PI
            left -= piece
            remaining -= piece
        self._move_left, self._move_z = left, (z_head, z_dist)
        return Pose(x, y, theta)

    def _turn(self, pose: Pose, angle: float) -> Pose:
        x, y, theta = pose.x, pose.y, pose.theta
        sign = 1.0 if angle > 0.0 else -1.0
        remaining = abs(angle)
        res, slack = self._res_rad, _CELL_SLACK * self._res_rad
        scale, head_per_rad, dist_per_rad = self._turn_scale, self._head_per_rad, self._dist_per_rad
        left, (z_head, z_dist) = self._turn_left, self._turn_z
        while remaining > 0.0:
            if left <= slack:
                left = res
                z_head, z_dist = self._normal_pair()
            piece = remaining if remaining <= left + slack else left
            slip = piece * dist_per_rad * z_dist  # forward error while turning (alpha4)
            if slip:
                x += math.cos(theta) * slip
                y += math.sin(theta) * slip
            turned = sign * piece * scale + piece * head_per_rad * z_head
            theta = (theta + turned + _PI) % _TWO_PI - _PI
            left -= piece
            remaining -= piece
        self._turn_left, self._turn_z = left, (z_head, z_dist)
        return Pose(x, y, theta)


def heading_variance_rad2(
    noise: OdometryNoise, distance_m: ArrayLike, turned_rad: ArrayLike
) -> FloatArray:
    """The variance (rad²) of odometry's random heading error over paths of
    ``distance_m`` metres driven and ``turned_rad`` radians turned (absolute values)."""
    d = np.abs(np.asarray(distance_m, dtype=np.float64))
    a = np.abs(np.asarray(turned_rad, dtype=np.float64))
    return noise.alpha1**2 * a + noise.alpha2**2 * d
