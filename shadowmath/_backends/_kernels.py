"""The compiled loops' switch and loader (optional: needs Numba).

Numba is imported on first use, never by ``import shadowmath``. The loops of
:mod:`shadowmath._math._loops` inline the formulas of several modules, while Numba keys its disk
cache to the source file of each compiled function only: a change of a formula
in another file would leave a new process running the old machine code. So the
loops are compiled with Numba's cache directory set to a folder named after a
hash of every source file of the package (and the Python and Numba versions):
when any of them changes, the folder is new and the loops are compiled afresh.
"""

from __future__ import annotations

import contextlib
import functools
import importlib.util
import os
import sys
from collections.abc import Iterator
from types import SimpleNamespace
from typing import Any

import numpy as np


def available() -> bool:
    """Numba is installed, not disabled by ``SHADOWMATH_NUMBA=0`` nor by :func:`disabled`."""
    return _enabled[0]


# Read once: whether the compiled loops run (tests switch them with `disabled()`).
_enabled = [
    os.environ.get("SHADOWMATH_NUMBA") != "0" and importlib.util.find_spec("numba") is not None
]


@contextlib.contextmanager
def disabled() -> Iterator[None]:
    """Within the block, NumPy input runs as without Numba (no compiled loop)."""
    old = _enabled[0]
    _enabled[0] = False
    try:
        yield
    finally:
        _enabled[0] = old


def python_loop() -> bool:
    """One small NumPy fit without Numba may run the loop in Python (not in :func:`array_path`)."""
    return _python[0]


_python = [True]


@contextlib.contextmanager
def array_path() -> Iterator[None]:
    """Within the block, NumPy input runs the array path: no compiled loop, no Python loop."""
    old = _python[0]
    _python[0] = False
    try:
        with disabled():
            yield
    finally:
        _python[0] = old


# hashlib, tempfile and pathlib are imported where used: they cost ``from shadowmath import
# fit_shadow`` about 10 ms, and only the first compiled fit of a process needs them.
_PACKAGE = os.path.dirname(os.path.dirname(os.path.realpath(__file__)))


def sources_hash() -> str:
    """A hash of every Python source of the package, and of Python's and Numba's versions.

    The whole package (every ``*.py`` under it), not a list of the files the loops
    import today: a new import can never escape the key.
    """
    import hashlib
    from pathlib import Path

    import numba

    package = Path(_PACKAGE)
    digest = hashlib.sha256(f"{sys.version}|{numba.__version__}".encode())
    for path in sorted(package.rglob("*.py")):
        digest.update(str(path.relative_to(package)).encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


def cache_dir(key: str) -> str:
    """A writable folder for the compiled loops of sources ``key``.

    ``$NUMBA_CACHE_DIR/shadowmath-<key>`` when that variable is set, else the
    package's ``__pycache__/shadowmath-<key>``, else (read-only installs) a folder
    of the system's temporary directory.
    """
    import tempfile

    base = os.environ.get("NUMBA_CACHE_DIR") or os.path.join(_PACKAGE, "__pycache__")
    for root in (base, os.path.join(tempfile.gettempdir(), f"shadowmath-numba-{os.getuid()}")):
        path = os.path.join(root, f"shadowmath-{key}")
        with contextlib.suppress(OSError):
            os.makedirs(path, exist_ok=True)
            if os.access(path, os.W_OK):
                return path
    return tempfile.mkdtemp(prefix="shadowmath-numba-")


@functools.cache
def loops() -> SimpleNamespace:
    """The formulas and loops compiled by Numba (or loaded) under their sources' cache key."""
    import numba
    from numba.core import config as numba_config

    from shadowmath._math import _fit_entry
    from shadowmath._math._specialize import scalar_primitives, specialize

    from . import _reductions

    config: Any = numba_config
    old = config.CACHE_DIR
    config.CACHE_DIR = cache_dir(sources_hash())
    try:
        jit = numba.njit(cache=True, error_model="numpy")
        primitives = {
            **scalar_primitives(),
            **_reductions.primitives(),
            "where": jit(_select),
            "rint": np.rint,
            "alloc": jit(_zeros),
            "flag": jit(_flag),
            "take_last": jit(_take),
            "to_single": jit(_fit_entry.to_single),
        }
        return specialize(primitives, wrap=jit)
    finally:
        config.CACHE_DIR = old


def _zeros(n: int) -> Any:
    """The loops' float buffer for Numba (module level, so that its disk cache finds it)."""
    return np.zeros(n)


def _flag(ok: Any, bit: int) -> int:
    """A check's status bit, for Numba: 0 where ``ok`` (module level, for the disk cache)."""
    return 0 if ok else bit


def _take(row: Any, k: int) -> Any:
    """Entry ``k`` of a row, for Numba (module level, so that its disk cache finds it)."""
    return row[k]


def _select(c: Any, a: Any, b: Any) -> Any:
    """``where`` on scalars, for Numba (module level, so that its disk cache finds it)."""
    return a if c else b


def sphere_support(points: Any) -> Any:
    """The minimal enclosing sphere's support of ``(*batch, N, 3)`` points: ``(*batch, 5)``
    int32 rows ``(i_0, i_1, i_2, i_3, k)``: Welzl's algorithm compiled
    (:mod:`shadowmath._math._loops`) when Numba is available, else every entry at once in NumPy
    (:func:`shadowmath._math._ball_support.support_arrays`)."""
    p = np.asarray(points, dtype=np.float64)
    flat = np.ascontiguousarray(p.reshape(-1, *p.shape[-2:]))
    if available():
        out = np.zeros((len(flat), 5), dtype=np.int32)
        loops().support_loop(flat.reshape(len(flat), -1), out)  # rows x0, y0, z0, x1, ...
    else:
        from shadowmath._math._ball_support import support_arrays

        out = support_arrays(flat)
    return out.reshape(*p.shape[:-2], 5)
