r"""Percentage-closer soft shadows (PCSS): the texels per unit of stored depth of any map.

A shader's blocker search and penumbra are linear in the stored depth ``d`` (trusted
cores; the door is :mod:`shadowmath._fits._pcss`):

.. math::

    w_\mathrm{search} = K \, |d_R - d_\mathrm{near}|, \qquad
    w_\mathrm{penumbra} = K \max(\sigma (d_R - d_B), 0), \qquad \sigma = 1 - 2 d_\mathrm{near},

in texels per axis, ``K`` read from the map's ``world_to_texture`` ``M`` (rows
``m_0 .. m_3``, world to ``(s q, t q, r q, q)``) and its texture's size ``(W, H)``:

* **perspective** (``m_3`` not affine: ``q = lambda z`` with ``z`` the light depth along
  ``Z = m_3 / |m_3|``): ``r = alpha + beta / q``, ``beta = m_{2,3} - (m_2 . Z) m_{3,3} /
  lambda``; a light disk of radius ``R`` facing ``Z`` spreads a blocker point at depth
  ``z_B`` over a disk of ``R (1/z_B - 1/z_R)`` tan units on a receiver at ``z_R``, and
  ``s`` moves ``|m_0 - (m_0 . Z) Z| / lambda`` per tan unit, so
  ``K_s = R W |m_0 - (m_0 . Z) Z| / |beta|``;
* **orthographic** (``q`` constant): ``r`` is affine in the light depth along
  ``Z = m_2 / |m_2|``; a sun of angular radius ``theta`` spreads a point over
  ``tan(theta) |z_R - z_B|`` world units, so ``K_s = tan(theta) W |m_0 - (m_0 . Z) Z| / |m_2|``.

(``K_t`` likewise with ``m_1`` and ``H``; vectors are the rows' first three entries.)
"""

from __future__ import annotations

from types import ModuleType

from shadowmath._boundary._validate import Array

from ._vector import dot


def _across(xp: ModuleType, row: Array, Z: Array) -> Array:
    """``|row - (row . Z) Z|``: the row's rate across the unit axis ``Z``, ``(*b,)``."""
    r = row[..., :3]
    side = r - dot(xp, r, Z)[..., None] * Z
    return xp.sqrt(dot(xp, side, side))


def _rates(xp: ModuleType, M: Array, size: tuple[float, float], Z: Array) -> Array:
    """``(W |m_0 across Z|, H |m_1 across Z|)`` as ``(*b, 2)``."""
    return xp.stack(
        (size[0] * _across(xp, M[..., 0, :], Z), size[1] * _across(xp, M[..., 1, :], Z)), axis=-1
    )


def perspective_terms(
    xp: ModuleType, M: Array, size: tuple[float, float], radius: Array
) -> tuple[Array, Array]:
    """``(K (*b, 2), d_near (*b,))`` of perspective maps ``M (*b, 4, 4)`` for lights of
    radius ``radius (*b,)``; ``d_near`` is 0 where depth grows away from the light, else 1."""
    g = M[..., 3, :3]
    lam = xp.sqrt(dot(xp, g, g))
    Z = g / lam[..., None]
    beta = M[..., 2, 3] - dot(xp, M[..., 2, :3], Z) * M[..., 3, 3] / lam
    K = radius[..., None] * _rates(xp, M, size, Z) / xp.abs(beta)[..., None]
    return K, xp.astype(beta > 0, M.dtype)


def orthographic_terms(
    xp: ModuleType, M: Array, size: tuple[float, float], tangent: Array, toward: Array
) -> tuple[Array, Array]:
    """``(K (*b, 2), d_near (*b,))`` of orthographic maps ``M (*b, 4, 4)`` for suns of
    angular radius ``atan(tangent)`` (``(*b,)``) whose light travels along ``toward (*b, 3)``
    (any length); ``d_near`` is 0 where depth grows along ``toward``, else 1."""
    g = M[..., 2, :3]
    mu = xp.sqrt(dot(xp, g, g))
    Z = g / mu[..., None]
    K = tangent[..., None] * _rates(xp, M, size, Z) / mu[..., None]
    return K, xp.astype(dot(xp, g, toward) < 0, M.dtype)


def kernel_widths(
    xp: ModuleType, K: Array, near_depth: Array, receiver: Array, blocker: Array
) -> tuple[Array, Array]:
    """``(search, penumbra)`` in texels, ``(*b, 2)`` each, from the stored depths of the
    receiver and of the (average) blocker, ``(*b,)`` each: the shader's two lines."""
    sign = 1 - 2 * near_depth
    search = K * xp.abs(receiver - near_depth)[..., None]
    penumbra = K * xp.maximum(sign * (receiver - blocker), 0)[..., None]
    return search, penumbra
