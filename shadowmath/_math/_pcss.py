r"""Percentage-closer soft shadows (PCSS): the texels per unit of stored depth of any map.

A shader's blocker search and penumbra are linear in the stored depth ``d`` (trusted
cores; the door is :mod:`shadowmath._fits.pcss._door`):

.. math::

    w_\mathrm{search} = K \, |d_R - d_\mathrm{near}|, \qquad
    w_\mathrm{penumbra} = K \max(\sigma (d_R - d_B), 0), \qquad \sigma = 1 - 2 d_\mathrm{near},

in texels per axis, ``K`` read from the map's ``world_to_texture`` ``M`` (rows
``m_0 .. m_3``, world to ``(s q, t q, r q, q)``) and its texture's size ``(W, H)``:

* **perspective** (``m_3`` not affine: ``q = lambda z`` with ``z`` the light depth along
  ``Z = m_3 / |m_3|``): ``r = alpha + beta / q``, ``beta = m_{2,3} - (m_2 . Z) m_{3,3} /
  lambda``; a light disk of radius ``R`` facing ``Z`` spreads a blocker point at depth
  ``z_B`` over a disk of ``R (1/z_B - 1/z_R)`` tan units on a receiver at ``z_R``, and
  ``s`` moves ``|m_0 x Z| / lambda`` per tan unit, so ``K_s = R W |m_0 x Z| / |beta|``;
* **orthographic** (``q`` constant): ``r`` is affine in the light depth along
  ``Z = m_2 / |m_2|``; a sun of angular radius ``theta`` spreads a point over
  ``tan(theta) |z_R - z_B|`` world units, so ``K_s = tan(theta) W |m_0 x Z| / |m_2|``.

(``K_t`` likewise with ``m_1`` and ``H``; vectors are the rows' first three entries.)

Written with the primitives of :mod:`._specialize` (``where``, ``sqrt``, ``fabs``): the door
runs them on whole arrays, on Python floats, or compiled by Numba (:func:`pcss_loop`).
"""

from __future__ import annotations

from types import ModuleType

from shadowmath._boundary._shapes import Array, ArrayLike, Float, Row, Scalar

from ._formulas import fabs, normalize3, sqrt, where


def pcss_across(m: Row, i: int, Zx: Scalar, Zy: Scalar, Zz: Scalar) -> Scalar:
    """``|r x Z|`` of the row ``r = m[i : i + 3]``: its rate across the unit axis ``Z``
    (``|r - (r . Z) Z|`` without its cancellation)."""
    x, y, z = m[i], m[i + 1], m[i + 2]
    cx, cy, cz = y * Zz - z * Zy, z * Zx - x * Zz, x * Zy - y * Zx
    return sqrt(cx * cx + cy * cy + cz * cz)


def pcss_perspective(m: Row, w: Scalar, h: Scalar, radius: Scalar) -> tuple[Scalar, Scalar, Scalar]:
    """``(K_s, K_t, d_near)`` of a perspective map's 16 row-major entries ``m`` (scalars
    or arrays) and texture of ``w x h`` texels, for a light of radius ``radius``;
    ``d_near`` is 0 where depth grows away from the light, else 1."""
    Zx, Zy, Zz, lam = normalize3(m[12], m[13], m[14])
    beta = m[11] - (m[8] * Zx + m[9] * Zy + m[10] * Zz) * m[15] / lam
    scale = radius / fabs(beta)
    s = scale * w * pcss_across(m, 0, Zx, Zy, Zz)
    return s, scale * h * pcss_across(m, 4, Zx, Zy, Zz), where(beta > 0, 1.0, 0.0)


def pcss_orthographic(
    m: Row, w: Scalar, h: Scalar, tangent: Scalar, toward: tuple[Scalar, Scalar, Scalar]
) -> tuple[Scalar, Scalar, Scalar]:
    """``(K_s, K_t, d_near)`` of an orthographic map's entries ``m`` for a sun of angular
    radius ``atan(tangent)`` whose light travels along ``toward`` (any length); ``d_near``
    is 0 where depth grows along ``toward``, else 1."""
    Zx, Zy, Zz, mu = normalize3(m[8], m[9], m[10])
    scale = tangent / mu
    going = m[8] * toward[0] + m[9] * toward[1] + m[10] * toward[2]
    s = scale * w * pcss_across(m, 0, Zx, Zy, Zz)
    return s, scale * h * pcss_across(m, 4, Zx, Zy, Zz), where(going < 0, 1.0, 0.0)


def pcss_loop(
    rows: Float[ArrayLike, "n 16"],
    size: tuple[Scalar, Scalar],
    spread: Scalar,
    toward: Float[ArrayLike, "..."],
    out: Float[Array, "n 3"],
) -> int:
    """The maps ``rows (n, 16)`` of a texture of ``size = (w, h)`` texels into ``out (n, 3)``
    (``K_s, K_t, d_near``): perspective for ``toward`` of shape ``(0, 3)`` (``spread`` the
    light's radius), else orthographic along ``toward (n, 3)`` (``spread = tan(theta)``).
    Returns how many orthographic maps are not (a varying ``q``: a warped cascade)."""
    bad = 0
    for i in range(len(rows)):
        m = rows[i]
        if len(toward) == 0:
            a, b, c = pcss_perspective(m, size[0], size[1], spread)
        else:
            if m[12] != 0 or m[13] != 0 or m[14] != 0:
                bad += 1
            t = (toward[i][0], toward[i][1], toward[i][2])
            a, b, c = pcss_orthographic(m, size[0], size[1], spread, t)
        out[i, 0], out[i, 1], out[i, 2] = a, b, c
    return bad


FUNCTIONS = ("pcss_across", "pcss_perspective", "pcss_orthographic", "pcss_loop")


def kernel_widths(
    xp: ModuleType,
    K: Float[Array, "*#b 2"],
    near_depth: Float[Array, "*#b"],
    receiver: Float[Array, "*#b"],
    blocker: Float[Array, "*#b"],
) -> tuple[Float[Array, "*b 2"], Float[Array, "*b 2"]]:
    """``(search, penumbra)`` in texels, ``(*b, 2)`` each, from the stored depths of the
    receiver and of the (average) blocker, ``(*b,)`` each: the shader's two lines."""
    sign = 1 - 2 * near_depth
    search = K * xp.abs(receiver - near_depth)[..., None]
    penumbra = K * xp.maximum(sign * (receiver - blocker), 0)[..., None]
    return search, penumbra
