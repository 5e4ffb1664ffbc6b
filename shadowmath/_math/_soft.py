r"""Soft shadows from area lights: Heckbert and Herf's pyramid matrix and light samples.

Heckbert and Herf ("Simulating Soft Shadows with Graphics Hardware", 1997; seed
004) average the hard shadows of many point samples on an area light. Each
sample's hard shadow on a receiver polygon is drawn through a projective matrix
that maps the pyramid from the sample (the apex) over a parallelogram around
the receiver (the base) onto the unit box, so every sample's image of the
receiver lands on the same texels. The derivation and the seed's errata are on
``docs/soft-shadows.md``.

Trusted cores only: the public functions, which check their arguments and
call these, are in :mod:`shadowmath._geometry._area_light`.
"""

from __future__ import annotations

import math
from types import ModuleType

from shadowmath._boundary._shapes import Float
from shadowmath._boundary._validate import Array

from ._vector import cross, dot

DEGENERATE = (
    "edge_u, edge_v: the parallelogram is degenerate (a zero edge, or parallel edges "
    "relative to their lengths); the two edges must span a plane"
)


# ------------------------------------------------------------------ cores


def _row(
    xp: ModuleType,
    normal: Float[Array, "*#batch 3"],
    point: Float[Array, "*#batch 3"],
    denominator: Float[Array, "*#batch"],
) -> Float[Array, "*batch 4"]:
    """The matrix row ``(n, -n . point) / denominator``: ``n . (p - point) / denominator``."""
    offset = -dot(xp, normal, point)[..., None]
    normal = xp.broadcast_to(normal, (*offset.shape[:-1], 3))
    return xp.concat([normal, offset], axis=-1) / denominator[..., None]


def pyramid_to_unit_cube(
    xp: ModuleType,
    a: Float[Array, "*#batch 3"],
    b: Float[Array, "*#batch 3"],
    eu: Float[Array, "*#batch 3"],
    ev: Float[Array, "*#batch 3"],
) -> Float[Array, "*batch 4 4"]:
    ew = b - a  # apex to the base corner
    n_x = cross(xp, ew, ev)  # normal of the side through a, b, b + ev   (x = 0)
    n_y = cross(xp, eu, ew)  # normal of the side through a, b, b + eu   (y = 0)
    n_w = cross(xp, ev, eu)  # normal of the base                        (w = 0 at a)
    row_x = _row(xp, n_x, b, dot(xp, n_x, eu))
    row_y = _row(xp, n_y, b, dot(xp, n_y, ev))
    row_w = _row(xp, n_w, a, dot(xp, n_w, ew))
    e4 = xp.asarray([0, 0, 0, 1], dtype=row_w.dtype)
    row_z = e4 - row_w  # z = 1/w - 1: 0 on the base, +inf toward the apex plane
    return xp.stack(xp.broadcast_arrays(row_x, row_y, row_z, row_w), axis=-2)


def grid(count: int) -> tuple[int, int]:
    """``(rows, cols)``: the most nearly square factorization, ``rows <= cols``."""
    rows = max(d for d in range(1, math.isqrt(count) + 1) if count % d == 0)
    return rows, count // rows


def area_light_samples(
    xp: ModuleType,
    corner: Float[Array, "*#batch 3"],
    eu: Float[Array, "*#batch 3"],
    ev: Float[Array, "*#batch 3"],
    jitter: Float[Array, "*#batch count 2"],
    *,
    grid: tuple[int, int],
) -> Float[Array, "*batch count 3"]:
    rows, cols = grid
    k = xp.arange(rows * cols)
    col = xp.astype(k % cols, jitter.dtype)
    row = xp.astype(k // cols, jitter.dtype)
    u = (col + jitter[..., 0]) / cols  # (*batch, count)
    v = (row + jitter[..., 1]) / rows
    return corner[..., None, :] + u[..., None] * eu[..., None, :] + v[..., None] * ev[..., None, :]
