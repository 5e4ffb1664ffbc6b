"""The compiled loop of ``fit_shadow`` for NumPy input (optional: needs Numba).

One loop over the batch; per entry, the two passes over the vertices that
Nagy's algorithm needs (the viewing direction and the scales; then the
ratios and the depth range in light coordinates), each reading the vertices
once, then the frame, frustum and matrices from the formulas of
:mod:`._formulas`, the same functions the array path runs on whole arrays.
Sums are accumulated in float64 whatever the input dtype.

Validity is reported per batch entry as bits of a status word; the boundary
(:mod:`._setup`) turns the first failing check into the array path's own
``ValueError``. Numba is imported on first use, never by ``import shadowmath``;
compiled code is cached on disk (``cache=True``).
"""

from __future__ import annotations

import contextlib
import importlib.util
import os
from collections.abc import Iterator
from typing import Any

# Status bits, in the order the checks are reported (the array path's order).
NONFINITE_LIGHT = 1
NONFINITE_VERTICES = 2
NONFINITE_PLACEMENT = 4
PROJECTIVE_PLACEMENT = 8
ZERO_DIRECTION = 16
BEHIND_LIGHT = 32
ZERO_SILHOUETTE = 64
NEAR_NOT_FINITE = 128
FAR_NOT_FINITE = 256
NEAR_POSITIVE = 512
NEAR_CLIPS = 1024
FAR_CLIPS = 2048
NEAR_FAR = 4096
OVERFLOW = 8192

#: Layout of one output row: origin, X, Y, Z (3 each), the eight frustum fields; and
#: of one matrix block (4, 4, 4): world_to_light, blocker_to_clip, world_to_texture,
#: blocker_to_world.
ROW = 12 + 8


def available() -> bool:
    """Numba is installed, not disabled by ``SHADOWMATH_NUMBA=0`` nor by :func:`disabled`."""
    return _enabled[0]


# Read once: whether the compiled loops run (tests switch them with `disabled()`).
_enabled = [
    os.environ.get("SHADOWMATH_NUMBA") != "0" and importlib.util.find_spec("numba") is not None
]


@contextlib.contextmanager
def disabled() -> Iterator[None]:
    """Within the block, NumPy input runs the array path instead of the compiled loops."""
    old = _enabled[0]
    _enabled[0] = False
    try:
        yield
    finally:
        _enabled[0] = old


# Status bits of planar_projection's loop, in the order of its checks.
PLANAR_NONFINITE_PLANE = 1
PLANAR_NONFINITE_LIGHT = 2
PLANAR_ZERO_NORMAL = 4
PLANAR_ZERO_LIGHT = 8
PLANAR_IN_PLANE = 16


def planar_kernel() -> Any:
    """The compiled batch loop of ``planar_projection`` (Numba imported on first use)."""
    from ._loops import planar_loop

    return planar_loop


def fit_kernel() -> Any:
    """The compiled batch loop of ``fit_shadow`` (Numba imported on first use)."""
    from ._loops import fit_loop

    return fit_loop
