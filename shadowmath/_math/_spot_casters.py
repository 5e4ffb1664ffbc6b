r"""The casters a spot light's map can use: clipped to its cone's bounding square pyramid.

A spot light's map is clipped to the square pyramid ``|x| <= t z``, ``|y| <= t z``
(``t = tan(angle)``) in its frame (``Z`` the cone's axis; :func:`._fit_formulas.spot_sides`).
A receiver point ``P`` inside the cone is shadowed only by geometry on the segment
from the light to ``P``, which lies inside the cone (a cone is convex from its
apex), so geometry outside the pyramid never shadows a lit point: it is dropped
here, before the fit. A triangle that crosses the pyramid's sides (or the light's
plane) is clipped to its part inside. The renderer may still draw every caster
with the fitted matrix: the GPU clips what lies outside the frustum (behind the
light: ``w < 0``).

The pyramid's four side planes through the apex ``L`` are
``pi_k = (n_k, -n_k . L)`` with ``n = t Z - X, t Z + X, t Z - Y, t Z + Y``
(:func:`pyramid_planes`), ``pi . (p, 1) >= 0`` inside. With a placement ``B``
(``p_world = B q``) the planes act on local points as ``B^T pi``
(``pi . (B q) = (B^T pi) . q``), so the casters stay in local coordinates.

**Triangles** (:func:`clip_triangles`). The clipped polygon is convex and its
corners are among 19 candidates per triangle, each a barycentric combination of
its corners:

* its 3 corners;
* the 12 points where an edge ``i -> j`` crosses a plane ``k``:
  ``s = g_i / (g_i - g_j)`` with ``g = pi_k . q``, ``0 <= s <= 1``;
* the 4 points where a lateral edge of the pyramid (planes ``k``, ``m`` adjacent:
  ``x = +-t z``, ``y = +-t z``) pierces the triangle: barycentric ``b_i = n_i / det``
  by Cramer's rule on ``sum b = 1``, ``sum b g_k = sum b g_m = 0``, inside when every
  ``n_i`` has the sign of ``det``;

each valid when all four plane values are ``>= -tau`` (``tau = 64 eps`` times the sum
of the corners' ``|g|``: a rounding of the coordinates' scale, as
:func:`._fit_formulas.triangle_far`). A vertex of the clipped polygon is a corner
inside, or lies on one plane (an edge crossing) or on two (a lateral edge, which
meets the triangle's plane in one point); so the valid candidates hold every
vertex of the polygon and lie in it. The fit needs extremes only: of the ratios
``x / z``, ``y / z`` (each linear-fractional with ``z > 0`` on the polygon, so
monotone along every segment) and of ``z`` (linear), which a convex polygon attains
at its vertices.

**Static shapes.** Candidates are never removed: an invalid one is replaced by the
first valid candidate of its batch entry, which changes no maximum or minimum (the
set of values is the same). When none is valid the entry's ``4`` spare slots hold
the corners of a square ``|x|, |y| <= s z0`` at depth ``z0`` (:func:`empty_square`),
and every slot takes the first of them: an empty fit, a frustum inside the pyramid
with no caster in it. Under ``jit`` and ``vmap`` the shapes depend on ``M`` only, and
gradients flow through the kept candidates. A non-finite candidate is kept (never
silently dropped), and so is every caster (a triangle's corners) where the planes are
not finite (a non-finite light, ``up`` or placement), so the fit's own checks report it.
That is JAX's form (:func:`clip_triangles`).

**NumPy: only the straddling triangles clipped.** Most triangles of a scene lie wholly
inside the sides or wholly outside one (or behind the light). :func:`classify` tells
them from their corners' 12 plane values (:func:`corner_values`): an inside triangle's
corners stand for its clipped polygon, an outside one has no valid candidate, and only
the rest (the straddling ones, and any with a non-finite value) go through the 19
candidates (:func:`candidates`, as :func:`clip_triangles`). :func:`select_triangles`
returns the kept points compacted, each batch entry padded with its first;
:func:`shadowmath._math._spot_loop.spot_clip_loop` does the same in one compiled loop
for one light (Numba). The kept count is the same; so are the points' extremes (an
inside triangle's valid candidates on its edges aside, which lie between its corners).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from types import ModuleType
from typing import NamedTuple

import numpy as np

from shadowmath._boundary._shapes import Bool, Float, Int
from shadowmath._boundary._validate import Array
from shadowmath._math._vector import matmul


class Selection(NamedTuple):
    """Casters as the fit reads them, and how many were kept.

    Attributes:
        points: ``(*batch, K, 3)`` in the casters' (local) coordinates: the kept
            points or clipped candidates, the invalid ones replaced (see the module):
            ``K = N + 4`` for points (``N`` in NumPy when every one is kept),
            ``19 M + 4`` for triangles under JAX; NumPy triangles' kept points compacted
            (the longest entry's count, or the square's 4 when nothing is kept), or
            every corner (``3 M``) when all are inside.
        kept: ``(*batch,)`` integer: the points or triangles kept; 0 means the empty fit.
    """

    points: Float[Array, "*batch K 3"]
    kept: Int[Array, "*batch"]


def pyramid_planes(
    xp: ModuleType,
    position: Float[Array, "*#batch 3"],
    axes: Float[Array, "*#batch 3 3"],
    t: Float[Array, "*#batch"],
) -> Float[Array, "*batch 5 4"]:
    """``(*batch, 5, 4)`` the pyramid ``|x|, |y| <= t z``'s side planes and the light's plane.

    ``position`` ``(*batch, 3)``; ``axes`` ``(*batch, 3, 3)`` rows ``X, Y, Z``;
    ``t`` ``(*batch,)``. Rows ``(n, -n . L)``: ``n = t Z -+ X``, ``t Z -+ Y`` (inside
    ``>= 0``), then ``n = Z`` (the light coordinate ``z``).
    """
    X, Y, Z = axes[..., 0, :], axes[..., 1, :], axes[..., 2, :]
    tz = t[..., None] * Z
    n = xp.stack([tz - X, tz + X, tz - Y, tz + Y, Z], axis=-2)
    d = -xp.sum(n * position[..., None, :], axis=-1)
    return xp.concatenate([n, d[..., None]], axis=-1)


def local_planes(
    xp: ModuleType, planes: Float[Array, "*#batch P 4"], B: Float[Array, "*#batch 4 4"] | None
) -> Float[Array, "*batch P 4"]:
    """Planes acting on local points: ``B^T pi`` per plane (rows ``pi^T B``)."""
    return planes if B is None else matmul(xp, planes, B)


def plane_values(
    xp: ModuleType, planes: Float[Array, "*#batch P 4"], q: Float[Array, "*#batch N 3"]
) -> Float[Array, "*batch N P"]:
    """``(*batch, N, P)`` the planes' values at points ``q`` ``(*batch, N, 3)``."""
    n = xp.matrix_transpose(planes[..., :3])
    return matmul(xp, q, n) + planes[..., None, :, 3]


def _tolerance(
    xp: ModuleType, g: Float[Array, "..."], axes: tuple[int, ...], eps: float
) -> Float[Array, "..."]:
    return 64.0 * eps * xp.sum(xp.abs(g), axis=axes)


def points_kept(
    xp: ModuleType, planes: Float[Array, "*#batch P 4"], q: Float[Array, "*#batch N 3"], eps: float
) -> Bool[Array, "*batch N"]:
    """``(*batch, N)`` the points ``q`` a spot's fit keeps (``planes`` of :func:`pyramid_planes`).

    A point set is kept as the fit has always read it, the blocker's vertices (whose
    ratio box, clipped to the square, covers their hull's part in the cone), less the
    points not in front of the light (``z <= 0``): the rest is kept unless, for some
    side plane, all of it lies outside by more than rounding (``g_k <= -tau``: nothing
    of it reaches the cone), when it is dropped as a whole. Where rounding cannot tell,
    the points are kept (keeping a caster never loses a shadow): the fit then reads them
    as it did before any selection, and refuses what lies within rounding of the light.
    A point at the light (every ``|g| <= tau``) is kept, for the fit to refuse.
    ``tau = 64 eps (|n| . |q| + |d|)`` per plane ``(n, d)``: the rounding of ``g``.
    """
    g = plane_values(xp, planes, q)
    tau = 64.0 * eps * plane_values(xp, xp.abs(planes), xp.abs(q))
    front = g[..., 4:5] > 0
    reaches = xp.all(xp.any(front & (g[..., :4] > -tau[..., :4]), axis=-2), axis=-1)
    at_light = xp.all(xp.abs(g) <= tau, axis=-1)
    return (front[..., 0] & reaches[..., None]) | at_light


def select_points(
    xp: ModuleType,
    planes: Float[Array, "*#batch P 4"],
    points: Float[Array, "*#batch N 3"],
    square: Float[Array, "*#batch 4 3"],
    eps: float,
) -> Selection:
    """Points ``(*batch, N, 3)`` selected by :func:`points_kept` (non-finite ones kept),
    the others replaced; ``square`` ``(*batch, 4, 3)`` for an empty entry."""
    keep = points_kept(xp, planes, points, eps) | ~xp.all(xp.isfinite(points), axis=-1)
    keep = keep | ~_finite_planes(xp, planes)[..., None]
    return _filled(xp, points, keep, xp.sum(keep, axis=-1), square)


def _finite_planes(xp: ModuleType, planes: Float[Array, "*batch P 4"]) -> Bool[Array, "*batch"]:
    """``(*batch,)`` the planes are finite: else (a non-finite light, ``up`` or placement,
    which the fit reports) nothing is dropped, so the fit's first check names the cause."""
    return xp.all(xp.isfinite(planes), axis=(-2, -1))


#: The 19 candidates' sources: the corner pairs of the edges and the adjacent plane pairs.
_EDGES = ((0, 1), (1, 2), (2, 0))
_LATERAL = ((0, 2), (0, 3), (1, 2), (1, 3))


def _weights(
    xp: ModuleType, g: Float[Array, "... 3 4"]
) -> tuple[Float[Array, "... 19 3"], Bool[Array, "... 19"]]:
    """Barycentric weights ``(..., 19, 3)`` of the candidates of triangles whose corners'
    plane values are ``g`` ``(..., 3, 4)``, and whether each exists ``(..., 19)``."""
    one, zero = xp.ones_like(g[..., 0, 0]), xp.zeros_like(g[..., 0, 0])
    rows: list[tuple[Array, Array, Array]] = [
        (one, zero, zero), (zero, one, zero), (zero, zero, one),
    ]  # fmt: skip
    ok: list[Array] = [one > 0] * 3
    for i, j in _EDGES:
        for k in range(4):
            gi, gj = g[..., i, k], g[..., j, k]
            den = gi - gj
            s = gi / xp.where(den != 0, den, one)
            w = [zero, zero, zero]
            w[i], w[j] = one - s, s
            rows.append((w[0], w[1], w[2]))
            ok.append((den != 0) & (s >= 0) & (s <= 1))
    for k, m in _LATERAL:
        a, b = g[..., k], g[..., m]  # (..., 3): the corners' values on planes k and m
        n0 = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
        n1 = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
        n2 = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
        det = n0 + n1 + n2
        inv = one / xp.where(det != 0, det, one)
        rows.append((n0 * inv, n1 * inv, n2 * inv))
        ok.append((n0 * det >= 0) & (n1 * det >= 0) & (n2 * det >= 0) & (det != 0))
    weights = xp.stack([xp.stack(r, axis=-1) for r in rows], axis=-2)
    return weights, xp.stack(ok, axis=-1)


def candidates(
    xp: ModuleType, g: Float[Array, "... 3 4"], corners: Float[Array, "... 3 3"], eps: float
) -> tuple[Float[Array, "... 19 3"], Bool[Array, "... 19"]]:
    """Triangles' 19 candidates ``(..., 19, 3)`` and which are kept ``(..., 19)``: valid
    (they exist and their four values ``w . g_k >= -tau``) or not finite.

    ``g`` ``(..., 3, 4)`` the corners' side values, ``corners`` ``(..., 3, 3)``;
    ``tau = 64 eps sum |g|`` per triangle (see the module).
    """
    w, exists = _weights(xp, g)
    points = matmul(xp, w, corners)
    values = matmul(xp, w, g)
    tau = _tolerance(xp, g, (-2, -1), eps)[..., None, None]
    inside = exists & xp.all(values >= -tau, axis=-1)
    return points, inside | ~xp.all(xp.isfinite(points), axis=-1)


def corner_values(
    planes: Float[Array, "*#batch P 4"], corners: Float[Array, "*#batch M 3 3"]
) -> Float[Array, "*batch 3 4 M"]:
    """NumPy: ``(*batch, 3, 4, M)`` the side planes' values ``g_ik`` at the corners of
    triangles ``(*batch, M, 3, 3)`` (triangles on the last axis: the reductions over a
    triangle's 12 values run along whole rows).

    One product ``(12, 9) @ (9, M)``: row ``4 i + k`` of the block-diagonal matrix holds
    ``n_k`` under corner ``i``'s coordinates, plus ``d_k``.
    """
    n, d = planes[..., :4, :3], planes[..., :4, 3]
    eye = np.eye(3, dtype=planes.dtype)
    N = eye[:, None, :, None] * n[..., None, :, None, :]  # (*batch, 3, 4, 3, 3)
    N = np.reshape(N, (*N.shape[:-4], 12, 9))
    X = np.swapaxes(np.reshape(corners, (*corners.shape[:-2], 9)), -1, -2)  # (*batch, 9, M)
    G = N @ X
    G += np.concatenate([d, d, d], axis=-1)[..., None]  # (in place: no fresh pages)
    return np.reshape(G, (*G.shape[:-2], 3, 4, G.shape[-1]))


def classify(
    G: Float[Array, "*batch 3 4 M"], eps: float
) -> tuple[Bool[Array, "*batch M"], Bool[Array, "*batch M"]]:
    """NumPy: which triangles lie inside the sides and which straddle them ``(*batch, M)``
    each, from their corners' side values ``G`` ``(*batch, 3, 4, M)``
    (:func:`corner_values`); the rest are dropped.

    With ``tau = 64 eps sum |g|`` finite: *inside* when every ``g_ik >= -tau`` (the corners
    are valid candidates, and every other valid one lies on the triangle, so the corners
    stand for its clipped polygon); *dropped* when for some side ``k`` every
    ``g_ik < -2 tau``, or every corner's ``sum_k g_ik < -8 tau`` (the sides sum to
    ``4 t z``: behind the light). Every candidate is a convex combination of the corners,
    so a dropped triangle has none valid (the factor 2 leaves the rounding of
    ``w . g`` far inside ``tau``). *Straddling*: the rest, and every triangle whose
    ``tau`` is not finite (a non-finite or overflowing corner): clipped as
    :func:`clip_triangles` clips it.

    Example:
        >>> import numpy as np
        >>> planes = pyramid_planes(np, np.zeros(3), np.eye(3), np.array(1.0))
        >>> tri = np.array([[[0, 0, 2.0], [0.5, 0, 2], [0, 0.5, 2]],   # inside
        ...                 [[5, 0, 2.0], [6, 0, 2], [5, 1, 2]],       # outside x <= z
        ...                 [[0, 0, -2.0], [1, 0, -2], [0, 1, -2]],    # behind the light
        ...                 [[0, 0, 2.0], [5, 0, 2], [0, 1, 2]]])      # crosses x = z
        >>> inside, straddle = classify(corner_values(planes, tri), 2.0**-52)
        >>> inside.tolist(), straddle.tolist()
        ([True, False, False, False], [False, False, False, True])
    """
    tau = 64.0 * eps * np.sum(np.abs(G), axis=(-3, -2))
    finite = np.isfinite(tau)
    inside = finite & (np.min(G, axis=(-3, -2)) >= -tau)
    outside = np.any(np.max(G, axis=-3) < -2.0 * tau[..., None, :], axis=-2)
    behind = np.max(np.sum(G, axis=-2), axis=-2) < -8.0 * tau
    return inside, ~inside & ~(finite & (outside | behind))


#: Triangles classified at a time by :func:`select_triangles`. A block's corner values
#: (``12 x 2048`` floats) and their temporaries stay in cache and reuse memory (one pass
#: over the whole ``(12, M)`` array writes fresh pages: about twice the time), and its
#: product ``(12, 9) @ (9, 2048)`` stays under OpenBLAS's bound for threads (``m n k <=
#: 65536 * 4``): on a loaded machine its threads made blocks of 8192 five times slower.
BLOCK = 2048


def select_triangles(
    planes: Float[Array, "*#batch P 4"],
    corners: Float[Array, "*#batch M 3 3"],
    square: Callable[[], Float[Array, "*#batch 4 3"]],
    eps: float,
) -> Selection:
    """NumPy: triangles ``(*batch, M, 3, 3)`` clipped by the planes, only the straddling
    ones through the 19 candidates (:func:`classify`): ``(*batch, K, 3)`` points.

    The kept points of each batch entry: an inside triangle's corners, a straddling one's
    kept candidates (:func:`candidates`); the entry's first point fills it up to the
    longest entry's ``K``; an entry with none holds the square ``square()``
    ``(*batch, 4, 3)`` (called only then). Where the planes are not finite every
    triangle's corners are kept, as :func:`clip_triangles` keeps them. ``kept`` counts
    the triangles with a kept point, as there. Classified :data:`BLOCK` triangles at a
    time.
    """
    shape = np.broadcast_shapes(planes.shape[:-2], corners.shape[:-3])
    count = corners.shape[-3]
    C = np.broadcast_to(corners, (*shape, count, 3, 3))
    entry = np.broadcast_to(np.arange(math.prod(shape)).reshape(*shape, 1), (*shape, count))
    finite = np.broadcast_to(_finite_planes(np, planes), shape)[..., None]
    inside = np.empty((*shape, count), dtype=bool)
    g_st, c_st, e_st = [], [], []  # the straddling triangles' values, corners, entries
    for start in range(0, count, BLOCK):
        part = slice(start, start + BLOCK)
        G = corner_values(planes, corners[..., part, :, :])  # (*batch, 3, 4, <= BLOCK)
        inside[..., part], straddle = classify(G, eps)
        inside[..., part] |= ~finite
        straddle &= finite
        if straddle.any():
            g_st.append(np.moveaxis(G, -1, -3)[straddle])  # (S, 3, 4)
            c_st.append(C[..., part, :, :][straddle])
            e_st.append(entry[..., part][straddle])
    if inside.all():  # the common case: every corner, unchanged
        flat = np.reshape(corners, (*corners.shape[:-3], -1, 3))
        return Selection(flat, np.full(shape, count, dtype=np.int64))
    dtype = np.result_type(planes, corners)
    g = np.concatenate(g_st) if g_st else np.zeros((0, 3, 4), dtype)
    points, keep = candidates(np, g, np.concatenate(c_st) if c_st else g[..., :3], eps)
    found = np.concatenate([C[inside].reshape(-1, 3), points[keep]])
    if not shape:  # one light: the points as found
        kept = np.sum(inside) + np.sum(np.any(keep, axis=-1))
        return Selection(found if len(found) else square(), kept)
    straddling = np.concatenate(e_st) if e_st else np.zeros(0, dtype=np.int64)
    ids = np.concatenate([np.repeat(entry[inside], 3), np.repeat(straddling, keep.sum(axis=-1))])
    clipped = np.bincount(straddling[keep.any(axis=-1)], minlength=entry.size // count)
    kept = np.sum(inside, axis=-1) + clipped.reshape(shape)
    return Selection(_padded(ids, found, shape, square), kept)


def _padded(
    ids: Int[Array, " n"],
    found: Float[Array, "n 3"],
    shape: tuple[int, ...],
    square: Callable[[], Float[Array, "*#batch 4 3"]],
) -> Float[Array, "*batch K 3"]:
    """Points ``found`` ``(n, 3)`` of entries ``ids`` as ``(*batch, K, 3)``: each entry's
    points, then its first repeated; an entry with none, the square's corners."""
    size = math.prod(shape)
    order = np.argsort(ids, kind="stable")
    ids, found = ids[order], found[order]
    counts = np.bincount(ids, minlength=size)
    empty = counts == 0
    width = max(int(counts.max(initial=0)), 4 if empty.any() else 1)
    starts = np.cumsum(counts) - counts
    out = np.empty((size, width, 3), dtype=found.dtype)
    if empty.any():
        corners = np.broadcast_to(square(), (*shape, 4, 3)).reshape(size, 4, 3)[empty]
        out[empty] = corners[:, :1]
        out[empty, :4] = corners
    full = ~empty
    out[full] = found[starts[full]][:, None]
    out[ids, np.arange(len(ids)) - starts[ids]] = found
    return out.reshape(*shape, width, 3)


def clip_triangles(
    xp: ModuleType,
    planes: Float[Array, "*#batch P 4"],
    corners: Float[Array, "*#batch M 3 3"],
    square: Float[Array, "*#batch 4 3"],
    eps: float,
) -> Selection:
    """Triangles ``(*batch, M, 3, 3)`` clipped by the planes: ``19 M + 4`` points (module).

    Example:
        >>> import numpy as np
        >>> axes = np.eye(3)  # the light at the origin looking down +Z, t = 1
        >>> planes = pyramid_planes(np, np.zeros(3), axes, np.array(1.0))
        >>> tri = np.array([[[0.0, 1.0, -1.0], [0.5, 1.0, 3.0], [-0.5, 1.0, 3.0]]])  # y = 1
        >>> s = clip_triangles(np, planes, tri, np.zeros((4, 3)), 2.0**-52)
        >>> int(s.kept), float(s.points[:, 2].min()), float(s.points[:, 2].max())  # y <= z
        (1, 1.0, 3.0)
    """
    g = plane_values(xp, planes[..., None, :4, :], corners)  # (*batch, M, 3, 4)
    points, keep = candidates(xp, g, corners, eps)  # (*batch, M, 19, 3), (*batch, M, 19)
    corner = xp.arange(19) < 3  # the corners themselves (exact, whatever the planes)
    finite = _finite_planes(xp, planes)[..., None, None]
    keep = xp.where(finite, keep, corner)
    kept = xp.sum(xp.any(keep, axis=-1), axis=-1)
    flat = xp.reshape(points, (*points.shape[:-3], -1, 3))
    return _filled(xp, flat, xp.reshape(keep, flat.shape[:-1]), kept, square)


def _filled(
    xp: ModuleType,
    points: Float[Array, "*#batch K 3"],
    keep: Bool[Array, "*#batch K"],
    kept: Int[Array, "*#batch"],
    square: Float[Array, "*#batch 4 3"],
) -> Selection:
    """Every point not kept replaced by the first kept one (the square's first corner when
    none is); the square's four corners appended, kept only when nothing else is."""
    shape = xp.broadcast_shapes(points.shape[:-2], keep.shape[:-1], square.shape[:-2])
    count = points.shape[-2]
    empty = xp.broadcast_to(kept == 0, shape)
    points = xp.concatenate(
        [xp.broadcast_to(points, (*shape, count, 3)), xp.broadcast_to(square, (*shape, 4, 3))],
        axis=-2,
    )
    keep = xp.concatenate(
        [xp.broadcast_to(keep, (*shape, count)), xp.broadcast_to(empty[..., None], (*shape, 4))],
        axis=-1,
    )
    first = xp.argmax(keep, axis=-1)[..., None, None]
    fill = xp.take_along_axis(points, xp.broadcast_to(first, (*shape, 1, 3)), axis=-2)
    return Selection(xp.where(keep[..., None], points, fill), xp.broadcast_to(kept, shape))


def empty_square(
    xp: ModuleType,
    position: Float[Array, "*#batch 3"],
    axes: Float[Array, "*#batch 3 3"],
    t: Float[Array, "*#batch"],
    depth: Float[Array, "*#batch"],
) -> Float[Array, "*batch 4 3"]:
    """``(*batch, 4, 3)`` world corners ``L + z0 (+-s X +- s Y + Z)``, ``s = min(t, 1)``.

    The empty fit's casters: a square inside the pyramid (``s <= t``) and at most 90
    degrees wide (so a cone near 180 degrees still fits), at depth ``z0 = depth``.
    """
    s = xp.minimum(t, 1.0)[..., None, None]
    signs = xp.asarray([[1.0, 1.0], [1.0, -1.0], [-1.0, 1.0], [-1.0, -1.0]], dtype=axes.dtype)
    X, Y, Z = axes[..., None, 0, :], axes[..., None, 1, :], axes[..., None, 2, :]
    offset = s * (signs[:, 0:1] * X + signs[:, 1:2] * Y) + Z
    return position[..., None, :] + depth[..., None, None] * offset


def caster_depth(
    xp: ModuleType,
    planes: Float[Array, "*#batch P 4"],
    B: Float[Array, "*#batch 4 4"] | None,
    q: Float[Array, "*#batch N 3"],
) -> Float[Array, "*batch"]:
    """``(*batch,)`` the casters' largest ``|z|`` (1 if none or zero): the depth of the
    empty fit's square. ``planes`` of :func:`pyramid_planes` on local points
    ``q`` ``(*batch, N, 3)`` (the last is ``z``; ``B``'s last row gives ``w``)."""
    if B is None:
        z = plane_values(xp, planes[..., 4:5, :], q)[..., 0]
    else:
        zw = plane_values(xp, xp.concatenate([planes[..., 4:5, :], B[..., 3:4, :]], axis=-2), q)
        z = zw[..., 0] / xp.where(zw[..., 1] > 0, zw[..., 1], 1.0)
    depth = xp.max(xp.abs(z), axis=-1)
    return xp.where(xp.isfinite(depth) & (depth > 0), depth, 1.0)


def to_local(
    xp: ModuleType, B: Float[Array, "*#batch 4 4"] | None, p: Float[Array, "*#batch K 3"]
) -> Float[Array, "*batch K 3"]:
    """World points ``(*batch, K, 3)`` in the placement's local coordinates (``B^-1``).

    A singular or non-finite ``B`` is replaced by the identity (the fit refuses it).
    """
    if B is None:
        return p
    det = xp.linalg.det(B)
    ok = xp.isfinite(det) & (det != 0)
    safe = xp.where(ok[..., None, None], B, xp.eye(4, dtype=B.dtype))
    h = matmul(xp, xp.concatenate([p, xp.ones_like(p[..., :1])], axis=-1),
                  xp.matrix_transpose(xp.linalg.inv(safe)))  # fmt: skip
    return h[..., :3] / h[..., 3:]
