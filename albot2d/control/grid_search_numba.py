"""The compiled grid search (numba): ``grid_search.dijkstra_to_goal`` compiled as it is.

Loaded through ``albot2d.compiled`` (off with ``ALBOT2D_KERNELS=numpy``);
``nearest_goal_path`` uses it when the compiled kernels are on. The source is the Python
function itself, so both paths settle cells in the same order and return the same path.
"""

from __future__ import annotations

from numba import njit

from albot2d.control import grid_search

__all__ = ["dijkstra_to_goal"]

dijkstra_to_goal = njit(cache=True, nogil=True)(grid_search.dijkstra_to_goal)
