"""The paper's Albot_x as SLAM robots (optional ``[slam]`` extra: kiss-icp, gtsam).

- ``LoopClosingSLAM`` (``slam``): the scan-matching front end below, keyframes, loop
  closures found by proximity and short-range constraints to the keyframe 3 m back, each
  verified by registration (``loop_closure``), and a GTSAM pose graph solved by GNC
  (``pose_graph``); every view is placed by its keyframe's optimised pose.
- ``ScanMatchingSLAM`` (``scan_odometry``): the front end alone.

Front end (``KissIcpOdometry``, ``front_end``): every scan is registered against a local
voxel map by KISS-ICP, with the odometry increment as the prediction. Both mappers keep
every view's surfaces (same surface extraction as ``NaiveIntegration``), so the maps are
comparable.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from albot2d.frames import Frame
from albot2d.geometry import (
    Pose,
    between_arrays,
    compose_arrays,
    transform_points,
    wrap_angle,
)
from albot2d.mapping.baselines import ViewIntegrator as _ViewIntegrator
from albot2d.mapping.protocol import MapperCounts, MapSnapshot, StageTimer
from albot2d.mapping.slam.front_end import (
    KissIcpOdometry,
    ScanMatchingParams,
)
from albot2d.mapping.slam.loop_closure import ClosureCheck, LoopClosureParams, LoopVerifier
from albot2d.mapping.slam.pose_graph import PoseGraph, PoseGraphParams
from albot2d.perception import ExtractionParams, extract_surfaces
from albot2d.validation import check_positive, check_positive_int

__all__ = [
    "LoopClosingSLAM",
    "ScanMatchingSLAM",
    "SlamParams",
    "transform_points_each",
]


class ScanMatchingSLAM(_ViewIntegrator):
    """Albot_x's front end alone: views placed at KISS-ICP poses (odometry as the prior).

    Counts: ``triangulations`` are the views localised by scan matching (the sensor
    corrected the odometry), ``path_integrations`` those placed by odometry alone.
    """

    name = "scan_odometry"

    def __init__(
        self,
        params: ScanMatchingParams | None = None,
        extraction: ExtractionParams | None = None,
    ) -> None:
        super().__init__(extraction)
        self.params = params or ScanMatchingParams()
        self.front_end = KissIcpOdometry(self.params, self.timer)

    def _source_pose(self, frame: Frame) -> Pose:
        return Pose.from_array(self.front_end.register(frame))

    def counts(self) -> MapperCounts:
        n = len(self._poses)
        fe = self.front_end
        return MapperCounts(n, n, triangulations=fe.matched,
                            path_integrations=fe.dead_reckoned)  # fmt: skip


@dataclass(frozen=True, slots=True)
class SlamParams:
    """The ``slam`` mapper's settings: front end, loop closures, pose graph, whether wheel
    odometry joins scan matching between keyframes (``use_wheel_odometry``), and over how
    many recent keyframes its disagreement with scan matching is measured to floor its
    sigmas (``wheel_noise_window``; the floor is ``wheel_noise_factor`` × the median
    disagreement: 4.5 ≈ 3 robust sigmas, as wheel odometry's error is systematic as much
    as random: a heading drift per metre and a turn-scale error are small consistent
    errors that neither a robust kernel nor the median sees; 1.4826, one robust sigma,
    maps dataset 1 better and dataset 3 worse, see docs/albot-x.md)."""

    scan_matching: ScanMatchingParams = field(default_factory=ScanMatchingParams)
    loops: LoopClosureParams = field(default_factory=LoopClosureParams)
    graph: PoseGraphParams = field(default_factory=PoseGraphParams)
    use_wheel_odometry: bool = True
    wheel_noise_window: int = 100
    wheel_noise_factor: float = 4.5

    def __post_init__(self) -> None:
        check_positive_int(self, "wheel_noise_window")
        check_positive(self, "wheel_noise_factor")


class LoopClosingSLAM:
    """Albot_x as a full SLAM robot: KISS-ICP front end, verified loop closures, GTSAM graph.

    Every frame is localised by the front end. A keyframe is taken every
    ``keyframe_distance_m`` / ``keyframe_angle_deg`` of motion; it is a node of the pose
    graph, joined to the previous one by the front end's motion, and the place where loop
    closures are searched for (``albot2d.mapping.slam.loop_closure``). Every other frame hangs off
    its keyframe by the front end's relative pose, so ``trajectory()`` and
    ``global_map()`` (every view's surfaces, none deleted) follow the optimised keyframes:
    the map changes shape when a loop closes.

    Beyond loop closures (both on by default, docs/albot-x.md "The defaults"): short-range
    constraints (``LoopClosureParams.local_separation_m``, 3 m: each new keyframe also
    verified against the keyframe that far back, ``propose_local``) and scan-matching chain
    factors whose position information is shaped by the registration's Hessian
    (``PoseGraphParams.odom_information="hessian_xy"``).

    Counts: ``local_maps`` are the keyframes, ``triangulations`` the views localised by
    scan matching, ``path_integrations`` those placed by odometry alone; ``slam_stats()``
    adds the loop-closure counts (and the short-range constraints' when on).
    """

    name = "slam"

    def __init__(
        self,
        params: SlamParams | None = None,
        extraction: ExtractionParams | None = None,
    ) -> None:
        self.params = params or SlamParams()
        self.extraction = extraction or ExtractionParams()
        self.timer = StageTimer()
        self.graph = PoseGraph(self.params.graph)
        self.front_end = KissIcpOdometry(self.params.scan_matching, self.timer)
        self.verifier = LoopVerifier(
            self.params.loops, np.asarray(self.params.scan_matching.layer_heights_m)
        )
        self.checks: list[ClosureCheck] = []
        self.local_checks: list[ClosureCheck] = []  # short-range constraints
        self._origin: NDArray[np.float64] | None = None
        self._last_fe = np.zeros(3)
        self._path_m = 0.0
        self._last_closure_m = -np.inf  # path (front end) at the last accepted closure
        # per view
        self._segments: list[NDArray[np.float64]] = []
        self._view_kf: list[int] = []
        self._offsets: list[NDArray[np.float64]] = []
        self._map_cache: tuple[int, int, MapSnapshot] | None = None
        # per keyframe
        self._kf_fe: list[NDArray[np.float64]] = []
        self._kf_points: list[NDArray[np.float64]] = []
        self._kf_path_m: list[float] = []
        self._kf_odom: list[NDArray[np.float64]] = []
        self._wheel_gaps: list[tuple[float, float]] = []
        self.keyframe_rows: list[int] = []  # the view (0-based, in observed order) of each

    # -- the mapper protocol -------------------------------------------------------------
    def observe(self, frame: Frame) -> None:
        with self.timer.stage("extraction"):
            view = extract_surfaces(frame.scan, self.extraction)
        raw = self.front_end.register(frame)
        if self._origin is None:
            self._origin = raw
        fe = between_arrays(self._origin, raw)
        self._path_m += float(np.hypot(*(fe[:2] - self._last_fe[:2])))
        self._last_fe = fe
        if self._needs_keyframe(fe):
            self._add_keyframe(fe, frame.scan.points(), frame.odom_pose.as_array())
        self._segments.append(view.segments)
        self._view_kf.append(len(self._kf_fe) - 1)
        self._offsets.append(between_arrays(self._kf_fe[-1], fe))

    def pose(self) -> Pose:
        if not self._segments:
            return Pose()
        return Pose.from_array(compose_arrays(self.graph.estimate[self._view_kf[-1]],
                                              self._offsets[-1]))  # fmt: skip

    def trajectory(self) -> NDArray[np.float64]:
        if not self._segments:
            return np.zeros((0, 3))
        return compose_arrays(self.graph.estimate[np.array(self._view_kf)],
                              np.array(self._offsets))  # fmt: skip

    def global_map(self, at_update: int | None = None) -> MapSnapshot:
        """Every view's surfaces placed by the current (optimised) poses. ``at_update`` is
        accepted for the protocol; a SLAM map has no history of deletions."""
        key = (len(self._segments), self.graph.optimisations)
        if self._map_cache is not None and self._map_cache[:2] == key:
            return self._map_cache[2]
        with self.timer.stage("global_map"):
            counts = np.array([len(s) for s in self._segments], dtype=np.int64)
            owner = np.repeat(np.arange(len(counts)), counts)
            segs = np.concatenate(self._segments) if len(owner) else np.zeros((0, 4))
            poses = self.trajectory()[owner]
            a = transform_points_each(poses, segs[:, :2])
            b = transform_points_each(poses, segs[:, 2:])
            snap = MapSnapshot(np.column_stack([a, b]).reshape(-1, 4), owner + 1)
        self._map_cache = (*key, snap)
        return snap

    def counts(self) -> MapperCounts:
        fe = self.front_end
        return MapperCounts(len(self._segments), len(self._kf_fe), triangulations=fe.matched,
                            path_integrations=fe.dead_reckoned)  # fmt: skip

    def timings_ms(self) -> dict[str, float]:
        return self.timer.mean_ms_per(len(self._segments))

    # -- loop closing ----------------------------------------------------------------------
    def slam_stats(self) -> dict[str, int]:
        """Keyframes, loop-closure candidates verified / accepted / rejected, optimisations;
        with short-range constraints their candidates and accepted ones; with GNC also the
        accepted closures it down-weighted (weight < 0.5)."""
        accepted = sum(c.accepted for c in self.checks)
        stats = {
            "keyframes": len(self._kf_fe),
            "loop_candidates": len(self.checks),
            "loop_closures_accepted": accepted,
            "loop_closures_rejected": len(self.checks) - accepted,
            "optimisations": self.graph.optimisations,
        }
        if self.params.loops.local_separation_m is not None:
            stats["local_candidates"] = len(self.local_checks)
            stats["local_constraints_accepted"] = sum(c.accepted for c in self.local_checks)
        if self.params.graph.optimizer == "gnc":
            # accepted closures GNC weighs as outliers in the last optimisation
            stats["loop_closures_down_weighted"] = int(np.sum(self.graph.loop_weights < 0.5))
        return stats

    def verify_closure(
        self, i: int, j: int, guess: NDArray[np.float64] | None = None, *,
        local: bool = False,
    ) -> ClosureCheck:  # fmt: skip
        """Register keyframe ``i``'s local map onto keyframe ``j``'s (``guess``: ``i``'s pose
        in ``j``'s frame to start from; default the current estimate; the correction is
        always judged against the current estimate). ``local``: a short-range constraint
        under ``LoopClosureParams.local_query="scan"`` (keyframe ``i``'s own scan onto the
        keyframes up to ``j``). Adds nothing."""
        n, est = self.params.loops.submap_keyframes, self.graph.estimate
        if not (0 <= j < len(est) and 0 <= i < len(est) and i != j):
            raise ValueError(f"keyframes {i}, {j}: need two different ones of {len(est)}")
        estimate = between_arrays(est[j], est[i])
        guess = estimate if guess is None else np.asarray(guess, dtype=np.float64)
        if local and self.params.loops.local_query == "scan":
            query_ids: Any = [i]
            target_ids = list(range(max(0, j - n + 1), j + 1))
        else:
            query_ids = range(max(0, i - n + 1), i + 1)
            lo, hi = max(0, j - n), min(len(est), j + n + 1)
            target_ids = [k for k in range(lo, hi) if abs(k - i) >= n]
        query = self._submap(query_ids, i)
        target = self._submap(target_ids, j)
        path = abs(self._kf_path_m[i] - self._kf_path_m[j])
        scan = self._kf_points[i]
        check = self.verifier.check(i, j, query, scan, target, guess, path, estimate)
        if self.params.loops.gate == "chi2" and check.accepted:
            check = self.chi2_gate(check)
        return check

    def chi2_gate(self, check: ClosureCheck) -> ClosureCheck:
        """Judge a closure that registered well by its innovation: its relative pose
        against the current estimate's, under the estimate's covariance (the graph's
        marginals) plus the closure's own (the information it would enter the graph
        with). A test of individual compatibility: a closure the graph's uncertainty
        cannot explain is a look-alike place or a registration that slid."""
        i, j, est = check.i, check.j, self.graph.estimate
        covariance = self.graph.relative_covariance(i, j)
        if covariance is None:
            return replace(check, accepted=False, reason="no covariance for the χ² gate")
        closure = np.linalg.inv(self.graph.loop_information_matrix(check.information))
        innovation = between_arrays(check.relative, between_arrays(est[i], est[j]))
        innovation[2] = wrap_angle(innovation[2])
        chi2 = float(innovation @ np.linalg.solve(covariance + closure, innovation))
        limit = self.params.loops.gate_chi2
        reason = ""
        if chi2 > limit:
            reason = (f"χ² gate: innovation {chi2:.1f} > {limit:g} (correction "
                      f"{check.correction_m:.2f} m / {check.correction_deg:.1f}°)")  # fmt: skip
        return replace(check, accepted=not reason, reason=reason, chi2=chi2)

    def propose_closure(
        self, i: int, j: int, guess: NDArray[np.float64] | None = None
    ) -> ClosureCheck:
        """Verify a candidate; if accepted, add it to the graph and optimise."""
        with self.timer.stage("loop_closure"):
            check = self.verify_closure(i, j, guess)
        self.checks.append(check)
        if check.accepted:
            self._last_closure_m = self._kf_path_m[check.i]
            self.graph.add_loop(i, j, check.relative, check.information)
            with self.timer.stage("optimisation"):
                self.graph.optimise()
        return check

    def propose_local(self, i: int, j: int) -> ClosureCheck:
        """A short-range constraint (``LoopClosureParams.local_separation_m``): keyframe
        ``i`` registered against the keyframe ``j`` a few metres back by the closure
        verifier and gate; if accepted it joins the graph as a closure does (same noise
        model and kernel), without touching the loop-closure spacing or counts."""
        with self.timer.stage("loop_closure"):
            check = self.verify_closure(i, j, local=True)
        self.local_checks.append(check)
        if check.accepted:
            self.graph.add_loop(i, j, check.relative, check.information)
        return check

    def _local_target(self, i: int) -> int | None:
        """The newest keyframe at least ``local_separation_m`` of path before keyframe
        ``i`` (None when off, too early, or ``i``'s scan is too sparse)."""
        sep = self.params.loops.local_separation_m
        if sep is None or len(self._kf_points[i]) < self.params.scan_matching.min_points:
            return None
        back = np.flatnonzero(self._kf_path_m[i] - np.array(self._kf_path_m[:i]) >= sep)
        return int(back[-1]) if len(back) else None

    def _submap(self, ids: Any, frame_kf: int) -> NDArray[np.float64]:
        est = self.graph.estimate
        parts = [transform_points(between_arrays(est[frame_kf], est[k]), self._kf_points[k])
                 for k in ids]  # fmt: skip
        return np.concatenate(parts) if parts else np.zeros((0, 2))

    def _needs_keyframe(self, fe: NDArray[np.float64]) -> bool:
        if not self._kf_fe:
            return True
        p = self.params.loops
        motion = between_arrays(self._kf_fe[-1], fe)
        return bool(np.hypot(motion[0], motion[1]) >= p.keyframe_distance_m
                    or abs(motion[2]) >= np.radians(p.keyframe_angle_deg))  # fmt: skip

    def _add_keyframe(
        self, fe: NDArray[np.float64], points: NDArray[np.float64], odom: NDArray[np.float64]
    ) -> None:
        if self._kf_fe:
            motion = between_arrays(self._kf_fe[-1], fe)
            wheel = between_arrays(self._kf_odom[-1], odom)
            # How far wheel odometry strays from scan matching on this robot: a multiple of
            # the median of their disagreement over the recent keyframes floors the wheel
            # factor's sigmas, so poor odometry (a real log) is not over-trusted.
            gap = between_arrays(motion, wheel)
            self._wheel_gaps.append((float(np.hypot(gap[0], gap[1])), abs(float(gap[2]))))
            recent = np.array(self._wheel_gaps[-self.params.wheel_noise_window :])
            floor = self.params.wheel_noise_factor * np.median(recent, axis=0)
            information = None
            if self.params.graph.odom_information != "fixed":
                with self.timer.stage("chain_information"):
                    information = self.verifier.chain_information(
                        motion, self._kf_points[-1], np.asarray(points, dtype=np.float64)
                    )
            self.graph.add_keyframe(
                motion, compose_arrays(self.graph.estimate[-1], motion),
                wheel if self.params.use_wheel_odometry else None, (floor[0], floor[1]),
                information,
            )  # fmt: skip
        else:
            self.graph.add_keyframe(None, fe)
        self._kf_fe.append(fe)
        self._kf_odom.append(odom)
        self._kf_points.append(np.asarray(points, dtype=np.float64))
        self._kf_path_m.append(self._path_m)
        self.keyframe_rows.append(len(self._segments))
        i = len(self._kf_fe) - 1
        for j in self._candidates(i):
            self.propose_closure(i, j)
        local = self._local_target(i)
        if local is not None:
            self.propose_local(i, local)
        with self.timer.stage("optimisation"):
            self.graph.optimise()  # runs only when due

    def _candidates(self, i: int) -> list[int]:
        """Older keyframes near keyframe ``i`` under the current estimate, nearest first."""
        p = self.params.loops
        if len(self._kf_points[i]) < self.params.scan_matching.min_points or i == 0:
            return []
        if self._kf_path_m[i] - self._last_closure_m < p.closure_spacing_m:
            return []
        est = self.graph.estimate
        path = self._kf_path_m[i] - np.array(self._kf_path_m[:i])
        radius = np.minimum(p.search_radius_m + p.search_radius_per_m * path,
                            p.max_search_radius_m)  # fmt: skip
        dist = np.hypot(*(est[:i, :2] - est[i, :2]).T)
        ok = (path >= p.min_separation_m) & (dist <= radius)
        order = np.flatnonzero(ok)[np.argsort(dist[ok], kind="stable")]
        return [int(j) for j in order[: p.max_candidates]]


def transform_points_each(
    poses: NDArray[np.float64], points: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Point ``k`` mapped from the frame of ``poses[k]`` into its parent frame (``(N, 2)``)."""
    c, s = np.cos(poses[:, 2]), np.sin(poses[:, 2])
    x, y = points[:, 0], points[:, 1]
    return np.column_stack([poses[:, 0] + c * x - s * y, poses[:, 1] + s * x + c * y])
