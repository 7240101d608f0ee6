"""One layout module per world kind; ``LAYOUTS`` maps a kind name to its layout function.

A layout function ``(rect, params, rng) -> Layout`` fills the rectangle ``[x0, y0, x1, y1]``
with free floor, clutter, doorways and the features the kind promises.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from worldgen.kinds._plan import Layout
from worldgen.kinds.corridors import layout_corridors
from worldgen.kinds.fig6 import layout_fig6
from worldgen.kinds.mixed import layout_mixed
from worldgen.kinds.office import layout_office
from worldgen.kinds.open_halls import layout_open
from worldgen.kinds.rooms import layout_rooms

__all__ = ["LAYOUTS", "Layout"]

LAYOUTS: dict[str, Callable[[np.ndarray, Any, np.random.Generator], Layout]] = {
    "corridors": layout_corridors,
    "rooms": layout_rooms,
    "open": layout_open,
    "office": layout_office,
    "mixed": layout_mixed,
    "fig6": layout_fig6,
}
