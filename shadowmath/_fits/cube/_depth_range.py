r"""The depth range of a point light's cube shadow map: :func:`cube_depth_range`.

A cube map's faces are fixed 90-degree frustums (:func:`cube_face_views`); what a fit
can choose is only ``near`` and ``far``. Face ``i`` sees a point ``p`` at the depth
``D = max(|r_x|, |r_y|, |r_z|)`` of ``r = p - L`` (the selected face's axis), so the
range that keeps every caster and every receiver comes from ``D``'s extremes. The same
core fits the cube lights of :func:`fit_atlas`.
"""

from __future__ import annotations

from types import ModuleType
from typing import NamedTuple

import numpy as np

from shadowmath._boundary._shapes import ArrayLike, Bool, Float, Int, Real, Scalar
from shadowmath._boundary._validate import (
    Array,
    Checks,
    batch_shape,
    convert,
    integer,
    non_finite,
    require_last,
    require_no_new_batch,
    require_vertices,
)
from shadowmath._fits.shadow._door import _receiver_kind, _receiver_rows, caster_triangles
from shadowmath._geometry._cube_faces import face_scale
from shadowmath._math._frustum import NEAR_FAR_SLACK
from shadowmath.receivers import Mesh, Triangles


class CubeDepthRange(NamedTuple):
    """``near`` and ``far`` of a cube shadow map's faces, each ``(*batch,)``: the
    distances along a face's axis to give :func:`cube_face_projection` and
    :func:`cube_face_depth`."""

    near: Float[Array, "*batch"]
    far: Float[Array, "*batch"]


#: A triangle whose bounding box is this near the nearest corner (in ulps of its size)
#: is searched: its candidates might round below the corner.
_KEEP_ULPS = 64

#: A caster this close to the light (relative to the coordinates' size) is "at" it.
_AT_LIGHT_ULPS = 32

AT_LIGHT = (
    "a caster lies at the cube light's position (within rounding); no near plane can keep "
    "it: move the light or the caster"
)


def cube_depth_core(
    xp: ModuleType,
    light: Float[Array, "*#b 3"],
    vertices_t: Float[Array, "*#b 3 N"],
    corners: Float[Array, "*#b M 3"] | None,
    *,
    k: Scalar,
    eps: float,
    triangles: Float[Array, "*#b T 3 3"] | None = None,
) -> tuple[Float[Array, "*b"], Float[Array, "*b"], Bool[Array, "*b"]]:
    """``(near, far, ok)`` for trusted arrays: ``light (*b, 3)``, the casters' points
    ``vertices_t (*b, 3, N)`` (components first: NumPy reduces a trailing axis of 3
    slowly), receiver points ``corners (*b, M, 3)`` or None, the window scale ``k`` of the
    border ring, and the casters' triangles ``(*b, T, 3, 3)`` when they are surfaces (their
    corners are the points); ``ok`` is False where the nearest caster is within rounding
    of the light."""
    D = _chebyshev(xp, *(vertices_t[..., c, :] - light[..., c, None] for c in range(3)))
    d_max = xp.max(D, axis=-1)
    # a triangle may pass nearer the light than its corners
    d_min = xp.min(D, axis=-1) if triangles is None else nearest_triangle(xp, triangles, light, eps)
    if corners is not None:  # a triangle's largest D is at a corner (D is convex)
        d_max = xp.maximum(d_max, xp.max(xp.abs(corners - light[..., None, :]), axis=(-2, -1)))
    largest = xp.maximum(xp.max(vertices_t, axis=(-2, -1)), -xp.min(vertices_t, axis=(-2, -1)))
    scale = xp.maximum(largest, xp.max(xp.abs(light), axis=-1))  # max |coordinate|
    ok = d_min > _AT_LIGHT_ULPS * eps * scale
    return k * d_min * (1 - NEAR_FAR_SLACK), d_max * (1 + NEAR_FAR_SLACK), ok


def nearest_triangle(
    xp: ModuleType, triangles: Float[Array, "*#b T 3 3"], light: Float[Array, "*#b 3"], eps: float
) -> Float[Array, "*b"]:
    """``min D`` over all the triangles ``(*b, T, 3, 3)`` of each batch entry, ``(*b,)``.

    The triangles relative to the light go components first, ``(3 corners, 3 components,
    *b, T)``. NumPy computes :func:`triangle_min_chebyshev` only for the triangles that
    could come nearer than the nearest corner (:func:`_candidates`); under JAX (traced
    shapes) every triangle counts. Both give the same minimum: a triangle left out lies,
    box and all, farther than a corner already found."""
    nb = max(triangles.ndim - 3, light.ndim - 1)  # the batch's dimensions
    triangles = xp.reshape(triangles, (1,) * (nb + 3 - triangles.ndim) + triangles.shape)
    first = xp.moveaxis(triangles, (-2, -1), (0, 1))
    L = xp.moveaxis(xp.reshape(light, (1,) * (nb + 1 - light.ndim) + light.shape), -1, 0)
    L = L[..., None]  # (3, *b, 1)
    if xp is not np:
        return xp.min(triangle_min_chebyshev(xp, first - L), axis=-1)
    shape = (3, 3, *np.broadcast_shapes(first.shape[2:], L.shape[1:]))
    R = np.subtract(first, L, out=np.empty(shape, dtype=triangles.dtype))  # contiguous
    R = R.reshape(3, 3, -1, shape[-1])  # (corner, component, entry, triangle)
    upper, rows, cols = _candidates(R, eps)
    best = triangle_min_chebyshev(np, R[:, :, rows, cols])
    np.minimum.at(upper, rows, best)
    return upper.reshape(shape[2:-1])


def _candidates(
    R: Float[Array, "3 3 e T"], eps: float
) -> tuple[Float[Array, " e"], Int[Array, " n"], Int[Array, " n"]]:
    """``(upper, rows, cols)``: the corners' smallest ``D`` of each entry (an upper bound of
    the answer) and the (entry, triangle) pairs whose bounding box comes nearer than it,
    ``D`` of the box being ``max_i max(lo_i, -hi_i, 0)`` (a box exactly at the bound cannot
    improve on it); a margin of a few ulps of the triangle's size keeps the triangles
    whose candidates could round below the bound.
    Row by row (``(entries, T)`` each): NumPy's large temporaries cost more than its
    arithmetic."""
    D = [_chebyshev(np, R[c, 0], R[c, 1], R[c, 2]) for c in range(3)]
    upper = np.min(np.minimum(np.minimum(D[0], D[1]), D[2]), axis=-1)
    size = np.maximum(np.maximum(D[0], D[1]), D[2])
    gap = np.zeros_like(size)
    for i in range(3):
        lo = np.minimum(np.minimum(R[0, i], R[1, i]), R[2, i])
        hi = np.maximum(np.maximum(R[0, i], R[1, i]), R[2, i])
        np.maximum(gap, np.maximum(lo, -hi), out=gap)
    bound = upper[:, None]  # a floor right under the light: its triangles all tie at it
    rows, cols = np.nonzero((gap != bound) & (gap <= bound + _KEEP_ULPS * eps * size))
    return upper, rows, cols


def _chebyshev(
    xp: ModuleType, x: Float[Array, "..."], y: Float[Array, "..."], z: Float[Array, "..."]
) -> Float[Array, "..."]:
    return xp.maximum(xp.maximum(xp.abs(x), xp.abs(y)), xp.abs(z))


def _safe_divide(
    xp: ModuleType, num: Float[Array, "..."], den: Float[Array, "..."], ok: Bool[Array, "..."]
) -> Float[Array, "..."]:
    """``num / den`` where ``ok``, 0 elsewhere, with finite gradients on both sides."""
    return xp.where(ok, num / xp.where(ok, den, xp.ones_like(den)), xp.zeros_like(num))


#: The six planes ``r_i = sign r_j`` as index and sign rows, and the eight diagonal
#: directions ``(+-1, +-1, +-1)`` (where three faces' depths are equal) as ``(3, 8)``.
_PLANE_I, _PLANE_J = np.array([0, 0, 1, 0, 0, 1]), np.array([1, 2, 2, 1, 2, 2])
_PLANE_SIGN = np.array([1.0, 1.0, 1.0, -1.0, -1.0, -1.0])
_DIAGONALS = np.array(
    [(sx, sy, sz) for sx in (1.0, -1.0) for sy in (1.0, -1.0) for sz in (1.0, -1.0)]
).T


def triangle_min_chebyshev(xp: ModuleType, R: Float[Array, "3 3 ..."]) -> Float[Array, "..."]:
    r"""``min D`` over each triangle of ``R (3 corners, 3 components, ...)`` (corners
    relative to the light, components first so that NumPy reads contiguous arrays), with
    ``D(r) = max(|r_x|, |r_y|, |r_z|)``; shape ``(...)``.

    ``D`` is convex and linear on each region where one signed coordinate is the largest,
    so its minimum over a triangle lies at a vertex of those regions inside it: a corner,
    an edge ``P + s (Q - P)`` crossing a plane ``r_i = +-r_j`` (``0 <= s <= 1``), or the
    triangle crossing a diagonal line ``r = t (+-1, +-1, +-1)`` (``t > 0``, inside every
    edge; there ``D = t``). The candidates outside the triangle are dropped (``inf``);
    the minimum of the others is exact. The 18 edge candidates and the 8 diagonals are
    computed at once, on arrays ``(3 edges, 6 planes, ...)`` and ``(8, ...)``.
    """
    rest = (1,) * (R.ndim - 2)
    inf = xp.asarray(xp.inf, dtype=R.dtype)
    P = R  # the edges A -> B, B -> C, C -> A
    d = xp.concatenate([R[1:], R[:1]]) - P
    corners = _chebyshev(xp, P[:, 0], P[:, 1], P[:, 2])
    sign = xp.asarray(np.reshape(_PLANE_SIGN, (6, *rest)), dtype=R.dtype)
    Pi, Pj, di, dj = P[:, _PLANE_I], P[:, _PLANE_J], d[:, _PLANE_I], d[:, _PLANE_J]
    den = di - sign * dj  # P_i + s d_i = sign (P_j + s d_j)
    ok = den != 0
    s = _safe_divide(xp, sign * Pj - Pi, den, ok)
    inside = ok & (s >= 0) & (s <= 1)
    x, y, z = (P[:, c, None] + s * d[:, c, None] for c in range(3))
    edges = xp.where(inside, _chebyshev(xp, x, y, z), inf)
    A, e1, e2 = R[0], R[1] - R[0], R[2] - R[0]
    n = (
        e1[1] * e2[2] - e1[2] * e2[1],
        e1[2] * e2[0] - e1[0] * e2[2],
        e1[0] * e2[1] - e1[1] * e2[0],
    )
    sigma = xp.asarray(np.reshape(_DIAGONALS, (3, 8, *rest)), dtype=R.dtype)
    den = n[0] * sigma[0] + n[1] * sigma[1] + n[2] * sigma[2]  # (8, ...)
    ok = den != 0
    t = _safe_divide(xp, n[0] * A[0] + n[1] * A[1] + n[2] * A[2], den, ok)  # n.(t sigma - A) = 0
    # t sigma on the inner side of every edge: n . (d x (t sigma - P)) >= 0, (3 edges, 8, ...)
    q = [t * sigma[c] - P[:, c, None] for c in range(3)]
    e = [d[:, c, None] for c in range(3)]
    side = (
        n[0] * (e[1] * q[2] - e[2] * q[1])
        + n[1] * (e[2] * q[0] - e[0] * q[2])
        + n[2] * (e[0] * q[1] - e[1] * q[0])
    )
    inside = ok & (t > 0) & xp.all(side >= 0, axis=0)
    diagonals = xp.where(inside, t, inf)
    return xp.minimum(
        xp.minimum(xp.min(corners, axis=0), xp.min(edges, axis=(0, 1))), xp.min(diagonals, axis=0)
    )


def border_scale(map_size: int | None, border_texels: int) -> float:
    """``k`` of :func:`face_scale`; 1 without a ring, where ``map_size`` may be None."""
    if map_size is None:
        if integer("border_texels", border_texels, 0) == 0:
            return 1.0
        raise ValueError("map_size: a border ring of border_texels > 0 needs the face's map_size")
    return face_scale(map_size, border_texels)


def cube_depth_range(
    light_position: Real[ArrayLike, "*#batch 3"],
    casters: Real[ArrayLike, "*#batch N 3"] | Real[ArrayLike, "*#batch N 3 3"] | Triangles | Mesh,
    *,
    receivers: Real[ArrayLike, "*#batch M 3"] | Triangles | Mesh | None = None,
    map_size: int | None = None,
    border_texels: int = 0,
) -> CubeDepthRange:
    r"""Fit ``near`` and ``far`` of a point light's cube shadow map to its casters.

    With ``D(p) = max(|p_x - L_x|, |p_y - L_y|, |p_z - L_z|)``, the depth of ``p`` along
    the axis of the face that sees it, and ``k = (N - 2b) / N`` for a border ring of
    ``b`` texels (:func:`cube_face_projection`; ``k = 1`` without one):

    .. math::

        n = k \min_{\text{casters}} D \,(1 - s), \qquad
        f = \max_{\text{casters, receivers}} D \,(1 + s), \qquad s = 1/64
        \ (\texttt{NEAR\_FAR\_SLACK}).

    A face's ring shows its neighbours' directions, where a caster's depth along this
    face's axis can drop to ``k D``: ``k`` keeps those casters too. ``D`` is convex, so
    its largest value over a triangle is at a corner but its smallest may lie inside
    (a wall beside the light): casters given as :class:`Triangles` or a :class:`Mesh`
    count their whole surface (exactly: the minimum lies at a corner, where an edge
    crosses a plane ``r_i = +-r_j``, or where the triangle crosses a diagonal
    ``r = t (+-1, +-1, +-1)``); casters given as points count those points. Receivers only
    push ``far``: a receiver nearer the light than every caster is never in shadow. Every
    caster drawn then lies in ``[near, far]`` with room for float32 rounding.

    Arguments:
        light_position: ``(*batch, 3)`` the point light.
        casters: ``(*batch, N, 3)`` points (a mesh's vertices: exact unless a triangle
            passes nearer the light than its corners), :class:`Triangles`
            ``(*batch, M, 3, 3)`` or a :class:`Mesh`.
        receivers: what the shadows fall on: ``(*batch, M, 3)`` points,
            :class:`Triangles` ``(*batch, M, 3, 3)`` or a :class:`Mesh`; None: the
            casters only. They add no batch dimension (a raw ``(M, 3, 3)`` array is
            ``M`` point sets, refused beside one light: wrap it in :class:`Triangles`).
        map_size: texels per face side; needed with ``border_texels``.
        border_texels: the border ring of :func:`cube_face_projection`.

    Returns:
        :class:`CubeDepthRange` ``(near, far)``, each ``(*batch,)``.

    Raises:
        ValueError: wrong shapes (receivers with batch dimensions that neither
            ``light_position`` nor ``casters`` has); non-finite values; a caster at the
            light's position
            (within rounding: no near plane keeps it); a border that leaves no inner
            texel. Under JAX transformations the affected entries (and their gradients)
            are NaN.

    Example:
        >>> import numpy as np, shadowmath as sm
        >>> box = np.array([[x, y, z] for x in (1, 2) for y in (-1, 1) for z in (-1, 1)], float)
        >>> near, far = cube_depth_range([0.0, 0.0, 0.0], box)
        >>> float(near), float(far)  # D from 1 to 2, with 1/64 of slack
        (0.984375, 2.03125)
        >>> float(cube_depth_range([0.0, 0.0, 0.0], box, map_size=64, border_texels=2).near)
        0.9228515625
        >>> wall = sm.Triangles(np.array([[[1.0, -5, -5], [1, 5, -5], [1, 0, 5]]]))
        >>> float(cube_depth_range([0.0, 0.0, 0.0], wall).near)  # its corners are 5 away
        0.984375
    """
    k = border_scale(map_size, border_texels)
    c_kind, c_name, c_array = _receiver_kind(casters, "casters")
    r_kind, r_name, r_array = _receiver_kind(receivers)
    ctx, (light, C, R) = convert(
        light_position=light_position, **{c_name: c_array}, **{r_name: r_array}
    )
    xp = ctx.xp
    require_last("light_position", light, 3, hint="a point light is (x, y, z)")
    triangles = None
    if c_kind == "points":
        require_vertices("casters", C)
    else:
        triangles = caster_triangles(ctx, c_kind, C, casters, "casters")
    points = C if triangles is None else xp.reshape(triangles, (*triangles.shape[:-3], -1, 3))
    shapes = (tuple(light.shape[:-1]), tuple(points.shape[:-2]))
    shape = batch_shape(*shapes, names=("light_position", "casters"))
    corners = None
    if R is not None:
        R = _receiver_rows(ctx, r_kind, R, receivers)
        corners = xp.reshape(R, (*R.shape[:-2], -1, 3))  # triangles' rows of 9: 3 corners
        require_no_new_batch("receivers", R.shape[:-2], shape)
    checks = Checks(ctx)
    checks.require(xp.all(xp.isfinite(light), axis=-1), non_finite("light_position"))
    checks.require(xp.all(xp.isfinite(points), axis=(-2, -1)), non_finite("casters"))
    if corners is not None:
        checks.require(xp.all(xp.isfinite(corners), axis=(-2, -1)), non_finite("receivers"))
    near, far, ok = cube_depth_core(
        xp, light, xp.matrix_transpose(points), corners, k=k, eps=ctx.eps, triangles=triangles
    )
    checks.require(ok, f"casters: {AT_LIGHT}")
    near, far = xp.broadcast_to(near, shape), xp.broadcast_to(far, shape)
    return CubeDepthRange(checks.poison(near, 0), checks.poison(far, 0))
