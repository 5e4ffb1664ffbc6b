"""The depth range of a point light's cube shadow map on trusted arrays: :func:`cube_depth_core`.

A cube map's faces are fixed 90-degree frustums (:func:`cube_face_views`); what a fit
can choose is only ``near`` and ``far``. Face ``i`` sees a point ``p`` at the depth
``D = max(|r_x|, |r_y|, |r_z|)`` of ``r = p - L`` (the selected face's axis), so the
range that keeps every caster and every receiver comes from ``D``'s extremes. The same
core fits the cube lights of :func:`fit_atlas`.
"""

from __future__ import annotations

from types import ModuleType

import numpy as np

from shadowmath._boundary._shapes import Bool, Float, Int, Scalar
from shadowmath._boundary._validate import Array
from shadowmath._math._frustum import NEAR_FAR_SLACK

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
