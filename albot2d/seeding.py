"""The one place randomness comes from: seeds → ``numpy.random.Generator``s, children via spawn.

No module keeps a global RNG. Callers pass a Generator down explicitly; independent
streams (per episode, per sensor, per worker) come from ``SeedSequence.spawn`` so
results never depend on how work is split across processes.
"""

from __future__ import annotations

import numpy as np

from albot2d.errors import InputError

__all__ = [
    "RUN_STREAMS",
    "WORLD_STREAMS",
    "SeedLike",
    "make_rng",
    "spawn_rngs",
    "spawn_seeds",
    "stream_rng",
    "stream_seed",
]

SeedLike = int | np.random.SeedSequence | np.random.Generator

# Named child streams (the simulator's own are ``sim.simulator._STREAMS``): a stream's
# position in its tuple is its spawn index, so these tuples are never reordered (that
# would change every recorded run).
#: Children of a run seed (``RunSpec.seed``). The world is generated from the run seed
#: itself and the tour from the world's seed, so only the simulator stream is drawn; the
#: first two stay reserved so the simulator keeps the seeds recorded runs were made with.
RUN_STREAMS = ("reserved_0", "reserved_1", "simulator")
#: Children of a world's seed (the generator draws from the seed itself): the tour the
#: command line plans (``worldgen.plan_tour``), so planning never shifts the world's draws.
WORLD_STREAMS = ("reserved_0", "tour")


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


def stream_seed(seed: SeedLike, streams: tuple[str, ...], name: str) -> np.random.SeedSequence:
    """The child of ``seed`` named ``name`` in ``streams`` (e.g. ``RUN_STREAMS``).

    The same child ``SeedSequence(seed).spawn(len(streams))`` gives at that position, built
    directly, so it does not depend on (or advance) the parent's spawn counter.
    """
    if name not in streams:
        raise ValueError(f"no random stream {name!r}; streams: {', '.join(streams)}")
    parent = _seed_sequence(seed)
    return np.random.SeedSequence(
        parent.entropy, spawn_key=(*parent.spawn_key, streams.index(name)),
        pool_size=parent.pool_size,
    )  # fmt: skip


def stream_rng(seed: SeedLike, streams: tuple[str, ...], name: str) -> np.random.Generator:
    """A Generator on the child stream ``name`` of ``seed`` (see ``stream_seed``)."""
    return np.random.Generator(np.random.PCG64(stream_seed(seed, streams, name)))
