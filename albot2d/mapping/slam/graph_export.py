"""The ``slam`` mapper's pose graph as plain data, for export (g2o files).

``pose_graph_edges(graph)`` lists every relative-pose factor of a ``PoseGraph``
(scan-matching chain, wheel odometry, loop closures and short-range constraints) with its
measurement and the information matrix its *last optimisation* effectively used:

- under GNC (the default back end, once there are closures) each closure's Gaussian
  information times its GNC weight, and the chain's Gaussian information (GNC drops
  robust kernels);
- under Levenberg–Marquardt a robust factor's information times its kernel's weight at
  the current estimate (iteratively reweighted least squares: at an optimum of the
  robust graph that weighted Gaussian graph has the same optimum).

So a plain Gaussian solver (g2o, ``gtsam.readG2o``) re-optimising the exported graph from
the mapper's estimate stays at that estimate once the mapper's last optimisation came after
its last keyframe. A closure GNC rejected outright (weight 0) constrains nothing and is
left out (``PoseGraphEdges.dropped``).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from albot2d.mapping.slam.pose_graph import PoseGraph

__all__ = ["EDGE_KINDS", "PoseGraphEdges", "pose_graph_edges"]

EDGE_KINDS = ("scan_matching", "wheel", "loop")


class PoseGraphEdges(NamedTuple):
    """Relative-pose edges: ``ij (E, 2)`` keyframe ids, ``measurements (E, 3)`` (pose of
    ``j`` in ``i``'s frame), ``information (E, 3, 3)`` (x, y, θ), ``kinds (E,)`` (one of
    ``EDGE_KINDS``) and how many zero-weight closures were ``dropped``."""

    ij: NDArray[np.int64]
    measurements: NDArray[np.float64]
    information: NDArray[np.float64]
    kinds: tuple[str, ...]
    dropped: int


def pose_graph_edges(graph: PoseGraph) -> PoseGraphEdges:
    """Every relative-pose factor of ``graph`` with its effective information (see the
    module docstring)."""
    import gtsam

    factors = graph.factor_graph
    loop_index = {f: k for k, f in enumerate(graph.loop_factor_indices)}
    weights = graph.loop_weights
    gnc = graph.params.optimizer == "gnc" and bool(loop_index)
    values = gtsam.Values()
    for k, pose in enumerate(graph.estimate):
        values.insert(k, gtsam.Pose2(*pose))
    ij: list[tuple[int, int]] = []
    measurements: list[tuple[float, float, float]] = []
    information: list[NDArray[np.float64]] = []
    kinds: list[str] = []
    dropped = 0
    for f in range(int(factors.size())):
        factor = factors.at(f)
        if not isinstance(factor, gtsam.BetweenFactorPose2):
            continue  # the first keyframe's prior: the g2o reader fixes a vertex itself
        i, j = (int(k) for k in factor.keys())  # noqa: SIM118 (a gtsam KeyVector)
        noise: Any = factor.noiseModel()  # (gtsam stubs type it as the base class)
        weight = 1.0
        if isinstance(noise, gtsam.noiseModel.Robust):
            base = noise.noise()
            kernel: Any = noise.robust()
            if not gnc:
                distance = float(np.linalg.norm(base.whiten(factor.unwhitenedError(values))))
                weight = float(kernel.weight(distance))
            noise = base
        if f in loop_index:
            kind = "loop"
            weight *= float(weights[loop_index[f]]) if gnc else 1.0
        else:  # consecutive keyframes: the scan-matching factor, then the wheel's
            kind = "wheel" if ij and ij[-1] == (i, j) and kinds[-1] == "scan_matching" else (
                "scan_matching")  # fmt: skip
        if weight == 0.0:
            dropped += 1
            continue
        m = factor.measured()
        ij.append((i, j))
        measurements.append((m.x(), m.y(), m.theta()))
        matrix = weight * np.asarray(noise.information(), dtype=np.float64)
        information.append(0.5 * (matrix + matrix.T))
        kinds.append(kind)
    return PoseGraphEdges(
        np.array(ij, dtype=np.int64).reshape(-1, 2),
        np.array(measurements, dtype=np.float64).reshape(-1, 3),
        np.array(information, dtype=np.float64).reshape(-1, 3, 3),
        tuple(kinds),
        dropped,
    )
