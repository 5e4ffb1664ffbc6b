"""The fits' per-vertex and per-entry formulas, one source for every backend.

The fits (:mod:`shadowmath._fits.shadow._arrays` on whole arrays, :mod:`._loops`
compiled per batch entry) are two drivers of the same steps:

1. a pass over the vertices (through the placement, :func:`place`): sums,
   bounds and scales;
2. the frame (:func:`fit_axes`);
3. a pass in light coordinates (:func:`to_light`): ratios or box, depth range;
4. the sides (:func:`point_sides`, :func:`box_sides`, :func:`stable_sides`);
5. a pass over the receivers (:func:`receiver_counted`) that widens the depth range;
6. the depth range (:func:`depth_range`; :func:`directional_origin` first for a
   directional light) and the matrices (:func:`fit_rows`).

Every step here is plain arithmetic written with the primitives ``where``,
``sqrt``, ``fabs``, ``rint`` and ``isfinite`` (bound per backend by
:func:`._formulas.specialize`), so the drivers differ only in how they loop and
reduce. Flags that are static for a call (``has_up``, ``directional``, ...) are
Python booleans: the array driver branches on them while tracing, the compiled
loop at run time. Checks come back as booleans (True: valid), in the order of
:data:`shadowmath._boundary._status.FORMULA_CHECKS`; ``True`` means the check does not apply.

Trusted inputs only: nothing here raises.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from shadowmath._boundary._messages import MAX_FOV_TAN, WIDE_FOV_TAN

# Backend primitives and the shared formulas, rebound by specialize().
from shadowmath._boundary._shapes import Scalar, Truth

from ._formulas import (  # noqa: F401  (names the specialized copies look up)
    clip_rows,
    fabs,
    frame_axes,
    isfinite,
    light_rows,
    maximum,
    normalize3,
    projection_rows,
    rolled_axes,
    sqrt,
    where,
)
from ._rows import MatrixEntries
from ._vector import matmul

rint: Any = None  # round half to even; bound by specialize()
array_api: Any = None  # the array mode's namespace; bound by specialize()
fit_rows: Any = None  # the mode's form (:data:`FORMS`); bound by specialize()

#: Names bound per mode by specialize(): ``name: (loop form, array form)``.
FORMS = {"fit_rows": ("_rows_loop", "_rows_array")}


def place(
    b: tuple[Scalar, ...], px: Scalar, py: Scalar, pz: Scalar
) -> tuple[Scalar, Scalar, Scalar, Scalar]:
    """A vertex through the placement ``b`` (16 row-major entries): world ``x, y, z`` and ``w``.

    The homogeneous divide uses a safe ``w`` (1 where ``w <= 0``; such a vertex is
    reported by the ``projective`` check).
    """
    w = b[12] * px + b[13] * py + b[14] * pz + b[15]
    s = 1.0 / where(w > 0, w, 1.0)
    return (
        (b[0] * px + b[1] * py + b[2] * pz + b[3]) * s,
        (b[4] * px + b[5] * py + b[6] * pz + b[7]) * s,
        (b[8] * px + b[9] * py + b[10] * pz + b[11]) * s,
        w,
    )


def to_light(
    ox: Scalar, oy: Scalar, oz: Scalar, a: tuple[Scalar, ...]
) -> tuple[Scalar, Scalar, Scalar]:
    """``(X . o, Y . o, Z . o)``: light coordinates of the offset ``o`` from the frame's origin."""
    return (
        ox * a[0] + oy * a[1] + oz * a[2],
        ox * a[3] + oy * a[4] + oz * a[5],
        ox * a[6] + oy * a[7] + oz * a[8],
    )


def bounds_about(
    lo: tuple[Scalar, ...], hi: tuple[Scalar, ...], o: tuple[Scalar, ...]
) -> tuple[tuple[Scalar, Scalar, Scalar], tuple[Scalar, Scalar, Scalar], Scalar, Scalar]:
    """The bounds of ``p - o`` from the bounds ``lo <= hi`` of the points ``p`` (3 each),
    the reach ``max |p - o|`` over the components and the coordinates' size ``max |p|``.

    Exact, not a bound: a rounded difference ``fl(p - o)`` is monotone in ``p``, so
    its extremes are the differences of the extremes, and over ``[lo, hi]`` the
    largest ``|v|`` is ``max(hi, -lo)``. So one pass's bounds of ``p`` give them about
    any point ``o``.
    """
    lo_o = (lo[0] - o[0], lo[1] - o[1], lo[2] - o[2])
    hi_o = (hi[0] - o[0], hi[1] - o[1], hi[2] - o[2])
    return lo_o, hi_o, _largest(lo_o, hi_o), _largest(lo, hi)


def _largest(lo: tuple[Scalar, ...], hi: tuple[Scalar, ...]) -> Scalar:
    """``max |v|`` over the boxes ``[lo_j, hi_j]``: ``max_j max(hi_j, -lo_j)``."""
    m = maximum(hi[0], -lo[0])
    return maximum(maximum(m, maximum(hi[1], -lo[1])), maximum(hi[2], -lo[2]))


def fit_axes(
    d: tuple[Scalar, Scalar, Scalar],
    up: tuple[Scalar, Scalar, Scalar],
    has_up: bool,
    coords: Scalar,
    eps: float,
) -> tuple[tuple[Scalar, ...], Truth, Truth, Truth]:
    """The frame of the viewing direction ``d``: axes ``X, Y, Z`` (9) and three checks.

    Nagy's helper axis (:func:`._formulas.frame_axes`), or with an up hint the
    look-at frame: ``Y`` the part of ``up`` perpendicular to ``Z``, ``X = Z x Y``
    (:func:`._formulas.rolled_axes` at angle 0). Checks: ``d`` nonzero (a
    directional light's own direction), ``d`` longer than the rounding noise of
    the coordinates (``32 eps coords``; a point light at the blocker's centre),
    ``up`` nonzero and not within ``256 eps`` radians of ``d``.
    """
    if has_up:
        one = d[0] * 0.0 + 1.0
        r = rolled_axes(d, up, one, one - 1.0)
        axes = (r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8])
        length = r[9]
        up_len = where(fabs(up[0]) >= fabs(up[1]), fabs(up[0]), fabs(up[1]))
        up_len = where(up_len >= fabs(up[2]), up_len, fabs(up[2]))
        tolerance = 256.0 * eps
        ok_up = (up_len > 0) & (r[10] > tolerance * tolerance)
    else:
        f = frame_axes(d[0], d[1], d[2])
        axes = (f[0], f[1], f[2], f[3], f[4], f[5], f[6], f[7], f[8])
        length = f[9]
        ok_up = True
    return axes, length > 0, length > 32.0 * eps * coords, ok_up


def placement_ok(b: tuple[Scalar, ...], eps: float) -> Truth:
    """The placement ``b`` (16 row-major entries) does not flatten the blocker.

    Its linear part ``A`` (the upper-left 3 x 3) is invertible beyond rounding:
    ``|det A| > 64 eps prod_i |A_i|`` over its rows. By Hadamard's inequality the
    ratio lies in ``[0, 1]`` whatever the scale, and the translation does not enter,
    so a tiny, huge or far-moved placement passes and a zero scale fails.
    """
    det = (
        b[0] * (b[5] * b[10] - b[6] * b[9])
        - b[1] * (b[4] * b[10] - b[6] * b[8])
        + b[2] * (b[4] * b[9] - b[5] * b[8])
    )
    n0 = sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2])
    n1 = sqrt(b[4] * b[4] + b[5] * b[5] + b[6] * b[6])
    n2 = sqrt(b[8] * b[8] + b[9] * b[9] + b[10] * b[10])
    return fabs(det) > 64.0 * eps * (n0 * n1 * n2)


def placement_affine(b: tuple[Scalar, ...], eps: float) -> Truth:
    """The placement ``b`` (16 row-major entries) has the last row ``(0, 0, 0, 1)`` to rounding.

    ``|b_3j - (0, 0, 0, 1)_j| <= 4 eps max |b|`` for every ``j``: rounding only, whatever
    the matrix's scale. A row-major (transposed) placement, its translation in the
    bottom row, fails, and so does a projective one.
    """
    big = fabs(b[0])
    for j in range(1, 16):
        big = maximum(big, fabs(b[j]))
    off = maximum(maximum(fabs(b[12]), fabs(b[13])), maximum(fabs(b[14]), fabs(b[15] - 1.0)))
    return off <= 4.0 * eps * big


def near_clear(z_min: Scalar, coords: Scalar, eps: float) -> Truth:
    """The nearest caster clears the rounding of the coordinates (``z > 32 eps coords``)."""
    return z_min > 32.0 * eps * coords


def fov_ok(
    sides: tuple[Scalar, Scalar, Scalar, Scalar], margins: tuple[float, float]
) -> tuple[Truth, Truth]:
    """A perspective map's widest ratio ``|c| + h / m`` within the hard and the warning limit.

    The map's edge is at ``u = c +- h / m`` (NDC ``+-1``); ``atan`` of the larger is
    half the field of view. Limits: ``MAX_FOV_TAN`` (170 degrees, refused) and
    ``WIDE_FOV_TAN`` (120 degrees, warned) of :mod:`shadowmath._boundary._messages`.
    """
    half_x, half_y, cx, cy = sides
    tx = fabs(cx) + half_x / margins[0]
    ty = fabs(cy) + half_y / margins[1]
    t = where(tx >= ty, tx, ty)
    return t <= MAX_FOV_TAN, t <= WIDE_FOV_TAN


def point_sides(
    bounds: tuple[Scalar, Scalar, Scalar, Scalar], z_min: Scalar, reach: Scalar, eps: float
) -> tuple[Scalar, Scalar, Truth, Truth]:
    """The article's symmetric frustum: half-widths ``max(hi, -lo)`` of the ratios, two checks.

    ``bounds = (hi_x, lo_x, hi_y, lo_y)`` of ``x / z``, ``y / z`` (as :func:`spot_sides`).
    Thresholds relative to the blocker's reach from the light (``noise = 32 eps
    reach``): a vertex is in front only when its ``z`` clears the rounding noise
    of light coordinates, and a silhouette has width only when its ratios clear
    ``2 noise / z_min``, in any units.
    """
    hi_x, lo_x, hi_y, lo_y = bounds
    noise = 32.0 * eps * reach
    half_x = where(hi_x >= -lo_x, hi_x, -lo_x)
    half_y = where(hi_y >= -lo_y, hi_y, -lo_y)
    ratio_noise = 2.0 * noise / where(z_min > 0, z_min, 1.0)
    ok_sil = (half_x > ratio_noise) & (half_y > ratio_noise)
    return half_x, half_y, z_min > noise, ok_sil


def spot_sides(
    bounds: tuple[Scalar, Scalar, Scalar, Scalar],
    t: Scalar,
    z_min: Scalar,
    reach: Scalar,
    eps: float,
) -> tuple[Scalar, Scalar, Scalar, Scalar, Truth, Truth, Truth]:
    """A spot light's frustum: the ratios' bounds clipped to its cone's bounding square.

    ``bounds = (hi_x, lo_x, hi_y, lo_y)`` of ``x / z``, ``y / z`` in the frame whose
    ``Z`` is the cone's axis, ``t = tan(angle)``. The clipped bounds
    ``[max(lo, -t), min(hi, t)]`` give an off-centre frustum (half-widths and
    centres) that holds every caster inside the cone and no texel outside the
    square ``|x / z|, |y / z| <= t`` around it. Checks: in front (as a point
    light), inside the cone's square, a silhouette of nonzero width.
    """
    hi_x, lo_x, hi_y, lo_y = bounds
    hx, lx = where(hi_x <= t, hi_x, t), where(lo_x >= -t, lo_x, -t)
    hy, ly = where(hi_y <= t, hi_y, t), where(lo_y >= -t, lo_y, -t)
    noise = 32.0 * eps * reach
    ratio_noise = 2.0 * noise / where(z_min > 0, z_min, 1.0)
    half_x, half_y = 0.5 * (hx - lx), 0.5 * (hy - ly)
    ok_cone = (hx > lx) & (hy > ly)
    ok_sil = (half_x > ratio_noise) & (half_y > ratio_noise)
    return half_x, half_y, 0.5 * (hx + lx), 0.5 * (hy + ly), z_min > noise, ok_cone, ok_sil


def spot_angle_ok(angle: Scalar) -> Truth:
    """A spot light's half-angle lies in ``(0, pi/2)`` (a cone, not a half-space)."""
    return (angle > 0) & (angle < 1.5707963267948966)


def box_sides(
    bounds: tuple[Scalar, Scalar, Scalar, Scalar], reach: Scalar, eps: float
) -> tuple[Scalar, Scalar, Scalar, Scalar, Truth]:
    """A directional light's box: half-widths and centre of the light-space bounds, a check.

    ``bounds = (hi_x, lo_x, hi_y, lo_y)`` of ``x`` and ``y`` in light coordinates.
    """
    hi_x, lo_x, hi_y, lo_y = bounds
    half_x, half_y = 0.5 * (hi_x - lo_x), 0.5 * (hi_y - lo_y)
    noise = 64.0 * eps * reach  # twice the coordinates' noise, as for the ratios
    ok_sil = (half_x > noise) & (half_y > noise)
    return half_x, half_y, 0.5 * (hi_x + lo_x), 0.5 * (hi_y + lo_y), ok_sil


def stable_sides(
    sphere: tuple[tuple[Scalar, Scalar, Scalar], Scalar],
    a: tuple[Scalar, ...],
    texels: tuple[Scalar, Scalar, Scalar, Scalar],
    reach: Scalar,
    eps: float,
) -> tuple[Scalar, Scalar, Scalar, Scalar, Truth]:
    """A stable map's box: the bounding sphere enlarged by half a texel, centre snapped.

    ``sphere = (c, r^2)``, ``texels = (m_x, m_y, width, height)``. The half-width
    ``h`` holds the sphere of radius ``r`` after the centre moved by up to half a texel:
    ``h (1 - 1 / (m W)) = r``, one texel being ``2 h / (m W)``. The centre's
    coordinates along ``X`` and ``Y`` from the world origin, ``c . X``, are
    rounded to whole texels, so the texel grid is anchored in world space.
    Returns the half-widths, the centre's offsets from ``c`` and a check.
    """
    c, r2_max = sphere
    mx, my, width, height = texels
    radius = sqrt(r2_max)
    half_x = radius / (1.0 - 1.0 / (mx * width))
    half_y = radius / (1.0 - 1.0 / (my * height))
    tx, ty = 2.0 * half_x / (mx * width), 2.0 * half_y / (my * height)
    ax = c[0] * a[0] + c[1] * a[1] + c[2] * a[2]
    ay = c[0] * a[3] + c[1] * a[4] + c[2] * a[5]
    safe_tx, safe_ty = where(tx > 0, tx, 1.0), where(ty > 0, ty, 1.0)
    cx = rint(ax / safe_tx) * tx - ax
    cy = rint(ay / safe_ty) * ty - ay
    noise = 64.0 * eps * reach
    return half_x, half_y, cx, cy, (half_x > noise) & (half_y > noise)


def _dot(d: tuple[Scalar, ...], i: int, j: int) -> Scalar:
    return d[3 * i] * d[3 * j] + d[3 * i + 1] * d[3 * j + 1] + d[3 * i + 2] * d[3 * j + 2]


def sphere_through(q: tuple[Scalar, ...], k: Scalar) -> tuple[Scalar, Scalar, Scalar, Scalar]:
    """The smallest sphere with the first ``k`` (1 to 4) of four points on it: centre, ``r^2``.

    ``q``: the points ``p_0 .. p_3`` (12 numbers). With ``d_i = p_i - p_0`` the
    centre is ``c = p_0 + sum l_i d_i`` over the ``k - 1`` active ``d_i``, where
    ``d_i . (c - p_0) = |d_i|^2 / 2`` (equidistant from ``p_0`` and ``p_i``):
    the Gram system ``G l = |d|^2 / 2``, solved by cofactors, with the identity in
    the rows of inactive points (their ``l_i = 0``). For ``k = 2`` the diameter
    sphere, for 3 the circumcircle's sphere, for 4 the circumsphere. The minimal
    enclosing sphere of a point set is one of these on its support points
    (:func:`._loops._enclosing_sphere` finds them), so it is a smooth function of
    them: its derivative is theirs.
    """
    d = (
        q[3] - q[0], q[4] - q[1], q[5] - q[2],
        q[6] - q[0], q[7] - q[1], q[8] - q[2],
        q[9] - q[0], q[10] - q[1], q[11] - q[2],
    )  # fmt: skip
    on1, on2, on3 = k > 1, k > 2, k > 3
    zero = d[0] * 0.0

    g00, g11, g22 = (
        where(on1, _dot(d, 0, 0), 1.0),
        where(on2, _dot(d, 1, 1), 1.0),
        where(on3, _dot(d, 2, 2), 1.0),
    )
    g01 = where(on1 & on2, _dot(d, 0, 1), zero)
    g02 = where(on1 & on3, _dot(d, 0, 2), zero)
    g12 = where(on2 & on3, _dot(d, 1, 2), zero)
    b0, b1, b2 = (
        where(on1, 0.5 * _dot(d, 0, 0), zero),
        where(on2, 0.5 * _dot(d, 1, 1), zero),
        where(on3, 0.5 * _dot(d, 2, 2), zero),
    )
    c00, c01, c02 = g11 * g22 - g12 * g12, g02 * g12 - g01 * g22, g01 * g12 - g02 * g11
    c11, c12, c22 = g00 * g22 - g02 * g02, g01 * g02 - g00 * g12, g00 * g11 - g01 * g01
    det = g00 * c00 + g01 * c01 + g02 * c02
    inv = 1.0 / where(det != 0, det, 1.0)
    l0 = (c00 * b0 + c01 * b1 + c02 * b2) * inv
    l1 = (c01 * b0 + c11 * b1 + c12 * b2) * inv
    l2 = (c02 * b0 + c12 * b1 + c22 * b2) * inv
    ox = l0 * d[0] + l1 * d[3] + l2 * d[6]
    oy = l0 * d[1] + l1 * d[4] + l2 * d[7]
    oz = l0 * d[2] + l1 * d[5] + l2 * d[8]
    return q[0] + ox, q[1] + oy, q[2] + oz, ox * ox + oy * oy + oz * oz


def side_values(
    x: Scalar, y: Scalar, z: Scalar, sides: tuple[Scalar, Scalar, Scalar, Scalar], directional: bool
) -> tuple[Scalar, Scalar, Scalar, Scalar]:
    """The map's four side planes at a point: ``(g_0, g_1, g_2, g_3)``, all ``>= 0`` inside.

    ``sides = (s_x, s_y, c_x, c_y)``: NDC ``x = s_x (u - c_x)`` with ``u = x / z``
    (perspective) or ``u = x`` (orthographic). With ``w = z`` (perspective) or
    ``w = 1``, ``g = w -+ s_x (x - c_x w)`` and ``w -+ s_y (y - c_y w)``: affine in
    the point, so along a segment or over a triangle they interpolate linearly
    (which :func:`triangle_far` relies on), and for a perspective map all four
    ``>= 0`` already implies ``z >= 0`` (the map's cone has one nappe).
    """
    sx, sy, cx, cy = sides
    w = x * 0.0 + 1.0 if directional else z
    ex, ey = sx * (x - cx * w), sy * (y - cy * w)
    return w - ex, w + ex, w - ey, w + ey


def receiver_counted(
    x: Scalar, y: Scalar, z: Scalar, sides: tuple[Scalar, Scalar, Scalar, Scalar], directional: bool
) -> Truth:
    """True for a receiver point inside the map's side planes (and, for a point, in front)."""
    g = side_values(x, y, z, sides, directional)
    inside = (g[0] >= 0) & (g[1] >= 0) & (g[2] >= 0) & (g[3] >= 0)
    return inside & ((z > 0) | directional)


def _inside_but(g: tuple[Scalar, Scalar, Scalar, Scalar], k: int, m: int, tau: Scalar) -> Truth:
    """All side values ``>= -tau`` except planes ``k`` and ``m`` (those the point lies on)."""
    ok = (k == 0) | (m == 0) | (g[0] >= -tau)
    ok = ok & ((k == 1) | (m == 1) | (g[1] >= -tau))
    ok = ok & ((k == 2) | (m == 2) | (g[2] >= -tau))
    return ok & ((k == 3) | (m == 3) | (g[3] >= -tau))


def _corner_in(
    g: tuple[Scalar, ...], z: Scalar, best: Scalar, tau: Scalar, directional: bool
) -> Scalar:
    """``best`` raised to a triangle corner's ``z`` when the corner is inside the sides."""
    ok = _inside_but(g, -1, -1, tau) & ((z > 0) | directional)
    return where(ok & (z > best), z, best)


def _lerp4(
    a: tuple[Scalar, ...], b: tuple[Scalar, ...], t: Scalar
) -> tuple[Scalar, Scalar, Scalar, Scalar]:
    return (
        a[0] + t * (b[0] - a[0]),
        a[1] + t * (b[1] - a[1]),
        a[2] + t * (b[2] - a[2]),
        a[3] + t * (b[3] - a[3]),
    )


def _edge_far(
    g: tuple[tuple[Scalar, ...], tuple[Scalar, ...]],
    z: tuple[Scalar, Scalar],
    best: Scalar,
    tau: Scalar,
) -> Scalar:
    """``best`` raised to ``z`` where the edge ``i -> j`` crosses a side plane inside the others.

    ``g = (g_i, g_j)``: the ends' side values; ``z = (z_i, z_j)``: their light ``z``.
    """
    gi, gj = g
    zi, zj = z
    for k in range(4):
        den = gi[k] - gj[k]
        t = gi[k] / where(den != 0, den, 1.0)
        cross = (t >= 0) & (t <= 1) & (den != 0)  # the signs differ (or one is zero)
        ok = cross & _inside_but(_lerp4(gi, gj, t), k, k, tau)
        zc = zi + t * (zj - zi)
        best = where(ok & (zc > best), zc, best)
    return best


def _corner_far(
    g: tuple[tuple[Scalar, ...], tuple[Scalar, ...], tuple[Scalar, ...]],
    z: tuple[Scalar, Scalar, Scalar],
    planes: tuple[int, int],
    best: Scalar,
    tau: Scalar,
) -> Scalar:
    """``best`` raised to ``z`` where the map's edge (``planes = (k, m)``) pierces the triangle.

    Barycentric ``b_i = n_i / det`` (Cramer's rule on ``sum b = 1``,
    ``sum b g_k = sum b g_m = 0``); inside the triangle when every ``n_i`` has the
    sign of ``det``.
    """
    g0, g1, g2 = g
    k, m = planes
    n0 = g1[k] * g2[m] - g2[k] * g1[m]
    n1 = g2[k] * g0[m] - g0[k] * g2[m]
    n2 = g0[k] * g1[m] - g1[k] * g0[m]
    det = n0 + n1 + n2
    inside = (n0 * det >= 0) & (n1 * det >= 0) & (n2 * det >= 0) & (det != 0)
    inv = 1.0 / where(det != 0, det, 1.0)
    b0, b1, b2 = n0 * inv, n1 * inv, n2 * inv
    gp = (
        b0 * g0[0] + b1 * g1[0] + b2 * g2[0],
        b0 * g0[1] + b1 * g1[1] + b2 * g2[1],
        b0 * g0[2] + b1 * g1[2] + b2 * g2[2],
        b0 * g0[3] + b1 * g1[3] + b2 * g2[3],
    )
    ok = inside & _inside_but(gp, k, m, tau)
    zc = b0 * z[0] + b1 * z[1] + b2 * z[2]
    return where(ok & (zc > best), zc, best)


def triangle_far(
    p: tuple[Scalar, ...],
    sides: tuple[Scalar, Scalar, Scalar, Scalar],
    directional: bool,
    eps: float,
) -> Scalar:
    """The largest light ``z`` of a triangle's part inside the map's sides (``-inf``: none).

    ``p``: the three corners' light coordinates (9). The part inside is the triangle
    clipped by the four side planes (:func:`side_values`; for a perspective map
    their cone lies in front of the light). ``z`` is linear over it, so its maximum
    is at a corner of the clipped polygon, one of: a triangle corner inside the
    sides; an edge crossing a side plane inside the others; a map edge (two
    adjacent side planes) piercing the triangle. Exact up to rounding: points
    within ``64 eps`` of the side values' scale outside a plane count as inside
    (a range a rounding larger, never smaller).
    """
    g0 = side_values(p[0], p[1], p[2], sides, directional)
    g1 = side_values(p[3], p[4], p[5], sides, directional)
    g2 = side_values(p[6], p[7], p[8], sides, directional)
    scale = fabs(g0[0]) + fabs(g0[1]) + fabs(g1[0]) + fabs(g1[1]) + fabs(g2[0]) + fabs(g2[1])
    scale = scale + fabs(g0[2]) + fabs(g0[3]) + fabs(g1[2]) + fabs(g1[3])
    tau = 64.0 * eps * (scale + fabs(g2[2]) + fabs(g2[3]))
    z = (p[2], p[5], p[8])
    best = z[0] * 0.0 - math.inf  # in the corners' type
    best = _corner_in(g0, z[0], best, tau, directional)
    best = _corner_in(g1, z[1], best, tau, directional)
    best = _corner_in(g2, z[2], best, tau, directional)
    best = _edge_far((g0, g1), (z[0], z[1]), best, tau)
    best = _edge_far((g1, g2), (z[1], z[2]), best, tau)
    best = _edge_far((g2, g0), (z[2], z[0]), best, tau)
    for k in range(4):  # the adjacent pairs (0, 2), (0, 3), (1, 2), (1, 3)
        best = _corner_far((g0, g1, g2), z, (k // 2, 2 + k % 2), best, tau)
    return best


def directional_origin(
    z: tuple[Scalar, Scalar],
    half: tuple[Scalar, Scalar],
    c: tuple[Scalar, Scalar, Scalar],
    a: tuple[Scalar, ...],
) -> tuple[Scalar, Scalar, Scalar, Scalar]:
    """The directional frame's origin, behind everything counted, and the shift along ``Z``.

    ``z = (z_lo, z_hi)``: the counted depth range; ``half = (h_x, h_y)``: the box's half-widths.

    ``origin = c + Z (z_lo - pad)``, ``pad = (z_hi - z_lo) + max(h_x, h_y)``: the
    depth range plus the box's size, so that ``near > 0`` with room to spare even
    for a flat blocker seen face-on (``z_hi = z_lo``).
    """
    (z_lo, z_hi), (half_x, half_y) = z, half
    pad = (z_hi - z_lo) + where(half_x >= half_y, half_x, half_y)
    shift = z_lo - pad
    return c[0] + shift * a[6], c[1] + shift * a[7], c[2] + shift * a[8], shift


def depth_range(
    z: tuple[Scalar, Scalar, Scalar, Scalar],
    given: tuple[Scalar, Scalar],
    has: tuple[bool, bool],
    slack: float,
) -> tuple[Scalar, Scalar, tuple[Truth, ...]]:
    """``near`` and ``far``: given, or ``z_lo (1 - slack)`` and ``z_hi (1 + slack)``; checks.

    ``z = (z_lo, z_hi, zb_min, zb_max)``: the counted range and the blocker's own.
    Checks (in order): given near finite, given far finite, given near ``> 0``,
    ``near < far``, given near not cutting into the blocker, given far neither.
    """
    z_lo, z_hi, zb_min, zb_max = z
    if has[0]:
        near = given[0]
        ok_nf, ok_pos, ok_nclip = isfinite(near), near > 0, near <= zb_min
    else:
        near = z_lo * (1.0 - slack)
        ok_nf, ok_pos, ok_nclip = True, True, True
    if has[1]:
        far = given[1]
        ok_ff, ok_fclip = isfinite(far), far >= zb_max
    else:
        far = z_hi * (1.0 + slack)
        ok_ff, ok_fclip = True, True
    return near, far, (ok_nf, ok_ff, ok_pos, near < far, ok_nclip, ok_fclip)


def ortho_rows(
    scale: tuple[Scalar, Scalar], centre: tuple[Scalar, Scalar], near: Scalar, far: Scalar
) -> tuple[Scalar, ...]:
    """The nonzero entries of an orthographic box's projection (light to OpenGL clip).

    ``P = [[sx, 0, 0, -sx cx], [0, sy, 0, -sy cy], [0, 0, a, b], [0, 0, 0, 1]]``,
    ``a = 2 / (f - n)``, ``b = -(f + n) / (f - n)``: depth ``-1`` at near, ``+1`` at far.
    ``scale = (sx, sy)``, ``centre = (cx, cy)``. Returns ``(sx, -sx cx, sy, -sy cy, a, b)``.
    """
    (sx, sy), (cx, cy) = scale, centre
    inv = 1.0 / (far - near)
    return sx, -sx * cx, sy, -sy * cy, 2.0 * inv, -(far + near) * inv


def ortho_clip_rows(w: tuple[Scalar, ...], p: tuple[Scalar, ...]) -> tuple[Scalar, ...]:
    """``P @ world_to_light`` for an orthographic ``P`` (:func:`ortho_rows`), 16 entries."""
    sx, sxc, sy, syc, a, b = p
    zero = fabs(w[0]) * 0.0  # +0.0 in the array's dtype
    return (
        sx * w[0], sx * w[1], sx * w[2], sx * w[3] + sxc,
        sy * w[4], sy * w[5], sy * w[6], sy * w[7] + syc,
        a * w[8], a * w[9], a * w[10], a * w[11] + b,
        zero, zero, zero, zero + 1.0,
    )  # fmt: skip


def _term(c: float, m: Scalar) -> Scalar:
    return m if c == 1.0 else c * m


def _crow(
    c: tuple[float, ...], i: int, m: tuple[Scalar, ...]
) -> tuple[Scalar, Scalar, Scalar, Scalar]:
    """Row ``i`` of ``C @ M`` for a constant ``C`` (16 floats): exact zeros and ones skipped.

    (So the identity costs nothing on whole arrays; the first term is always formed,
    which keeps the type the same for the compiled loop.)
    """
    c0, c1, c2, c3 = c[4 * i], c[4 * i + 1], c[4 * i + 2], c[4 * i + 3]
    r0, r1, r2, r3 = _term(c0, m[0]), _term(c0, m[1]), _term(c0, m[2]), _term(c0, m[3])
    started = c0 != 0.0
    for k, ck in ((1, c1), (2, c2), (3, c3)):
        if ck != 0.0:
            t0, t1 = _term(ck, m[4 * k]), _term(ck, m[4 * k + 1])
            t2, t3 = _term(ck, m[4 * k + 2]), _term(ck, m[4 * k + 3])
            if started:
                r0, r1, r2, r3 = r0 + t0, r1 + t1, r2 + t2, r3 + t3
            else:
                r0, r1, r2, r3 = t0, t1, t2, t3
            started = True
    return r0, r1, r2, r3


def const_times(c: tuple[float, ...], m: tuple[Scalar, ...]) -> tuple[Scalar, ...]:
    """``C @ M`` for a constant ``C`` (16 row-major floats) and 16 row-major entries ``M``."""
    if c == IDENTITY16:  # OpenGL's own clip space: nothing to multiply
        return m
    return (*_crow(c, 0, m), *_crow(c, 1, m), *_crow(c, 2, m), *_crow(c, 3, m))


#: The 4x4 identity as 16 row-major floats (:func:`const_times`'s shortcut).
IDENTITY16 = (1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0)


def _rows_loop(
    frame: tuple[tuple[Scalar, Scalar, Scalar], tuple[Scalar, ...]],
    box: tuple[Scalar, Scalar, Scalar, Scalar, Scalar, Scalar],
    margins: tuple[float, float],
    directional: bool,
    api: tuple[tuple[float, ...], tuple[float, ...]],
) -> tuple[tuple[Scalar, ...], tuple[Scalar, ...], tuple[Scalar, ...]]:
    """``world_to_light`` (12), ``blocker_to_clip`` without placement (16), ``world_to_texture``.

    ``frame = (origin, axes)``: the light frame's origin (3) and axes ``X, Y, Z`` (9).
    ``box = (h_x, h_y, c_x, c_y, near, far)``, already safe (``h > 0``, ``far > near``).
    ``api = (C, T C)``: OpenGL clip to the API's clip, and to its texture coordinates.
    The loop form of ``fit_rows`` (:data:`FORMS`): the constant products entry by entry.
    """
    hx, hy, cx, cy, near, far = box
    w = light_rows(frame[0], frame[1])
    scale = (margins[0] / hx, margins[1] / hy)
    if directional:
        gl = ortho_clip_rows(w, ortho_rows(scale, (cx, cy), near, far))
    else:
        gl = clip_rows(w, projection_rows(scale, (cx, cy), near, far))
    return w, const_times(api[0], gl), const_times(api[1], gl)


def _rows_array(
    frame: tuple[tuple[Scalar, Scalar, Scalar], tuple[Scalar, ...]],
    box: tuple[Scalar, Scalar, Scalar, Scalar, Scalar, Scalar],
    margins: tuple[float, float],
    directional: bool,
    api: tuple[tuple[float, ...], tuple[float, ...]],
) -> tuple[tuple[Scalar, ...], tuple[Scalar, ...], tuple[Scalar, ...]]:
    """The array form of ``fit_rows`` (:func:`_rows_loop`): the same rows, the products as
    matrix products on ``(*b, 4, 4)``: ``G = P @ W`` (``P`` the orthographic box's or the
    blocker projection's, :func:`ortho_rows`, :func:`._formulas.projection_rows`), then
    ``C @ G`` and ``T C @ G``. Under JAX a program a fraction of the size of the entries
    written out, which XLA compiles in a fraction of the time."""
    xp = array_api
    hx, hy, cx, cy, near, far = box
    w = light_rows(frame[0], frame[1])
    scale = (margins[0] / hx, margins[1] / hy)
    if directional:
        sx, sxc, sy, syc, a, b = ortho_rows(scale, (cx, cy), near, far)
    else:
        sx, sxc, sy, syc, a, b = projection_rows(scale, (cx, cy), near, far)
    z = xp.zeros_like(sx)
    one = z + 1.0
    if directional:
        P = (sx, z, z, sxc, z, sy, z, syc, z, z, a, b, z, z, z, one)
    else:
        P = (sx, z, sxc, z, z, sy, syc, z, z, z, a, b, z, z, one, z)
    G = matmul(xp, _matrix(P), _matrix((*w, z, z, z, one)))
    gl = MatrixEntries(G)
    return w, _const_matmul(api[0], G, gl), _const_matmul(api[1], G, gl)


def _matrix(entries: tuple[Scalar, ...]) -> Scalar:
    """16 row-major entries ``(*b)`` as one ``(*b, 4, 4)`` array."""
    if isinstance(entries, MatrixEntries):
        return entries.matrix
    xp = array_api
    m = xp.stack(xp.broadcast_arrays(*entries), axis=-1)
    return xp.reshape(m, (*m.shape[:-1], 4, 4))


def _const_matmul(c: tuple[float, ...], G: Scalar, gl: tuple[Scalar, ...]) -> tuple[Scalar, ...]:
    """``C @ G`` (``G``: ``gl``'s 16 entries as ``(*b, 4, 4)``) as 16 entries (``gl`` itself
    for the identity)."""
    if c == IDENTITY16:
        return gl
    xp = array_api
    return MatrixEntries(matmul(xp, xp.asarray(np.reshape(c, (4, 4)), dtype=G.dtype), G))


def safe_box(
    box: tuple[Scalar, Scalar, Scalar, Scalar, Scalar, Scalar],
) -> tuple[Scalar, Scalar, Scalar, Scalar, Scalar, Scalar]:
    """The box ``(h_x, h_y, c_x, c_y, near, far)`` with safe divisors (``h > 0``, ``far > near``).

    Invalid entries are poisoned.
    """
    half_x, half_y, cx, cy, near, far = box
    return (
        where(half_x > 0, half_x, 1.0),
        where(half_y > 0, half_y, 1.0),
        cx,
        cy,
        where(near > 0, near, 1.0),
        where(far > near, far, where(near > 0, near, 1.0) + 1.0),
    )


FUNCTIONS = (
    "place",
    "to_light",
    "bounds_about",
    "_largest",
    "fit_axes",
    "placement_ok",
    "placement_affine",
    "near_clear",
    "fov_ok",
    "point_sides",
    "spot_sides",
    "spot_angle_ok",
    "box_sides",
    "stable_sides",
    "_dot",
    "sphere_through",
    "side_values",
    "receiver_counted",
    "_inside_but",
    "_corner_in",
    "_lerp4",
    "_edge_far",
    "_corner_far",
    "triangle_far",
    "directional_origin",
    "depth_range",
    "ortho_rows",
    "ortho_clip_rows",
    "_term",
    "_crow",
    "const_times",
    "_rows_loop",
    "_rows_array",
    "_matrix",
    "_const_matmul",
    "safe_box",
)
