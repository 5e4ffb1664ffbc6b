"""The light coordinate system of Nagy's projective shadow texture.

Origin at the light, ``Z`` toward the blocker (the normalized mean direction
vector), ``X = normalize(Z x V)`` with ``V`` the helper axis, ``Y = X x Z``.
Because ``X x Y = X x (X x Z) = -Z``, ``(X, Y, Z)`` is a *left-handed* frame:
it is an OpenGL right-handed look-at camera at the light with its ``z`` axis
flipped (the camera looks down its ``-z``, which is our ``+Z``).

Trusted cores only: the public functions, which check their arguments and
call these, are in :mod:`shadowmath._geometry._light_frame`.
"""

from __future__ import annotations

from types import ModuleType
from typing import NamedTuple

import numpy as np

from shadowmath._boundary._shapes import Float, Scalar
from shadowmath._boundary._validate import Array, Context

from ._rows import MatrixEntries
from ._specialize import formulas


class LightFrame(NamedTuple):
    """The light coordinate system, all fields in world coordinates.

    Attributes:
        origin: ``(*batch, 3)`` the light position.
        x_axis: ``(*batch, 3)`` unit ``X_light``.
        y_axis: ``(*batch, 3)`` unit ``Y_light``.
        z_axis: ``(*batch, 3)`` unit ``Z_light``, from the light toward the blocker.

    ``(x_axis, y_axis, z_axis)`` is orthonormal and left-handed
    (``x_axis x y_axis = -z_axis``).
    """

    origin: Float[Array, "*batch 3"]
    x_axis: Float[Array, "*batch 3"]
    y_axis: Float[Array, "*batch 3"]
    z_axis: Float[Array, "*batch 3"]


def zero_direction_noise(ctx: Context, coords: Float[Array, "*batch"]) -> Float[Array, "*batch"]:
    """How short a computed viewing direction may be and still be rounding noise.

    A light at the blocker's centre computed in floating point (e.g. the mean
    of the vertices) leaves an MDV of rounding noise, a few ulps of the
    coordinates, pointing anywhere. Relative to the coordinates' size (the
    precision the scene is stored with), anything that short is treated as
    zero; any unit of length works.
    """
    return 32 * ctx.eps * coords


def light_entries(xp: ModuleType, frame: LightFrame) -> tuple[Float[Array, "*batch"], ...]:
    """The 12 entries of ``world_to_light``'s first three rows, from a trusted frame."""
    o, x, y, z = frame
    entries: tuple[Array, ...] = formulas(xp).light_rows(
        (o[..., 0], o[..., 1], o[..., 2]),
        (
            x[..., 0], x[..., 1], x[..., 2],
            y[..., 0], y[..., 1], y[..., 2],
            z[..., 0], z[..., 1], z[..., 2],
        ),
    )  # fmt: skip
    return entries


def stack_matrix(xp: ModuleType, entries: tuple[Scalar, ...]) -> Float[Array, "*batch 4 4"]:
    """``(*batch, 4, 4)`` from 16 row-major entries (or 12: the last row is ``(0, 0, 0, 1)``;
    the entries of an array form's product, :class:`._rows.MatrixEntries`, its matrix)."""
    if isinstance(entries, MatrixEntries):
        return entries.matrix
    if len(entries) == 12:
        zero = xp.zeros_like(entries[0])
        entries = (*entries, zero, zero, zero, zero + 1)
    shapes = [tuple(xp.asarray(e).shape) for e in entries]  # trusted: they broadcast
    shape = shapes[0] if all(s == shapes[0] for s in shapes) else np.broadcast_shapes(*shapes)
    dtype = xp.result_type(*entries)
    flat = xp.stack([xp.broadcast_to(xp.asarray(e, dtype=dtype), shape) for e in entries], axis=-1)
    return xp.reshape(flat, (*shape, 4, 4))
