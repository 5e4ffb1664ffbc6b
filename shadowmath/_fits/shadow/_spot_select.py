"""A spot light's casters selected at the door, before the fit's drivers (see
:mod:`shadowmath._math._spot_casters` for the rule and why it is exact).

The frame is the fit's own (:func:`shadowmath._math._fit_formulas.fit_axes` of the cone's axis and
``up``), so the pyramid the casters are clipped to is the one the map is clipped to.

Triangles are clipped by the compiled loop (:mod:`shadowmath._math._spot_loop`) for
one NumPy light with Numba (:func:`clipped`), by
:func:`shadowmath._math._spot_casters.select_triangles` for other NumPy input (only the straddling
triangles through the 19 candidates), and by :func:`shadowmath._math._spot_casters.clip_triangles`
(static shapes) under JAX. The first two hand the fit the kept points only.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from shadowmath._backends import _kernels
from shadowmath._boundary._validate import Array, Context
from shadowmath._math import _spot_casters as sc
from shadowmath._math._specialize import formulas


def spot_selection(
    ctx: Context,
    light: Array,
    up: Array | None,
    B: Array | None,
    casters: Array,
    *,
    triangles: bool,
) -> sc.Selection:
    """The casters of spot lights ``light`` ``(*batch, 8)`` (position, axis, ``tan``, angle)
    that the map can use: ``casters`` ``(*batch, M, 3, 3)`` triangles clipped to the cone's
    square pyramid, or ``(*batch, N, 3)`` points inside it; shapes already checked."""
    xp = ctx.xp
    with np.errstate(all="ignore"):  # a zero axis or NaN light: refused by the fit's checks
        position, axes, t = _frame(ctx, light, up)
        planes = sc.local_planes(xp, sc.pyramid_planes(xp, position, axes, t), B)
        points = xp.reshape(casters, (*casters.shape[:-3], -1, 3)) if triangles else casters

        def square() -> Array:
            """The empty fit's casters (needed only where nothing is kept)."""
            depth = sc.caster_depth(xp, planes, B, points)
            return sc.to_local(xp, B, sc.empty_square(xp, position, axes, t, depth))

        if xp is np and triangles:
            one = casters.ndim == 3 and planes.ndim == 2  # one light, unbatched casters
            if _kernels.available() and one and bool(np.all(np.isfinite(planes))):
                return clipped(planes, casters, square, ctx.eps)
            return sc.select_triangles(planes, casters, square, ctx.eps)
        if xp is np and _all_kept(planes, points, ctx.eps):  # the common case
            shape = np.broadcast_shapes(planes.shape[:-2], points.shape[:-2])
            return sc.Selection(points, np.full(shape, casters.shape[-2], dtype=np.int64))
        if triangles:
            return sc.clip_triangles(xp, planes, casters, square(), ctx.eps)
        return sc.select_points(xp, planes, points, square(), ctx.eps)


def clipped(
    planes: Array, triangles: Array, square: Callable[[], Array], eps: float
) -> sc.Selection:
    """One spot light's triangles ``(M, 3, 3)`` clipped by the compiled loop
    (:func:`shadowmath._math._spot_loop.spot_clip_loop`): the kept points ``(K, 3)``
    compacted (``square()`` ``(4, 3)`` when none is), and the triangles kept.

    ``planes`` ``(5, 4)`` finite (:func:`shadowmath._math._spot_casters.pyramid_planes` on the
    triangles' coordinates). The loop's output starts at ``3 M + 19 (M / 8 + 1)`` rows
    and doubles whenever fewer than 19 are left for the next triangle.
    """
    count = triangles.shape[0]
    flat = np.ascontiguousarray(triangles).reshape(-1)  # x0, y0, z0, x1, ... per triangle
    rows = np.ascontiguousarray(planes)
    out = np.empty((3 * count + 19 * (count // 8 + 1), 3), dtype=triangles.dtype)
    loop = _kernels.loops().spot_clip_loop
    start = at = kept = 0
    while True:
        start, at, more = loop(flat, rows, eps, out, (start, at))
        kept += more
        if start >= count:
            break
        grown = np.empty((2 * len(out), 3), dtype=out.dtype)
        grown[:at] = out[:at]
        out = grown
    return sc.Selection(out[:at] if at else square(), np.array(kept, dtype=np.int64))


def _frame(ctx: Context, light: Array, up: Array | None) -> tuple[Array, Array, Array]:
    """The spot's position, axes ``(*batch, 3, 3)`` (rows ``X, Y, Z``) and ``tan(angle)``."""
    xp = ctx.xp
    d = (light[..., 3], light[..., 4], light[..., 5])
    u = (0.0, 0.0, 0.0) if up is None else (up[..., 0], up[..., 1], up[..., 2])
    a, *_ = formulas(xp).fit_axes(d, u, up is not None, 1.0, ctx.eps)
    shape = xp.broadcast_shapes(*(xp.shape(c) for c in a))
    rows = [xp.broadcast_to(xp.stack(a[i : i + 3], axis=-1), (*shape, 3)) for i in (0, 3, 6)]
    return light[..., :3], xp.stack(rows, axis=-2), light[..., 6]


def _all_kept(planes: Array, points: Array, eps: float) -> bool:
    """NumPy: every point kept."""
    return bool(np.all(sc.points_kept(np, planes, points, eps)))
