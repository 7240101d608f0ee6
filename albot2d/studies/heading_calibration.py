"""The heading bound's error model against Albot1's real link errors, on fuzzing episodes.

``heading_error_bound`` (``albot2d.evaluation.checks.heading_bound``) gives every
triangulation link a heading sigma from the surfaces it was localised from: the laser's
noise and its discrete sampling (``direction_sigma``, ``discretisation_sigma``). This
study runs the fuzzing campaign's episodes (same draws as ``albot2d fuzz`` with the same
seed, noise and laser noise), records the surface pairs Albot1 reports for every link
(``on_localise``), and prints:

- per triangulation link, ``z = |heading error| / σ_link``: its percentiles beside a
  half-normal's (0.67, 1.64, 2.58, 3.29 at 50/90/99/99.9 %) and how many links lie beyond
  the bound's ``k`` sigmas; the worst links with their surfaces' beams and lengths;
- per episode, the largest heading error / bound over the run, and how many leave it.

Run::

    python -m albot2d.studies.heading_calibration --episodes 30 --seed 778
    python -m albot2d.studies.heading_calibration --episodes 80 --seed 777 --noise none \\
        --laser-noise zero
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from albot2d.evaluation.checks import heading_bound as hb
from albot2d.geometry import between_arrays, wrap_angle
from albot2d.mapping.albot1.mapper import Albot1, Localisation
from albot2d.perception.surfaces import Surfaces
from albot2d.sim.driving import get_profile
from albot2d.sim.laser import laser_noise_preset
from albot2d.sim.odometry import NOISE_PRESETS

__all__ = ["EpisodeCalibration", "LinkZ", "calibrate_episode", "main"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class LinkZ:
    """One triangulation link: its heading error (rad, signed), the model's sigma (rad),
    and the fewest beams / shortest length among the surfaces it reported."""

    map_id: int
    error_rad: float
    sigma_rad: float
    min_beams: int
    min_length_m: float


@dataclass(frozen=True, slots=True)
class EpisodeCalibration:
    """One episode: its links and the largest heading error / bound over the run."""

    index: int
    links: list[LinkZ]
    worst_ratio: float


def calibrate_episode(index: int, seed: int, noise: str, laser_noise: str) -> EpisodeCalibration:
    """Episode ``index`` of a campaign with ``seed``, mapped by Albot1 (defaults)."""
    from albot2d.evaluation.fuzz.campaign import CampaignParams
    from albot2d.evaluation.fuzz.episode import EpisodeSpec
    from albot2d.evaluation.run.setup import build_run

    campaign = CampaignParams(episodes=index + 1, seed=seed, noise=noise, laser_noise=laser_noise)
    spec = EpisodeSpec.draw(campaign, index)
    setup = build_run(spec.run_spec())
    mapper = Albot1()
    used: list[tuple[Surfaces, Surfaces]] = []

    def record(loc: Localisation) -> None:
        used.append((loc.tracked.local, loc.tracked.current))

    mapper.on_localise = record
    truth: list[FloatArray] = []
    rows: list[int] = []
    for frame in setup.simulator.drive(setup.tour, setup.profile):
        assert frame.true_pose is not None
        truth.append(frame.true_pose.as_array())
        rows.append(frame.index)
        mapper.observe(frame)
    true_poses = np.array(truth)
    index_rows = np.array(rows, dtype=np.int64)
    laser = laser_noise_preset(laser_noise)
    split = mapper.params.extraction.split_distance_m
    at = np.searchsorted(index_rows, [lm.frame_index for lm in mapper.route])
    links = []
    for k in range(1, len(mapper.route)):
        lm = mapper.route[k]
        local, current = used[k - 1]
        if lm.method != "triangulation" or not len(local):
            continue
        rel = between_arrays(true_poses[at[k - 1]], true_poses[at[k]])
        err = float(wrap_angle(lm.pose_in_previous.theta - rel[2]))
        var = hb.link_heading_variance(local, current, laser, split)
        beams = np.concatenate([local.beams[:, 1] - local.beams[:, 0] + 1,
                                current.beams[:, 1] - current.beams[:, 0] + 1])  # fmt: skip
        lengths = np.concatenate([local.lengths_m, current.lengths_m])
        links.append(LinkZ(lm.map_id, err, math.sqrt(var), int(beams.min()),
                           float(lengths.min())))  # fmt: skip
    bound = hb.heading_error_bound(
        mapper.route, index_rows, true_poses, NOISE_PRESETS[noise], get_profile(spec.profile),
        laser, mapper.params.tracking, extraction=mapper.params.extraction, used=used,
    )  # fmt: skip
    ratio = float(np.max(hb.heading_errors(mapper.trajectory(), true_poses) / bound))
    return EpisodeCalibration(index, links, ratio)


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m albot2d.studies.heading_calibration",
                                 description=__doc__.split("\n\n")[0])  # fmt: skip
    ap.add_argument("--episodes", type=int, default=20)
    ap.add_argument("--seed", type=int, default=778, help="campaign seed")
    ap.add_argument("--noise", default="typical", help="odometry noise preset")
    ap.add_argument(
        "--laser-noise",
        default="sick_lms200",
        help="a laser noise preset: sick_lms200 (default), zero or sick_lms200_any_jump",
    )
    ap.add_argument("--worst", type=int, default=5, help="worst links listed")
    args = ap.parse_args(argv)
    episodes = [calibrate_episode(i, args.seed, args.noise, args.laser_noise)
                for i in range(args.episodes)]  # fmt: skip
    links = [(e.index, link) for e in episodes for link in e.links]
    z = np.array([abs(link.error_rad) / link.sigma_rad for _, link in links])
    k = hb.HeadingBoundParams().sigmas
    ratios = np.array([e.worst_ratio for e in episodes])
    print(f"{args.episodes} episodes (seed {args.seed}, noise {args.noise}, laser "
          f"{args.laser_noise}): {len(z)} triangulation links")  # fmt: skip
    if len(z):
        p = np.percentile(z, [50, 90, 99, 99.9])
        beyond = f"beyond {k:g} sigma: {int((z > k).sum())} ({100 * np.mean(z > k):.2f} %)"
        print(f"|error| / sigma_link: median {p[0]:.2f}, p90 {p[1]:.2f}, p99 {p[2]:.2f}, "
              f"p99.9 {p[3]:.2f}, max {z.max():.1f} (half-normal 0.67, 1.64, 2.58, 3.29); "
              f"{beyond}")  # fmt: skip
        for j in np.argsort(z)[::-1][: args.worst]:
            ep, link = links[j]
            print(f"  episode {ep} map {link.map_id}: {math.degrees(link.error_rad):+.3f}° = "
                  f"{z[j]:.1f} sigma; fewest beams {link.min_beams}, shortest "
                  f"{link.min_length_m:.2f} m")  # fmt: skip
    print(
        f"largest error / bound per episode: median {np.median(ratios):.2f}, max "
        f"{ratios.max():.2f}; {int((ratios > 1).sum())} of {len(ratios)} episodes leave it"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
