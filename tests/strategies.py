"""Shared hypothesis strategies for albot2d's own tests (worlds live in ``worldgen.strategies``)."""

from __future__ import annotations

import numpy as np
from hypothesis import settings
from hypothesis import strategies as st

from albot2d.geometry import Pose

__all__ = ["angles", "coords", "examples", "poses", "segment_arrays"]

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


# The ``ci`` profile's example count; ``examples(n)`` scales from it.
_CI_EXAMPLES = 25


def examples(at_ci: int) -> int:
    """Example count for an expensive property: ``at_ci`` under the ``ci`` profile, scaled
    with the loaded profile (``dev`` ×4, ``fuzz`` ×200), so the profiles own the counts."""
    return max(1, round(at_ci * settings().max_examples / _CI_EXAMPLES))
