"""Shared hypothesis strategies for albot2d's own tests (worlds live in ``worldgen.strategies``)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from hypothesis import settings
from hypothesis import strategies as st

from albot2d.geometry import Pose

__all__ = ["angles", "coords", "corrupted", "examples", "poses", "segment_arrays"]

coords = st.floats(min_value=-1e3, max_value=1e3, allow_nan=False, allow_infinity=False)
angles = st.floats(min_value=-np.pi, max_value=np.pi, exclude_max=True, allow_nan=False)


@st.composite
def poses(draw: st.DrawFn) -> Pose:
    return Pose(draw(coords), draw(coords), draw(angles))


@st.composite
def segment_arrays(draw: st.DrawFn, max_size: int = 20) -> np.ndarray:
    n = draw(st.integers(min_value=0, max_value=max_size))
    values = draw(st.lists(coords, min_size=4 * n, max_size=4 * n))
    return np.asarray(values, dtype=np.float64).reshape(n, 4)


_CHUNKS = st.binary(min_size=1, max_size=8)


@st.composite
def corrupted(
    draw: st.DrawFn,
    data: bytes,
    *,
    edits: tuple[int, int] = (1, 6),
    chunks: st.SearchStrategy[bytes] = _CHUNKS,
    flips: bool = True,
    keep: int = 0,
    tails: Sequence[bytes] = (),
) -> bytes:
    """``data`` after a random number of edits in the range ``edits``: a bit flipped
    (``flips``), a chunk (drawn from ``chunks``) written over, inserted or its length
    deleted, the rest cut off (never the first ``keep`` bytes) or, given ``tails``, one of
    them appended."""
    out = bytearray(data)
    ops = [*(["flip"] if flips else []), "replace", "insert", "delete", "truncate"]
    ops += ["append"] if tails else []
    for _ in range(draw(st.integers(*edits))):
        at = draw(st.integers(0, len(out)))
        op = draw(st.sampled_from(ops))
        chunk = draw(chunks)
        if op == "flip" and at < len(out):
            out[at] ^= 1 << draw(st.integers(0, 7))
        elif op == "replace":
            out[at : at + len(chunk)] = chunk
        elif op == "insert":
            out[at:at] = chunk
        elif op == "delete":
            del out[at : at + len(chunk)]
        elif op == "truncate":
            del out[max(at, keep) :]
        elif op == "append":
            out += draw(st.sampled_from(list(tails)))
    return bytes(out)


# The ``ci`` profile's example count; ``examples(n)`` scales from it.
_CI_EXAMPLES = 25


def examples(at_ci: int) -> int:
    """Example count for an expensive property: ``at_ci`` under the ``ci`` profile, scaled
    with the loaded profile (``dev`` ×4, ``fuzz`` ×200), so the profiles own the counts."""
    return max(1, round(at_ci * settings().max_examples / _CI_EXAMPLES))
