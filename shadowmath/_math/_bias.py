r"""Depth-map bias: the texel's world size, the slope-scaled depth bias, the normal offset.

A depth shadow map stores, per texel, the depth of the nearest caster along the
ray through the texel's **centre**. A receiver point elsewhere in the texel is
compared with that value although its own ray hits the surface at a different
depth: on a surface tilted by ``theta`` (the angle between its normal and the
ray) the depth changes by ``tan(theta)`` per unit of lateral distance, so a lit
surface shadows itself in a moiré of stripes ("acne"). Both remedies below are
derived from one quantity, the texel's footprint at the receiver.

All functions take ``world_to_texture`` (``(*batch, 4, 4)``, any API convention
of :func:`api_convention`, perspective for point and spot lights, affine for
directional ones): ``M p = (s q, t q, r q, q)``. The gradients of
``u = (row_u . p) / q`` are ``grad u = (m_u - u m_3) / q`` (``m_u`` the first three
entries of row ``u``), and the **ray** through ``p`` is the direction along which
``s`` and ``t`` do not change: ``D = grad s x grad t``.

Trusted cores only: the public functions, which check their arguments and
call these, are in :mod:`shadowmath._geometry._depth_bias`.
"""

from __future__ import annotations

import math
from types import ModuleType
from typing import Literal

from shadowmath._boundary._shapes import Float
from shadowmath._boundary._validate import Array

from ._vector import cross, dot, norm

PcfFilter = Literal["box", "bilinear"]
PCF_FILTERS: tuple[PcfFilter, ...] = ("box", "bilinear")

#: Default constant term of :func:`slope_scaled_bias`, in units of the depth
#: buffer's resolution: one for the rounding of the stored depth, one for the
#: rounding of the compared one.
DEFAULT_CONSTANT_BIAS = 2.0


def kernel_reach(radius: int, filter: PcfFilter) -> float:
    """How far, in texels along each map axis, a lookup compares from the receiver point.

    A box kernel of radius ``k`` reads the centres of texels ``-k..k`` around the
    point's texel; the point may lie anywhere in its texel, so a centre is up to
    ``k + 1/2`` texels away per axis. A bilinear kernel fetches, for each of its
    taps ``-k..k`` texels from the point, the four texel centres around the tap,
    up to one texel further: ``k + 1``.
    """
    return radius + (1.0 if filter == "bilinear" else 0.5)


# ---------------------------------------------------------------------------
# Cores (trusted inputs, array API only).
# ---------------------------------------------------------------------------


def texture_gradients(
    xp: ModuleType, M: Float[Array, "*#batch 4 4"], p: Float[Array, "*#batch 3"]
) -> tuple[Float[Array, "*batch 3"], Float[Array, "*batch 3"], Float[Array, "*batch 3"]]:
    """``(grad s, grad t, grad r)`` at ``p``, each ``(*batch, 3)``; requires ``q > 0``."""
    hom = xp.sum(M[..., :3] * p[..., None, :], axis=-1) + M[..., 3]  # (*batch, 4)
    q = hom[..., 3:]
    uvw = hom[..., :3] / q
    grads = (M[..., :3, :3] - uvw[..., :, None] * M[..., 3:, :3]) / q[..., None]
    return grads[..., 0, :], grads[..., 1, :], grads[..., 2, :]


def texel_size(
    xp: ModuleType,
    M: Float[Array, "*#batch 4 4"],
    p: Float[Array, "*#batch 3"],
    size: tuple[int, int],
) -> Float[Array, "*batch"]:
    """``sqrt(1 / (W H |grad s x grad t|))``: the width across the ray, ``size = (W, H)``."""
    W, H = size
    gs, gt, _ = texture_gradients(xp, M, p)
    D = cross(xp, gs, gt)
    return 1 / xp.sqrt(W * H * norm(xp, D))  # |D| without squaring it (float32's range)


def texel_size_on_surface(
    xp: ModuleType,
    M: Float[Array, "*#batch 4 4"],
    p: Float[Array, "*#batch 3"],
    n: Float[Array, "*#batch 3"],
    size: tuple[int, int],
) -> Float[Array, "*batch"]:
    """``sqrt(1 / (W H |(grad s x grad t) . n|))`` with ``n`` unit: the texel on the surface.

    ``size = (W, H)``: the map's texels.
    """
    W, H = size
    gs, gt, _ = texture_gradients(xp, M, p)
    det = xp.abs(dot(xp, cross(xp, gs, gt), n))
    edge_on = det == 0
    size = 1 / xp.sqrt(W * H * xp.where(edge_on, xp.ones_like(det), det))
    return xp.where(edge_on, xp.asarray(math.inf, dtype=det.dtype), size)


def _depth_slope(
    xp: ModuleType,
    M: Float[Array, "*#batch 4 4"],
    p: Float[Array, "*#batch 3"],
    n: Float[Array, "*#batch 3"],
    size: tuple[int, int],
) -> Float[Array, "*batch 2"]:
    """``(*batch, 2)``: ``dr/dx`` and ``dr/dy`` per texel along the surface of normal ``n``.

    In the tangent plane the step ``v = (grad t x n) / ((grad s x grad t) . n)`` has
    ``ds = 1``, ``dt = 0``; ``(n x grad s) / (...)`` has ``ds = 0``, ``dt = 1``. So
    ``dr/ds = grad r . (grad t x n) / det`` and ``dr/dt = grad r . (n x grad s) / det``;
    one texel is ``1/W`` in ``s`` and ``1/H`` in ``t``. Infinite where the surface is
    seen edge-on (``det = 0``). ``size = (W, H)``: the map's texels.
    """
    W, H = size
    gs, gt, gr = texture_gradients(xp, M, p)
    det = dot(xp, cross(xp, gs, gt), n)
    dr_ds = dot(xp, gr, cross(xp, gt, n))
    dr_dt = dot(xp, gr, cross(xp, n, gs))
    edge_on = det == 0
    safe = xp.where(edge_on, xp.ones_like(det), det)
    inf = xp.asarray(math.inf, dtype=det.dtype)
    x = xp.where(edge_on, inf, xp.abs(dr_ds / (safe * W)))
    y = xp.where(edge_on, inf, xp.abs(dr_dt / (safe * H)))
    return xp.stack([x, y], axis=-1)


def slope_scaled_bias(
    xp: ModuleType,
    M: Float[Array, "*#batch 4 4"],
    p: Float[Array, "*#batch 3"],
    n: Float[Array, "*#batch 3"],
    size: tuple[int, int],
    *,
    constant: float,
    slope_factor: float,
    depth_resolution: float,
) -> Float[Array, "*batch"]:
    slope = xp.max(_depth_slope(xp, M, p, n, size), axis=-1)
    return constant * depth_resolution + slope_factor * slope


def normal_offset(
    xp: ModuleType,
    M: Float[Array, "*#batch 4 4"],
    p: Float[Array, "*#batch 3"],
    n: Float[Array, "*#batch 3"],
    size: tuple[int, int],
    *,
    reach: float,
    scale: float,
) -> Float[Array, "*batch 3"]:
    """``n * scale * reach * (|grad r . (grad t x n)| / W + |grad r . (n x grad s)| / H)
    / (|D| |grad r . d|)`` with ``n`` unit, ``D = grad s x grad t``, ``d = D / |D|``,
    ``size = (W, H)``."""
    W, H = size
    gs, gt, gr = texture_gradients(xp, M, p)
    D = cross(xp, gs, gt)
    length = xp.sqrt(dot(xp, D, D))
    along_ray = xp.abs(dot(xp, gr, D)) / length
    rise = xp.abs(dot(xp, gr, cross(xp, gt, n))) / W + xp.abs(dot(xp, gr, cross(xp, n, gs))) / H
    return n * (scale * reach * rise / (length * along_ray))[..., None]
