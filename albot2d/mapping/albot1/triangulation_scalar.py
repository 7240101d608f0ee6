"""Triangulation in plain Python floats for the common case of a few tracked surfaces.

Owns the scalar twin of ``triangulation.triangulate``'s array path, for fewer than eight
surfaces with the default heuristics (nearest to path integration, the outlier heuristic,
``heading="weighted"``). Per call numpy's small-array overhead cost more than the work
(160 µs against 43 µs here). The transcendental functions stay numpy's (this CPU's
vectorised ``arctan2``/``cos``/``sin``/``hypot`` differ from ``math``'s in the last bit), so
``tests/test_triangulation_small.py`` holds the two paths equal bit for bit. The rest runs
in Python floats, which round as numpy's float64 does (``%`` is numpy's remainder, see
``wrap_angle``).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from albot2d.compiled import compiled_kernel
from albot2d.geometry import Pose
from albot2d.perception.surfaces import Surfaces

if TYPE_CHECKING:
    from albot2d.mapping.albot1.triangulation import TriangulationParams

__all__ = ["triangulate_small", "triangulate_small_python"]

_TWO_PI = 2.0 * math.pi


def _wrap(a: float) -> float:
    return (a + math.pi) % _TWO_PI - math.pi


def _sum(values: list[float]) -> float:
    total = 0.0
    for v in values:
        total += v
    return total


def _fit_weights(surfaces: Surfaces, index: list[int]) -> list[float]:
    """``_fit_weight`` in scalars: max(n · L², 1e-12) with n the beams (1 without)."""
    segs = surfaces.segments
    length = np.hypot(segs[:, 2] - segs[:, 0], segs[:, 3] - segs[:, 1]).tolist()
    beams = surfaces.beams.tolist()
    out = []
    for i in index:
        b0, b1 = beams[i]
        n = float(b1 - b0 + 1) if b0 >= 0 else 1.0
        out.append(max(n * (length[i] * length[i]), 1e-12))
    return out


def _direction_differences(ls: np.ndarray, cs: np.ndarray) -> np.ndarray:
    """Each local surface's direction minus its current one's (numpy's ``arctan2``: both
    paths start from these same numbers)."""
    return np.arctan2(ls[:, 3] - ls[:, 1], ls[:, 2] - ls[:, 0]) - np.arctan2(
        cs[:, 3] - cs[:, 1], cs[:, 2] - cs[:, 0]
    )


def triangulate_small(
    local: Surfaces,
    current: Surfaces,
    pi: Pose,
    params: TriangulationParams,
    k: int,
    gate_m: float,
    gate_deg: float,
) -> Pose | None:
    """``triangulate`` for fewer than ``triangulation._SMALL`` surfaces with the default
    heuristics (``triangulation._small_path_covers``): the same float operations in the same
    order as the array path, so the same pose bit for bit; in one compiled call when numba
    imports (``triangulation_numba``), else in Python floats (``triangulate_small_python``)."""
    kernel = compiled_kernel("albot2d.mapping.albot1.triangulation_numba", "triangulate_kernel")
    if kernel is None or not len(local):
        return triangulate_small_python(local, current, pi, params, k, gate_m, gate_deg)
    ls, cs = local.segments, current.segments
    ang_l = _direction_differences(ls, cs)
    found, x, y, heading = kernel(
        ang_l, ls, cs, local.localisable, current.localisable, local.beams, current.beams,
        float(pi.x), float(pi.y), float(pi.theta), k * gate_m, k * math.radians(gate_deg),
        math.radians(params.heading_consensus_deg), bool(params.use_outlier_heuristic),
    )  # fmt: skip
    return Pose(float(x), float(y), float(heading)) if found else None


def triangulate_small_python(
    local: Surfaces,
    current: Surfaces,
    pi: Pose,
    params: TriangulationParams,
    k: int,
    gate_m: float,
    gate_deg: float,
) -> Pose | None:
    """``triangulate_small`` in Python floats (without numba; the reference the compiled
    kernel is tested against)."""
    n = len(local)
    if n == 0:
        return None
    ls, cs = local.segments, current.segments
    ang_l = _direction_differences(ls, cs)
    dtheta = [_wrap(a) for a in ang_l.tolist()]
    hint = pi.theta
    flipped = [abs(_wrap(d - hint)) > np.pi / 2 for d in dtheta]
    dtheta = [_wrap(d + np.pi) if f else d for d, f in zip(dtheta, flipped, strict=True)]
    loc_ok = local.localisable.tolist()
    cur_ok = current.localisable.tolist()
    dist = np.hypot(cs[:, 0::2], cs[:, 1::2]).tolist()
    lpts, cpts = ls.tolist(), cs.tolist()
    idx: list[int] = []
    ends: list[int] = []
    for i in range(n):
        lok = loc_ok[i][::-1] if flipped[i] else loc_ok[i]
        u0, u1 = lok[0] and cur_ok[i][0], lok[1] and cur_ok[i][1]
        if u0 and u1:
            ends.append(0 if dist[i][0] <= dist[i][1] else 1)  # argmin: first of equals
        elif u0 or u1:
            ends.append(0 if u0 else 1)
        else:
            continue
        idx.append(i)
    if not idx:
        return None
    th = [dtheta[i] for i in idx]
    th_arr = np.array(th)
    cos_l, sin_l = np.cos(th_arr).tolist(), np.sin(th_arr).tolist()
    xs: list[float] = []
    ys: list[float] = []
    pls: list[tuple[float, float]] = []
    pcs: list[tuple[float, float]] = []
    for j, (i, e) in enumerate(zip(idx, ends, strict=True)):
        c, s = cos_l[j], sin_l[j]
        le = 1 - e if flipped[i] else e  # a flipped match pairs the other local end
        pl = (lpts[i][2 * le], lpts[i][2 * le + 1])
        pc = (cpts[i][2 * e], cpts[i][2 * e + 1])
        xs.append(pl[0] - (c * pc[0] - s * pc[1]))
        ys.append(pl[1] - (s * pc[0] + c * pc[1]))
        pls.append(pl)
        pcs.append(pc)
    # The gate against path integration.
    near = np.hypot(np.array(xs) - pi.x, np.array(ys) - pi.y).tolist()
    turn_gate = k * math.radians(gate_deg)  # math.radians is numpy's: x * (pi / 180)
    keep_i = [j for j in range(len(idx))
              if near[j] <= k * gate_m and abs(_wrap(th[j] - pi.theta)) <= turn_gate]  # fmt: skip
    if not keep_i:
        return None
    xs, ys, th = [xs[j] for j in keep_i], [ys[j] for j in keep_i], [th[j] for j in keep_i]
    pls, pcs = [pls[j] for j in keep_i], [pcs[j] for j in keep_i]
    m = len(xs)
    kept = list(range(m))
    if params.use_outlier_heuristic and m > 2:
        mx, my = _sum(xs) / m, _sum(ys) / m
        d = np.hypot(np.array(xs) - mx, np.array(ys) - my).tolist()
        sigma = math.sqrt(_sum([v * v for v in d]) / m)
        kept = [j for j in range(m) if d[j] <= sigma]
        if not kept:
            low = min(d)
            kept = [j for j in range(m) if d[j] == low]
    d_pi = np.hypot(
        np.array([xs[j] for j in kept]) - pi.x, np.array([ys[j] for j in kept]) - pi.y
    ).tolist()
    best = kept[d_pi.index(min(d_pi))]  # argmin: the first of equals
    # heading="weighted": every tracked surface's direction (the PI gate, consensus).
    consensus = math.radians(params.heading_consensus_deg)
    gate_rad = k * math.radians(gate_deg)
    ok = [i for i in range(n) if abs(_wrap(dtheta[i] - pi.theta)) <= gate_rad]
    offset = 0.0
    if ok:
        chosen = th[best]
        dev = [_wrap(dtheta[i] - chosen) for i in ok]
        fit_l, fit_c = _fit_weights(local, ok), _fit_weights(current, ok)
        w = [1.0 / (1.0 / a + 1.0 / b) for a, b in zip(fit_l, fit_c, strict=True)]
        offset = _sum([a * b for a, b in zip(dev, w, strict=True)]) / _sum(w)
        agree = [j for j in range(len(ok)) if abs(dev[j] - offset) <= consensus]
        if agree:
            aw = [w[j] for j in agree]
            offset = _sum([dev[j] * w[j] for j in agree]) / _sum(aw)
    heading = _wrap(th[best] + offset)
    c, s = np.cos(heading), np.sin(heading)
    pl, pc = pls[best], pcs[best]
    x = pl[0] - (c * pc[0] - s * pc[1])
    y = pl[1] - (s * pc[0] + c * pc[1])
    return Pose(float(x), float(y), heading)
