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
  ``s`` moves ``|m_0 x Z| / lambda`` per tan unit, so ``K_s = R W |m_0 x Z| / |beta|``;
* **orthographic** (``q`` constant): ``r`` is affine in the light depth along
  ``Z = m_2 / |m_2|``; a sun of angular radius ``theta`` spreads a point over
  ``tan(theta) |z_R - z_B|`` world units, so ``K_s = tan(theta) W |m_0 x Z| / |m_2|``.

(``K_t`` likewise with ``m_1`` and ``H``; vectors are the rows' first three entries.)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from types import ModuleType, SimpleNamespace
from typing import Any

from shadowmath._boundary._validate import Array

#: The primitives of the formulas below on Python floats (one map at a time: the door's
#: path for a few NumPy maps); :func:`array_ops` gives them on whole arrays.
SCALAR = SimpleNamespace(sqrt=math.sqrt, abs=abs, tan=math.tan, flag=float)


def array_ops(xp: ModuleType, dtype: Any) -> SimpleNamespace:
    """The primitives on ``xp``'s arrays (``flag``: a boolean array as 0 and 1)."""
    return SimpleNamespace(sqrt=xp.sqrt, abs=xp.abs, tan=xp.tan, flag=lambda b: xp.astype(b, dtype))


def _unit(ops: Any, x: Any, y: Any, z: Any) -> tuple[Any, Any, Any, Any]:
    """``(x, y, z) / length`` and the length."""
    n = ops.sqrt(x * x + y * y + z * z)
    return x / n, y / n, z / n, n


def _across(ops: Any, m: Any, i: int, Z: Sequence[Any]) -> Any:
    """``|r x Z|`` of the row ``r = m[i : i + 3]``: its rate across the unit axis ``Z``
    (``|r - (r . Z) Z|`` without its cancellation)."""
    x, y, z = m[i], m[i + 1], m[i + 2]
    cx, cy, cz = y * Z[2] - z * Z[1], z * Z[0] - x * Z[2], x * Z[1] - y * Z[0]
    return ops.sqrt(cx * cx + cy * cy + cz * cz)


def perspective_terms(
    ops: Any, m: Any, size: tuple[float, float], radius: Any
) -> tuple[Any, Any, Any]:
    """``(K_s, K_t, d_near)`` of a perspective map's 16 row-major entries ``m`` (scalars
    or arrays) for a light of radius ``radius``; ``d_near`` is 0 where depth grows away
    from the light, else 1."""
    *Z, lam = _unit(ops, m[12], m[13], m[14])
    beta = m[11] - (m[8] * Z[0] + m[9] * Z[1] + m[10] * Z[2]) * m[15] / lam
    scale = radius / ops.abs(beta)
    return (scale * size[0] * _across(ops, m, 0, Z), scale * size[1] * _across(ops, m, 4, Z),
            ops.flag(beta > 0))  # fmt: skip


def orthographic_terms(
    ops: Any, m: Any, size: tuple[float, float], tangent: Any, toward: Any
) -> tuple[Any, Any, Any]:
    """``(K_s, K_t, d_near)`` of an orthographic map's entries ``m`` for a sun of angular
    radius ``atan(tangent)`` whose light travels along ``toward`` (3 entries, any length);
    ``d_near`` is 0 where depth grows along ``toward``, else 1."""
    *Z, mu = _unit(ops, m[8], m[9], m[10])
    scale = tangent / mu
    going = m[8] * toward[0] + m[9] * toward[1] + m[10] * toward[2]
    return (scale * size[0] * _across(ops, m, 0, Z), scale * size[1] * _across(ops, m, 4, Z),
            ops.flag(going < 0))  # fmt: skip


def kernel_widths(
    xp: ModuleType, K: Array, near_depth: Array, receiver: Array, blocker: Array
) -> tuple[Array, Array]:
    """``(search, penumbra)`` in texels, ``(*b, 2)`` each, from the stored depths of the
    receiver and of the (average) blocker, ``(*b,)`` each: the shader's two lines."""
    sign = 1 - 2 * near_depth
    search = K * xp.abs(receiver - near_depth)[..., None]
    penumbra = K * xp.maximum(sign * (receiver - blocker), 0)[..., None]
    return search, penumbra
