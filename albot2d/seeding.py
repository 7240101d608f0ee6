"""The one place randomness comes from: seeds → ``numpy.random.Generator``s, children via spawn.

No module keeps a global RNG. Callers pass a Generator down explicitly; independent
streams (per episode, per sensor, per worker) come from ``SeedSequence.spawn`` so
results never depend on how work is split across processes.
"""

from __future__ import annotations

import numpy as np

from albot2d.errors import InputError

__all__ = ["SeedLike", "make_rng", "spawn_rngs", "spawn_seeds"]

SeedLike = int | np.random.SeedSequence | np.random.Generator


def _seed_sequence(seed: SeedLike) -> np.random.SeedSequence:
    if isinstance(seed, np.random.SeedSequence):
        return seed
    if isinstance(seed, np.random.Generator):
        ss = seed.bit_generator.seed_seq
        if not isinstance(ss, np.random.SeedSequence):
            raise InputError("seed: this Generator was not made from a SeedSequence")
        return ss
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer):
        raise InputError(f"seed: expected a non-negative integer, got {seed!r}")
    if seed < 0:
        raise InputError(f"seed: expected a non-negative integer, got {seed}")
    return np.random.SeedSequence(int(seed))


def make_rng(seed: SeedLike) -> np.random.Generator:
    """A Generator from an int seed or SeedSequence; a Generator is returned unchanged."""
    if isinstance(seed, np.random.Generator):
        return seed
    return np.random.Generator(np.random.PCG64(_seed_sequence(seed)))


def spawn_seeds(seed: SeedLike, n: int) -> list[np.random.SeedSequence]:
    """``n`` independent child SeedSequences of ``seed`` (stable: same seed → same children).

    For a Generator this spawns from its bit generator's seed sequence, which advances
    that sequence's spawn counter (the documented numpy behaviour).
    """
    return _seed_sequence(seed).spawn(n)


def spawn_rngs(seed: SeedLike, n: int) -> list[np.random.Generator]:
    """``n`` independent Generators derived from ``seed``."""
    return [np.random.Generator(np.random.PCG64(s)) for s in spawn_seeds(seed, n)]
