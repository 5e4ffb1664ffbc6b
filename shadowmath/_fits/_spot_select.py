"""A spot light's casters selected at the door, before the fit's drivers (see
:mod:`shadowmath._math._spot_casters` for the rule and why it is exact).

The frame is the fit's own (:func:`._fit_formulas.fit_axes` of the cone's axis and
``up``), so the pyramid the casters are clipped to is the one the map is clipped to.
"""

from __future__ import annotations

import numpy as np

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
        if xp is np and _all_kept(planes, points, triangles, ctx.eps):  # the common case
            count = casters.shape[-3] if triangles else casters.shape[-2]
            shape = np.broadcast_shapes(planes.shape[:-2], points.shape[:-2])
            return sc.Selection(points, np.full(shape, count, dtype=np.int64))
        depth = sc.caster_depth(xp, planes, B, points)
        square = sc.to_local(xp, B, sc.empty_square(xp, position, axes, t, depth))
        if triangles:
            return sc.clip_triangles(xp, planes, casters, square, ctx.eps)
        return sc.select_points(xp, planes, points, square, ctx.eps)


def _frame(ctx: Context, light: Array, up: Array | None) -> tuple[Array, Array, Array]:
    """The spot's position, axes ``(*batch, 3, 3)`` (rows ``X, Y, Z``) and ``tan(angle)``."""
    xp = ctx.xp
    d = (light[..., 3], light[..., 4], light[..., 5])
    u = (0.0, 0.0, 0.0) if up is None else (up[..., 0], up[..., 1], up[..., 2])
    a, *_ = formulas(xp).fit_axes(d, u, up is not None, 1.0, ctx.eps)
    shape = xp.broadcast_shapes(*(xp.shape(c) for c in a))
    rows = [xp.broadcast_to(xp.stack(a[i : i + 3], axis=-1), (*shape, 3)) for i in (0, 3, 6)]
    return light[..., :3], xp.stack(rows, axis=-2), light[..., 6]


def _all_kept(planes: Array, points: Array, triangles: bool, eps: float) -> bool:
    """NumPy: every point kept (a triangle whose corners are all inside the sides is its
    own clipped polygon)."""
    if triangles:
        return bool(np.all(sc.inside_sides(np, sc.plane_values(np, planes, points), eps)))
    return bool(np.all(sc.points_kept(np, planes, points, eps)))
