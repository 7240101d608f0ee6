"""Where albot2d finds its compiled kernels (numba, a default dependency).

A kernel module (``*_numba.py``) imports numba at its top, so it is imported only when a
kernel is first asked for; where numba is not available (a platform without wheels, or
``ALBOT2D_KERNELS=numpy``) the answer is ``None`` and the caller takes its numpy path, the
reference every kernel is tested equal to. ``kernels()`` says which ran; report.json
records it.
"""

from __future__ import annotations

import functools
import importlib
import os
from collections.abc import Callable
from types import ModuleType
from typing import Any

__all__ = ["compiled_kernel", "compiled_module", "kernels"]

_CHOICES = ("numba", "numpy")


@functools.cache
def kernels() -> str:
    """``"numba X.Y"`` when the compiled kernels are in use, else ``"numpy"``.

    ``ALBOT2D_KERNELS=numpy`` turns them off (to compare the paths or time the reference);
    any other value is an InputError."""
    from albot2d.errors import InputError

    wanted = os.environ.get("ALBOT2D_KERNELS", "numba")
    if wanted not in _CHOICES:
        raise InputError(f"ALBOT2D_KERNELS={wanted!r}: expected one of {', '.join(_CHOICES)}")
    if wanted == "numpy":
        return "numpy"
    try:
        import numba
    except ImportError:
        return "numpy"
    return f"numba {numba.__version__}"


@functools.cache
def compiled_module(module: str) -> ModuleType | None:
    """The kernel module ``module`` (imported on first use, then kept), or ``None`` when the
    compiled kernels are off (``kernels()`` is ``"numpy"``)."""
    if kernels() == "numpy":
        return None
    try:
        return importlib.import_module(module)
    except ImportError:
        return None


def compiled_kernel(module: str, name: str) -> Callable[..., Any] | None:
    """The compiled function ``name`` of ``module``, or ``None`` (see ``compiled_module``)."""
    loaded = compiled_module(module)
    if loaded is None:
        return None
    kernel: Callable[..., Any] = getattr(loaded, name)
    return kernel
