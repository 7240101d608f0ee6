"""The environments' baseline policies measured: how often, how fast, how far.

``evaluate`` runs an environment's scripted baseline (``Explore-v0``: the frontier
explorer, which knows its true pose as the paper's operator did; ``GoTo-v0``: the goal
seeker, which knows only its odometry) for a number of episodes, ``reset(seed=s)`` for
``s`` from ``seed`` on, and returns one ``BaselineEpisode`` per episode. Run::

    python -m albot2d.envs.baselines GoTo-v0 --episodes 50 --noise typical
    python -m albot2d.envs.baselines Explore-v0 --episodes 5 --max-steps 3000

The summary states the success rate (episodes terminated: goal reached, or the coverage
goal met), steps, return and the miss (GoTo: true distance to the goal at the end;
Explore: the coverage at the end).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from typing import Any, NamedTuple

import gymnasium
import numpy as np

from albot2d.envs import ENV_IDS
from albot2d.envs.explore import ExploreEnv
from albot2d.envs.explore import baseline_policy as explore_policy
from albot2d.envs.goto import GoToEnv
from albot2d.envs.goto import baseline_policy as goto_policy
from albot2d.errors import InputError

__all__ = ["BaselineEpisode", "evaluate", "main"]


class BaselineEpisode(NamedTuple):
    """One episode of a baseline policy."""

    seed: int
    terminated: bool
    steps: int
    episode_return: float
    collisions: int
    #: GoTo: the true distance to the goal at the end (m); Explore: the coverage reached.
    final: float


def evaluate(
    env_id: str,
    *,
    episodes: int,
    seed: int = 0,
    max_steps: int | None = None,
    **options: Any,
) -> list[BaselineEpisode]:
    """Run ``env_id``'s baseline policy for ``episodes`` episodes (seeds ``seed``,
    ``seed + 1``, ...); ``options`` go to ``gymnasium.make``."""
    full_id = env_id if env_id.startswith("albot2d/") else f"albot2d/{env_id}"
    if full_id not in ENV_IDS:
        raise InputError(f"environment must be one of {sorted(ENV_IDS)}, got {env_id!r}")
    if episodes < 1:
        raise InputError(f"episodes must be at least 1, got {episodes!r}")
    out = []
    for s in range(seed, seed + episodes):
        env = gymnasium.make(full_id, max_episode_steps=max_steps, **options)
        obs, info = env.reset(seed=s)
        inner = env.unwrapped
        if isinstance(inner, GoToEnv):
            policy = goto_policy(inner)
        elif isinstance(inner, ExploreEnv):
            policy = explore_policy(inner)
        else:  # ENV_IDS names only these two
            raise TypeError(f"{full_id} has no baseline policy")
        terminated = truncated = False
        steps = collisions = 0
        total = 0.0
        while not (terminated or truncated):
            obs, reward, terminated, truncated, info = env.step(policy(obs, info))
            steps += 1
            collisions += bool(info["collided"])
            total += float(reward)
        final = info["coverage"] if isinstance(inner, ExploreEnv) else info["distance_m"]
        out.append(BaselineEpisode(s, bool(terminated), steps, total, collisions, float(final)))
        env.close()
    return out


def summary(env_id: str, episodes: Sequence[BaselineEpisode]) -> str:
    """A few lines: success rate, steps, return, the final miss or coverage."""
    ok = [e for e in episodes if e.terminated]
    finals = np.array([e.final for e in episodes])
    what = "coverage" if "Explore" in env_id else "true distance to goal (m)"
    lines = [
        f"{env_id}: {len(ok)} of {len(episodes)} episodes terminated "
        f"({100.0 * len(ok) / len(episodes):.0f} %)",
        f"  steps: median {np.median([e.steps for e in episodes]):.0f}"
        + (f", median when terminated {np.median([e.steps for e in ok]):.0f}" if ok else ""),
        f"  return: mean {np.mean([e.episode_return for e in episodes]):.2f}; "
        f"collision steps: {sum(e.collisions for e in episodes)}",
        f"  final {what}: median {np.median(finals):.2f}, max {finals.max():.2f}",
    ]
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        prog="python -m albot2d.envs.baselines", description=__doc__.split("\n\n")[0]
    )
    ap.add_argument("env", help="Explore-v0 or GoTo-v0")
    ap.add_argument("--episodes", type=int, default=20)
    ap.add_argument("--seed", type=int, default=0, help="first episode's reset seed")
    ap.add_argument("--kind", default="office", help="world kind (albot2d world --help)")
    ap.add_argument("--noise", default="typical", help="odometry noise preset")
    ap.add_argument("--max-steps", type=int, default=None, help="truncate episodes here")
    args = ap.parse_args(argv)
    try:
        episodes = evaluate(
            args.env, episodes=args.episodes, seed=args.seed, max_steps=args.max_steps,
            kind=args.kind, noise=args.noise,
        )  # fmt: skip
    except InputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(summary(args.env, episodes))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
