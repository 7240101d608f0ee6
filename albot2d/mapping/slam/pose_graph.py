"""The ``slam`` mapper's back end: a 2D pose graph of keyframes optimised by GTSAM.

Nodes are keyframe poses (``gtsam.Pose2``); the first is anchored by a tight prior.
Consecutive keyframes are joined by two factors: the scan-matching front end's relative
motion (under a robust kernel: scan matching now and then slips by a degree or two in a
corridor) and the wheel odometry's, each with a sigma growing with the motion (the wheel's
may get a robust kernel too, ``wheel_kernel``); by default the scan-matching factor's
position information takes the shape of its registration's Hessian (``odom_information=
"hessian_xy"``: along a corridor, where the scans do not fix the motion, the wheels do).
A verified loop closure (and a short-range constraint) adds a between factor whose
information matrix takes its shape from the registration's point-to-line Hessian (a
corridor fixes the position across it, not along it), under a robust kernel or GNC's
weights, so a false closure that slipped through verification is down-weighted instead of
bending the whole map.

Optimisation runs from the current estimate when a closure was added and every
``optimise_every`` keyframes (between runs a new keyframe is placed by composing the front
end's motion onto the latest estimate). By default (``optimizer="gnc"``) it is
Graduated Non-Convexity (Yang et al. 2020, GTSAM's ``GncLMOptimizer``): the chain
(prior, scan-matching and wheel factors) is known inliers, every closure a candidate whose
weight GNC decides jointly with all the others under a truncated least squares (or
Geman–McClure) loss; a closure is then Gaussian, as GNC replaces robust kernels by its
own (GTSAM drops a factor's ``Robust`` wrapper, so the chain is Gaussian too);
``optimizer="lm"`` is batch Levenberg–Marquardt with the kernels above.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from albot2d.errors import InputError
from albot2d.validation import check_non_negative, check_positive, check_positive_int

if TYPE_CHECKING:  # gtsam is an optional extra, imported when a PoseGraph is made
    import gtsam

__all__ = ["MISSING_GTSAM", "PoseGraph", "PoseGraphParams", "shaped_information"]

KERNELS = ("cauchy", "huber", "none")
OPTIMIZERS = ("lm", "gnc")
GNC_LOSSES = ("tls", "gm")
ODOM_INFORMATION = ("fixed", "hessian", "hessian_xy")
MISSING_GTSAM = "the slam mapper needs the optional extra: pip install 'albot2d[slam]' (gtsam)"


@dataclass(frozen=True, slots=True)
class PoseGraphParams:
    """Noise models and solver settings of the pose graph.

    - ``odom_sigma_m`` / ``odom_sigma_deg``: sigma of a scan-matching keyframe-to-keyframe
      factor at zero motion; ``odom_sigma_m_per_m`` / ``odom_sigma_deg_per_m`` add per metre
      moved; ``odom_kernel`` (``cauchy``, ``huber``, ``none``) its robust kernel and
      ``odom_kernel_width`` the kernel's width in sigmas.
    - ``wheel_sigma_m`` / ``wheel_sigma_deg`` (+ ``_per_m``, and ``wheel_sigma_deg_per_rad``
      per radian turned): the same for the wheel-odometry factor (Gaussian) on a robot
      with good odometry; the mapper raises them to what it measures (see ``slam.py``);
      ``wheel_kernel`` / ``wheel_kernel_width`` its robust kernel (wheel odometry slips too:
      a wheel that spun or a log's odometry jump is then out-voted like a scan-matching slip).
    - ``odom_information``: ``"fixed"`` (those sigmas on every axis) or ``"hessian"``: the
      scan-matching factor's information matrix shaped by the point-to-line Hessian of the
      two keyframes' scans aligned at the front end's motion (as ``loop_information`` does
      for closures; the best-constrained direction keeps the configured sigmas, a weaker
      one gets up to ``odom_max_sigma_ratio`` × them), so where scan matching is weakly
      constrained (along a corridor; a heading fixed by few, near points) the wheel
      odometry factor carries the motion; ``"hessian_xy"`` (the default): the same for
      the position only, the heading keeping its configured sigma.
    - ``loop_sigma_m`` / ``loop_sigma_deg``: sigma of a verified loop closure in its
      best-constrained direction; ``loop_information``: shape the closure's information
      matrix by the registration's Hessian (off: those sigmas on every axis), a direction
      the registration barely fixes getting up to ``loop_max_sigma_ratio`` × the sigma.
    - ``loop_kernel``: robust kernel on closures (``cauchy``, ``huber`` or ``none``) and its
      width ``loop_kernel_width`` (in sigmas).
    - ``max_iterations`` / ``relative_error_tol``: Levenberg–Marquardt stopping rules.
    - ``optimise_every``: keyframes between optimisations when no closure asks for one.
    - ``optimizer``: ``"gnc"`` (the default: Graduated Non-Convexity around
      Levenberg–Marquardt; the chain is known inliers, the closures and short-range
      constraints are weighed jointly; ``loop_kernel`` is then unused) or ``"lm"``
      (Levenberg–Marquardt alone, closures under ``loop_kernel``);
      ``gnc_loss``: ``"tls"`` (truncated least squares) or ``"gm"`` (Geman–McClure);
      ``gnc_inlier_probability``: a closure is an inlier while its cost is below the χ²₃
      quantile at this probability (GTSAM ``setInlierCostThresholdsAtProbability``).
    """

    odom_sigma_m: float = 0.02
    odom_sigma_deg: float = 0.1
    odom_sigma_m_per_m: float = 0.02
    odom_sigma_deg_per_m: float = 0.2
    odom_kernel: str = "cauchy"
    odom_kernel_width: float = 5.0
    odom_information: str = "hessian_xy"
    odom_max_sigma_ratio: float = 20.0
    wheel_sigma_m: float = 0.02
    wheel_sigma_deg: float = 0.3
    wheel_sigma_m_per_m: float = 0.05
    wheel_sigma_deg_per_m: float = 0.5
    wheel_sigma_deg_per_rad: float = 3.0
    wheel_kernel: str = "none"
    wheel_kernel_width: float = 5.0
    loop_sigma_m: float = 0.05
    loop_sigma_deg: float = 1.0
    loop_kernel: str = "cauchy"
    loop_kernel_width: float = 1.0
    loop_information: bool = True
    loop_max_sigma_ratio: float = 20.0
    max_iterations: int = 100
    relative_error_tol: float = 1e-6
    optimise_every: int = 10
    optimizer: str = "gnc"
    gnc_loss: str = "tls"
    gnc_inlier_probability: float = 0.99

    def __post_init__(self) -> None:
        check_positive(self, "odom_sigma_m", "odom_sigma_deg", "loop_sigma_m", "loop_sigma_deg",
                       "loop_kernel_width", "odom_kernel_width", "relative_error_tol",
                       "wheel_sigma_m", "wheel_sigma_deg", "wheel_kernel_width",
                       "loop_max_sigma_ratio", "odom_max_sigma_ratio")  # fmt: skip
        check_non_negative(self, "odom_sigma_m_per_m", "odom_sigma_deg_per_m",
                           "wheel_sigma_m_per_m", "wheel_sigma_deg_per_m",
                           "wheel_sigma_deg_per_rad")  # fmt: skip
        check_positive_int(self, "max_iterations", "optimise_every")
        if not 0.0 < self.gnc_inlier_probability < 1.0:
            raise InputError("PoseGraphParams.gnc_inlier_probability must be in (0, 1), "
                             f"got {self.gnc_inlier_probability!r}")  # fmt: skip
        choices: list[tuple[str, tuple[str, ...]]] = [
            (name, KERNELS) for name in ("loop_kernel", "odom_kernel", "wheel_kernel")
        ]
        choices += [
            ("optimizer", OPTIMIZERS),
            ("gnc_loss", GNC_LOSSES),
            ("odom_information", ODOM_INFORMATION),
        ]
        for name, allowed in choices:
            if getattr(self, name) not in allowed:
                raise InputError(
                    f"PoseGraphParams.{name} must be one of {', '.join(allowed)}, "
                    f"got {getattr(self, name)!r}"
                )


def shaped_information(
    information: NDArray[np.float64], sigmas: NDArray[np.float64], max_sigma_ratio: float
) -> NDArray[np.float64]:
    """A 3×3 information matrix with the shape of a registration's Hessian and the scale of
    ``sigmas`` (x, y, θ): the Hessian in units of those sigmas, scaled so its
    best-constrained direction has exactly those sigmas; a direction it constrains ``r``
    times less (eigenvalue ratio) gets ``1/√r`` times the sigma, at most
    ``max_sigma_ratio`` times. A Hessian that is not finite or has no positive eigenvalue
    gives the plain diagonal."""
    diagonal = np.diag(sigmas**-2)
    whitened = sigmas[:, None] * np.asarray(information, dtype=np.float64) * sigmas[None, :]
    if not np.all(np.isfinite(whitened)):
        return diagonal
    values, vectors = np.linalg.eigh(whitened)
    if not values[-1] > 0:
        return diagonal
    values = np.maximum(values / values[-1], max_sigma_ratio**-2)
    shaped = (vectors * values) @ vectors.T
    return np.asarray(shaped / sigmas[:, None] / sigmas[None, :])


class PoseGraph:
    """Keyframe poses, their factors, and the current optimised estimate (``(K, 3)``)."""

    def __init__(self, params: PoseGraphParams | None = None) -> None:
        try:
            import gtsam
        except ImportError as exc:
            raise InputError(MISSING_GTSAM) from exc
        self._gtsam: Any = gtsam
        self.params = params or PoseGraphParams()
        self._graph: Any = gtsam.NonlinearFactorGraph()
        self._estimate = np.zeros((0, 3))
        self.loops: list[tuple[int, int]] = []
        self._loop_factors: list[int] = []  # each closure's factor index in the graph
        self._loop_weights = np.ones(0)
        self.optimisations = 0
        self._pending = False
        self._since = 0
        self._marginals: Any = None
        self._marginals_key: tuple[int, ...] | None = None

    def __len__(self) -> int:
        return len(self._estimate)

    @property
    def estimate(self) -> NDArray[np.float64]:
        """``(K, 3)`` current keyframe poses (read-only view)."""
        view = self._estimate.view()
        view.flags.writeable = False
        return view

    def _diagonal(self, sigma_m: float, sigma_rad: float) -> Any:
        return self._gtsam.noiseModel.Diagonal.Sigmas(np.array([sigma_m, sigma_m, sigma_rad]))

    def _robust(self, kernel: str, width: float, noise: Any) -> Any:
        if kernel == "none":
            return noise
        m = self._gtsam.noiseModel.mEstimator
        estimator = (m.Cauchy if kernel == "cauchy" else m.Huber).Create(width)
        return self._gtsam.noiseModel.Robust.Create(estimator, noise)

    def add_keyframe(
        self,
        motion: NDArray[np.float64] | None,
        initial: NDArray[np.float64],
        wheel_motion: NDArray[np.float64] | None = None,
        wheel_floor: tuple[float, float] = (0.0, 0.0),
        information: NDArray[np.float64] | None = None,
    ) -> int:
        """Add a keyframe at ``initial``; ``motion``: its pose in the previous keyframe's frame
        by scan matching, ``wheel_motion`` by wheel odometry (None for the first keyframe,
        which is anchored there); ``wheel_floor``: lower bounds (m, rad) on the wheel
        factor's sigmas, e.g. measured on this robot; ``information``: the scan matching's
        point-to-line Hessian of ``motion`` (used with ``odom_information="hessian"``).
        Returns its index."""
        g, p = self._gtsam, self.params
        k = len(self._estimate)
        if k == 0:
            prior = self._diagonal(1e-4, 1e-5)
            self._graph.add(g.PriorFactorPose2(0, g.Pose2(*initial), prior))
        else:
            if motion is None:
                raise ValueError("every keyframe after the first needs its motion")
            d = float(np.hypot(motion[0], motion[1]))
            sigmas = np.array(
                [p.odom_sigma_m + p.odom_sigma_m_per_m * d] * 2
                + [np.radians(p.odom_sigma_deg + p.odom_sigma_deg_per_m * d)]
            )
            if p.odom_information != "fixed" and information is not None:
                noise = self._gtsam.noiseModel.Gaussian.Information(
                    self.odom_information_matrix(information, sigmas)
                )
            else:
                noise = self._gtsam.noiseModel.Diagonal.Sigmas(sigmas)
            noise = self._robust(p.odom_kernel, p.odom_kernel_width, noise)
            self._graph.add(g.BetweenFactorPose2(k - 1, k, g.Pose2(*motion), noise))
            if wheel_motion is not None:
                dw = float(np.hypot(wheel_motion[0], wheel_motion[1]))
                turn = abs(float(wheel_motion[2]))
                noise = self._diagonal(
                    max(p.wheel_sigma_m + p.wheel_sigma_m_per_m * dw, wheel_floor[0]),
                    max(np.radians(p.wheel_sigma_deg + p.wheel_sigma_deg_per_m * dw
                                   + p.wheel_sigma_deg_per_rad * turn), wheel_floor[1]),
                )  # fmt: skip
                noise = self._robust(p.wheel_kernel, p.wheel_kernel_width, noise)
                self._graph.add(g.BetweenFactorPose2(k - 1, k, g.Pose2(*wheel_motion), noise))
                self._since += 1
                self._pending |= self._since >= p.optimise_every
        self._estimate = np.vstack([self._estimate, np.asarray(initial, dtype=np.float64)])
        return k

    def add_loop(
        self,
        i: int,
        j: int,
        relative: NDArray[np.float64],
        information: NDArray[np.float64] | None = None,
    ) -> None:
        """A verified closure: keyframe ``j`` seen from keyframe ``i`` at ``relative``.

        ``information``: the registration's Hessian (``registration_information``), used for
        its shape when ``loop_information`` is on; see ``loop_noise``."""
        g, p = self._gtsam, self.params
        noise = self.loop_noise(information)
        if p.optimizer == "lm":
            noise = self._robust(p.loop_kernel, p.loop_kernel_width, noise)
        self._loop_factors.append(int(self._graph.size()))
        self._graph.add(g.BetweenFactorPose2(i, j, g.Pose2(*relative), noise))
        self.loops.append((i, j))
        self._loop_weights = np.append(self._loop_weights, 1.0)
        self._pending = True

    @property
    def factor_graph(self) -> gtsam.NonlinearFactorGraph:
        """The GTSAM factor graph itself (the first keyframe's prior, then each keyframe's
        scan-matching and wheel factors and the closures, in the order they were added), for
        readers such as the g2o export; change it only through this class."""
        return self._graph

    @property
    def loop_factor_indices(self) -> tuple[int, ...]:
        """Each closure's factor index in ``factor_graph`` (order of ``loops``)."""
        return tuple(self._loop_factors)

    @property
    def loop_weights(self) -> NDArray[np.float64]:
        """Each closure's weight (order of ``loops``) after the last optimisation: GNC's
        (0: rejected as an outlier, 1: inlier); 1 for every closure under ``"lm"`` and for
        a closure not yet optimised."""
        return self._loop_weights.copy()

    def odom_information_matrix(
        self, information: NDArray[np.float64], sigmas: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        """A scan-matching chain factor's 3×3 information matrix (``odom_information``):
        ``"hessian"`` the Hessian's shape at the scale of ``sigmas`` (``shaped_information``);
        ``"hessian_xy"`` that for the position alone (the Hessian's position block, i.e.
        what the scans fix with the heading known), the heading at its configured sigma."""
        ratio = self.params.odom_max_sigma_ratio
        if self.params.odom_information == "hessian":
            return shaped_information(information, sigmas, ratio)
        out = np.diag(sigmas**-2)
        out[:2, :2] = shaped_information(np.asarray(information)[:2, :2], sigmas[:2], ratio)
        return out

    def loop_noise(self, information: NDArray[np.float64] | None) -> Any:
        """A closure's Gaussian noise model (``loop_information_matrix``)."""
        information = self.loop_information_matrix(information)
        return self._gtsam.noiseModel.Gaussian.Information(information)

    def loop_information_matrix(
        self, information: NDArray[np.float64] | None
    ) -> NDArray[np.float64]:
        """A closure's 3×3 information matrix. Without ``information`` (or with
        ``loop_information`` off): ``loop_sigma_m``/``loop_sigma_deg`` on every axis. With
        it: the Hessian in units of those sigmas, scaled so its best-constrained direction
        has exactly those sigmas; a direction it constrains ``r`` times less (eigenvalue
        ratio) gets ``1/√r`` times the sigma, at most ``loop_max_sigma_ratio`` times. The
        shape says what the registration fixed (a corridor fixes the cross-corridor
        position and the heading, not the position along it); the scale stays the
        configured one, as a raw ICP Hessian is known to be overconfident (neighbouring
        points' errors are correlated)."""
        p = self.params
        sigmas = np.array([p.loop_sigma_m, p.loop_sigma_m, np.radians(p.loop_sigma_deg)])
        if information is None or not p.loop_information:
            return np.diag(sigmas**-2)
        return shaped_information(information, sigmas, p.loop_max_sigma_ratio)

    def relative_covariance(self, a: int, b: int) -> NDArray[np.float64] | None:
        """Covariance (3×3) of keyframe ``b``'s pose in ``a``'s frame under the graph as it
        stands, linearised at the current estimate (GTSAM ``Marginals``; GTSAM's Pose2
        local coordinates, a perturbation on the right): how far the current estimate of
        that relative pose may be off. None if the graph is indeterminate there."""
        g = self._gtsam
        key = (int(self._graph.size()), len(self._estimate), self.optimisations)
        if self._marginals_key != key:
            try:
                self._marginals = g.Marginals(self._graph, self._values())
            except RuntimeError:
                self._marginals = None
            self._marginals_key = key
        if self._marginals is None:
            return None
        joint = self._marginals.jointMarginalCovariance([a, b])
        caa, cab, cbb = joint.at(a, a), joint.at(a, b), joint.at(b, b)
        # between(x_a, x_b) perturbed: δ = -Ad(rel⁻¹) ξ_a + ξ_b
        rel = g.Pose2(*self._estimate[a]).between(g.Pose2(*self._estimate[b]))
        ja = -rel.inverse().AdjointMap()
        cov = ja @ caa @ ja.T + ja @ cab + cab.T @ ja.T + cbb
        cov = 0.5 * (cov + cov.T)
        return cov if np.all(np.isfinite(cov)) else None

    def _values(self) -> Any:
        g = self._gtsam
        values = g.Values()
        for k, pose in enumerate(self._estimate):
            values.insert(k, g.Pose2(*pose))
        return values

    def optimise(self) -> bool:
        """Levenberg–Marquardt from the current estimate if closures were added since the
        last run, or ``optimise_every`` keyframes with wheel odometry; returns whether it
        ran."""
        if not self._pending:
            return False
        g, p = self._gtsam, self.params
        values = self._values()
        lm = g.LevenbergMarquardtParams()
        lm.setMaxIterations(p.max_iterations)
        lm.setRelativeErrorTol(p.relative_error_tol)
        if p.optimizer == "gnc" and self._loop_factors:
            result = self._optimise_gnc(values, lm)
        else:
            result = g.LevenbergMarquardtOptimizer(self._graph, values, lm).optimize()
        out = np.empty_like(self._estimate)
        for k in range(len(out)):
            pose = result.atPose2(k)
            out[k] = (pose.x(), pose.y(), pose.theta())
        if np.all(np.isfinite(out)):
            self._estimate = out
        self.optimisations += 1
        self._pending = False
        self._since = 0
        return True

    def _optimise_gnc(self, values: Any, lm: Any) -> Any:
        """GNC from the current estimate: every factor but the closures is a known inlier;
        the closures' weights are kept (``loop_weights``)."""
        g, p = self._gtsam, self.params
        loops = set(self._loop_factors)
        params = g.GncLMParams(lm)
        params.setLossType(g.GncLossType.TLS if p.gnc_loss == "tls" else g.GncLossType.GM)
        params.setKnownInliers([k for k in range(int(self._graph.size())) if k not in loops])
        optimizer = g.GncLMOptimizer(self._graph, values, params)
        optimizer.setInlierCostThresholdsAtProbability(p.gnc_inlier_probability)
        result = optimizer.optimize()
        weights = np.asarray(optimizer.getWeights(), dtype=np.float64)
        self._loop_weights = weights[self._loop_factors]
        return result
