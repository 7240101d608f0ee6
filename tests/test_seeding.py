"""Seeds → Generators: determinism, independence of spawned streams, clear errors."""

from __future__ import annotations

import numpy as np
import pytest

from albot2d import InputError, make_rng, spawn_rngs, spawn_seeds


def test_same_seed_same_stream() -> None:
    assert np.array_equal(make_rng(7).random(5), make_rng(7).random(5))
    assert not np.array_equal(make_rng(7).random(5), make_rng(8).random(5))


def test_spawn_is_stable_and_independent() -> None:
    a = [r.random(3) for r in spawn_rngs(3, 4)]
    b = [r.random(3) for r in spawn_rngs(3, 4)]
    for x, y in zip(a, b, strict=True):
        assert np.array_equal(x, y)
    assert not np.array_equal(a[0], a[1])
    assert [s.spawn_key for s in spawn_seeds(3, 2)] == [(0,), (1,)]


def test_generator_passes_through() -> None:
    g = make_rng(1)
    assert make_rng(g) is g


@pytest.mark.parametrize("bad", [-1, 1.5, "3", True])
def test_bad_seed_names_value(bad: object) -> None:
    with pytest.raises(InputError, match="seed"):
        make_rng(bad)  # type: ignore[arg-type]


def test_named_streams_are_the_spawn_children_they_replace():
    """The named streams keep the seeds recorded runs were made with (``spawn`` order)."""
    from albot2d.seeding import RUN_STREAMS, WORLD_STREAMS, stream_rng, stream_seed

    for seed in (0, 5, 2**40):
        assert stream_seed(seed, RUN_STREAMS, "simulator").spawn_key == (2,)
        assert (
            stream_rng(seed, RUN_STREAMS, "simulator").random(4) == spawn_rngs(seed, 3)[2].random(4)
        ).all()
        assert (
            stream_rng(seed, WORLD_STREAMS, "tour").random(4) == spawn_rngs(seed, 2)[1].random(4)
        ).all()
    parent = np.random.SeedSequence(7, spawn_key=(3,))
    parent.spawn(5)  # a used parent: the named child does not depend on its spawn counter
    assert stream_seed(parent, WORLD_STREAMS, "tour").spawn_key == (3, 1)
    with pytest.raises(ValueError, match="no random stream 'laser'"):
        stream_seed(0, RUN_STREAMS, "laser")
