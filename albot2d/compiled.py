"""Where albot2d finds its optional compiled kernels (the ``fast`` extra: numba).

A kernel module (``*_numba.py``) imports numba at its top, so it is imported only when a
kernel is first asked for; without numba the answer is ``None`` and the caller takes its
numpy path, which gives the same numbers.
"""

from __future__ import annotations

import functools
import importlib
from collections.abc import Callable
from typing import Any

__all__ = ["compiled_kernel"]


@functools.cache
def compiled_kernel(module: str, name: str) -> Callable[..., Any] | None:
    """The compiled function ``name`` of ``module`` (imported on first use, then kept), or
    ``None`` when numba does not import."""
    try:
        loaded = importlib.import_module(module)
    except ImportError:
        return None
    kernel: Callable[..., Any] = getattr(loaded, name)
    return kernel
