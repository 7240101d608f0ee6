"""The compiled grid search (numba): ``grid_search.dijkstra_to_goal`` compiled as it is.

Importing this module needs numba (``pip install 'albot2d[fast]'``); ``nearest_goal_path``
uses it when numba imports. The source is the Python function itself, so both paths
settle cells in the same order and return the same path.
"""

from __future__ import annotations

from numba import njit

from albot2d.control import grid_search

__all__ = ["dijkstra_to_goal"]

dijkstra_to_goal = njit(cache=True, nogil=True)(grid_search.dijkstra_to_goal)
