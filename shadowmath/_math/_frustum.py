"""The adaptive perspective frustum of the shadow map, and its two projections.

Light coordinates (see :mod:`shadowmath._frame`) have the light at the origin
and ``+Z`` toward the blocker. A light-space point ``(x, y, z)`` with ``z > 0``
projects to the ratios ``x / z`` and ``y / z``; the frustum scales the largest
of them to the border margin, so the blocker's silhouette fills the map up to a
border of untouched texels.

Trusted cores only: the public functions, which check their arguments and
call these, are in :mod:`shadowmath._api._adaptive_frustum`.
"""

from __future__ import annotations

from types import ModuleType
from typing import NamedTuple

import numpy as np

from shadowmath._boundary._validate import Array

from ._specialize import formulas

#: Relative slack of the default near and far planes around the blocker:
#: ``near = z_min * (1 - NEAR_FAR_SLACK)``, ``far = z_max * (1 + NEAR_FAR_SLACK)``.
NEAR_FAR_SLACK = 1.0 / 64.0


class Frustum(NamedTuple):
    """A perspective frustum in light coordinates, symmetric unless offset.

    Attributes (each ``(*batch,)``):
        rx_max: half-width of the frustum at ``z = 1`` about its centre: for the
            article's symmetric frustum, the largest ``|x / z|`` of the blocker.
        ry_max: the same along light ``Y``.
        near: distance of the near plane from the light (``z``), ``> 0``.
        far: distance of the far plane, ``> near``.
        margin_x: fraction of the map's half-width the silhouette may fill
            (``(width - 2 border) / width``; the article's 0.98).
        margin_y: the same along light ``Y`` (the map's height).
        x_offset: the ratio ``x / z`` at the map's centre (default 0: symmetric).
            An off-centre frustum spans ``x / z`` in
            ``[x_offset - rx_max, x_offset + rx_max]`` (before the margin).
        y_offset: the same along light ``Y``.
        orthographic: ``False`` (default: perspective, a point light), ``True``, or
            a ``(*batch,)`` boolean array, True for the entries whose frustum is an
            orthographic box (a directional light). There ``rx_max``, ``ry_max``
            are the box's half-width and half-height in world units (before the
            margin), ``x_offset``, ``y_offset`` its centre in light coordinates
            (world units), and ``near``, ``far`` its depth range along ``Z``.
            :func:`fit_shadow` gives a Python ``False`` for a 3-vector light and a
            boolean array (``w == 0``) for a homogeneous 4-vector light.

    A perspective frustum maps light ``(x, y, z)`` to NDC
    ``x_ndc = m_x (x / z - c_x) / R_x``; an orthographic one to
    ``x_ndc = m_x (x - c_x) / R_x``.
    """

    rx_max: Array
    ry_max: Array
    near: Array
    far: Array
    margin_x: Array
    margin_y: Array
    x_offset: Array = 0.0
    y_offset: Array = 0.0
    orthographic: Array | bool = False


def blocker_reach(xp: ModuleType, light: Array, verts: Array) -> Array:
    """``(*batch,)`` the largest coordinate of any ``V - L``: the scale of the rounding noise."""
    return xp.max(xp.abs(verts - light[..., None, :]), axis=(-2, -1))


def projection_terms(xp: ModuleType, fr: Frustum) -> tuple[Array, ...]:
    """``(sx, -sx cx, sy, -sy cy, a, b)``: the nonzero entries of the blocker projection."""
    sx, sy = fr.margin_x / fr.rx_max, fr.margin_y / fr.ry_max
    terms: tuple[Array, ...] = formulas(xp).projection_rows(
        (sx, sy), (fr.x_offset, fr.y_offset), fr.near, fr.far
    )
    return terms


def projection_entries(xp: ModuleType, fr: Frustum) -> tuple[Array, ...]:
    """The 16 entries of the blocker projection of a trusted frustum (any ``orthographic``)."""
    sx, sxc, sy, syc, a, b = projection_terms(xp, fr)
    zero = xp.zeros_like(sx)
    one = zero + 1
    ortho = fr.orthographic
    if isinstance(ortho, bool | np.bool_) and not ortho:
        return (
            sx, zero, sxc, zero,
            zero, sy, syc, zero,
            zero, zero, a, b,
            zero, zero, one, zero,
        )  # fmt: skip
    # Orthographic entries (every field finite, far > near: both branches are finite,
    # so selecting with where keeps derivatives finite too).
    depth = fr.far - fr.near
    inv = 1.0 / xp.where(depth > 0, depth, xp.ones_like(depth))  # bad entries: poisoned
    oa, ob = 2.0 * inv, -(fr.far + fr.near) * inv
    if isinstance(ortho, bool | np.bool_):
        return (
            sx, zero, zero, sxc,
            zero, sy, zero, syc,
            zero, zero, oa, ob,
            zero, zero, zero, one,
        )  # fmt: skip

    def pick(o: Array, p: Array) -> Array:
        return xp.where(ortho, o, p)

    return (
        sx, zero, pick(zero, sxc), pick(sxc, zero),
        zero, sy, pick(zero, syc), pick(syc, zero),
        zero, zero, pick(oa, a), pick(ob, b),
        zero, zero, pick(zero, one), pick(one, zero),
    )  # fmt: skip
