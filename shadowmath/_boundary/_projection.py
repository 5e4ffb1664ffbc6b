"""A camera projection read at the door: is it a projection at all?

A camera's projection maps view coordinates to clip coordinates with ``w`` either the
view depth (perspective: last row ``(0, 0, -1, 0)`` for a camera looking down ``-z``,
``(0, 0, 1, 0)`` for one looking down ``+z``) or 1 (orthographic: ``(0, 0, 0, 1)``).
Every graphics API writes that row this way whatever its depth range, handedness or
reversed Z (they differ in the depth row only), so the row is checked exactly, to
rounding. Not up to scale: the transpose of a perspective projection has the last
row ``(0, 0, 2 f n / (n - f), 0)``, which is a (much narrower, shallower) camera up
to scale, and would be fitted silently; its scale is what gives it away.
"""

from __future__ import annotations

import math

import numpy as np

from ._validate import Array, Checks, all_finite, non_finite, require_matrix

PROJECTION_ROW = (
    "projection: its last row is neither a perspective projection's ((0, 0, -1, 0) or "
    "(0, 0, 1, 0)) nor an orthographic one's ((0, 0, 0, 1)). A transposed matrix (row-major "
    "memory read as column-major) has its last row in its last column: shadowmath takes "
    "column-vector matrices (clip = P @ view), so pass P.T; a scaled one: divide it by its "
    "last row's nonzero entry"
)


def check_projection(checks: Checks, P: Array) -> None:
    """Check ``P`` ``(*batch, 4, 4)`` as a camera projection (shape: always raises; values:
    the call's :class:`Checks`): finite, and its last row perspective or orthographic.

    A projection that passes may still be singular: the caller, which inverts it,
    checks that with its own tolerance.
    """
    require_matrix("projection", P)
    tol = 1024 * checks.ctx.eps
    if checks.mode == "raise" and P.shape == (4, 4) and type(P) is np.ndarray:
        a, b, c, d = P[3].tolist()  # one camera per frame: Python floats, no array ops
        if not all(math.isfinite(v) for v in (a, b, c, d)):
            raise ValueError(non_finite("projection"))
        if abs(a) > tol or abs(b) > tol or not _row_ok(c, d, tol):
            raise ValueError(PROJECTION_ROW)
        return
    xp = checks.ctx.xp
    checks.require(all_finite(xp, P, 2), non_finite("projection"))
    row = P[..., 3, :]
    zero = xp.abs(row) <= tol
    one = xp.abs(xp.abs(row) - 1) <= tol
    perspective = zero[..., 0] & zero[..., 1] & one[..., 2] & zero[..., 3]
    orthographic = zero[..., 0] & zero[..., 1] & zero[..., 2] & (xp.abs(row[..., 3] - 1) <= tol)
    checks.require(perspective | orthographic, PROJECTION_ROW)


def _row_ok(c: float, d: float, tol: float) -> bool:
    return (abs(abs(c) - 1) <= tol and abs(d) <= tol) or (abs(c) <= tol and abs(d - 1) <= tol)
