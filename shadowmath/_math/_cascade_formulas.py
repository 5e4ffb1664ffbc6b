r"""Cascaded shadow maps: the per-point and per-cascade formulas, one source for every backend.

A cascade is a directional light's orthographic map fitted to one slice of a
camera's view frustum, between two view depths ``a < b``. The steps of
:mod:`._cascade_steps` (run once per camera and cascade on floats, or once on whole arrays)
are:

1. the slice's eight corners, on the camera frustum's four edge lines at the
   depths ``a`` and ``b`` (:func:`edge_point`), then in world space;
2. the six half-spaces of the slice (:func:`slice_values`: the camera's four
   side planes ``w +- x >= 0``, ``w +- y >= 0`` of its clip coordinates, and
   ``a <= depth <= b``) and of the scene's box (:func:`box_values`), each an
   affine function of the point, so along a segment they interpolate linearly;
3. the vertices of the slice intersected with the scene's box: every such vertex
   is an end of an edge of one solid clipped to the other (Liang–Barsky,
   :func:`clip_segment`), so clipping the slice's 12 edges to the box and the
   box's 12 edges to the slice finds all of them;
4. the map's box in light coordinates (:func:`cascade_box`): the lateral bounds
   of those vertices, the far end at their deepest, the near end at the scene's
   box corner nearest the light (every caster that can shadow the slice lies
   between); or, stable, the slice's bounding sphere snapped to whole texels.

Corners are indexed ``k = i + 2 j + 4 l`` (``i``: ``x`` side, ``j``: ``y`` side,
``l``: near/far or low/high ``z``); :data:`EDGES` lists the 12 edges.

Trusted inputs only: nothing here raises.
"""

from __future__ import annotations

import math
from typing import Any

# Backend primitives and shared formulas, rebound by specialize().
from shadowmath._boundary._shapes import Row, Scalar, Truth

from ._fit_formulas import rint, stable_sides  # noqa: F401  (looked up by the specialized copies)
from ._formulas import fabs, log2, sqrt, where  # noqa: F401

#: Primitives of the mode, bound by specialize(): a float buffer of ``n`` entries
#: (``alloc(n)``), entry ``k`` of a per-entry row (``take_last(G, k)``) and, in the array
#: mode, the array namespace (``array_api``).
alloc: Any = None
take_last: Any = None
array_api: Any = None

#: The 12 edges of a box or slice as pairs of corner indices ``i + 2 j + 4 l``.
EDGES = (
    (0, 1), (2, 3), (4, 5), (6, 7),
    (0, 2), (1, 3), (4, 6), (5, 7),
    (0, 4), (1, 5), (2, 6), (3, 7),
)  # fmt: skip


def split_depth(near: Scalar, far: Scalar, lam: Scalar, frac: Scalar) -> Scalar:
    r"""The practical split at the fraction ``frac = i / N``: ``lam`` log plus ``1 - lam`` uniform.

    .. math:: s = \lambda\, n (f / n)^{i/N} + (1 - \lambda) (n + (f - n)\, i / N)

    The logarithmic part uses ``n = 1`` where ``n <= 0`` (only valid with ``lam = 0``,
    which the boundary checks), so a uniform range from the camera has no NaN.
    """
    safe = where(near > 0, near, 1.0 + 0.0 * near)
    return lam * (safe * (far / safe) ** frac) + (1.0 - lam) * (near + (far - near) * frac)


#: The depth ladder's steps per octave: a laddered depth is ``2^(k / LADDER_STEPS)``.
LADDER_STEPS = 4.0
#: How many ladder steps a laddered end may lag behind its target before it follows.
HYSTERESIS_STEPS = 1.0


def ladder_up(x: Scalar) -> Scalar:
    r"""The smallest ladder value ``2^(k/4) >= x`` (``k`` whole); ``x <= 0`` unchanged.

    .. math:: k = \lceil 4 \log_2 x \rceil

    written ``rint(4 log2 x + 1/2)`` (at least ``4 log2 x``), then one step up where
    rounding left the value below ``x``.
    """
    safe = where(x > 0, x, 1.0 + 0.0 * x)
    q = 2.0 ** (rint(LADDER_STEPS * log2(safe) + 0.5) / LADDER_STEPS)
    q = where(q < safe, q * 2.0 ** (1.0 / LADDER_STEPS), q)
    return where(x > 0, q, x)


def ladder_hold(t: Scalar, p: Scalar) -> Scalar:
    r"""A value ``>= t`` on the ladder, with hysteresis: ``p`` (the last one) or ``q``.

    With ``q`` = :func:`ladder_up` of ``t`` and one step ``s = 2^{1/4}``:

    .. math:: \begin{cases} p & t \le p \le q\, s^{M} \\ q & \text{otherwise} \end{cases}

    (``M = HYSTERESIS_STEPS``, compared at ``M + 1/2`` steps: ladder values are ``s``
    apart, so rounding cannot flip the choice). It grows at once (``t > p``) and
    shrinks only once ``q`` lies more than ``M`` steps below ``p``. ``p`` NaN: ``q``.
    """
    margin = 2.0 ** ((HYSTERESIS_STEPS + 0.5) / LADDER_STEPS)
    q = ladder_up(t)
    keep = (p >= t) & (p <= q * margin)
    return where(keep, p, where(q >= t, q, t))


def depth_hysteresis(
    t_lo: Scalar, t_hi: Scalar, p_lo: Scalar, p_hi: Scalar
) -> tuple[Scalar, Scalar]:
    r"""The depth range in use: the target ``[t_lo, t_hi]`` widened to the ladder with
    hysteresis, from the last one ``[p_lo, p_hi]`` (NaN: none).

    The far end is :func:`ladder_hold`; the near end is its mirror,
    ``1 / ladder_hold(1 / t_lo, 1 / p_lo)`` (a ladder value at most ``t_lo``, which
    grows the range at once and shrinks it only past the margin); ``t_lo <= 0`` (an
    orthographic camera's) is kept as it is. The result holds the target.
    """
    pos = t_lo > 0
    inv_t = 1.0 / where(pos, t_lo, 1.0 + 0.0 * t_lo)
    inv_p = 1.0 / where(p_lo > 0, p_lo, 0.0 * t_lo + math.inf)
    lo = 1.0 / ladder_hold(inv_t, inv_p)
    lo = where(pos, where(lo <= t_lo, lo, t_lo), t_lo)
    return lo, ladder_hold(t_hi, p_hi)


def edge_point(
    n: tuple[Scalar, ...], f: tuple[Scalar, ...], s: Scalar, d: Scalar
) -> tuple[Scalar, Scalar, Scalar]:
    r"""The point at view depth ``d`` on the camera frustum's edge from ``n`` toward ``f``.

    ``n = (x, y, z)``: the edge's near corner in view space; ``f = (x, y, z, w)``:
    its far corner, homogeneous (``w = 0`` for a projection with an infinite far
    plane). On the line ``H(u) = (1 - u) (n, 1) + u f``, the view depth
    ``s z / w = d`` (``s = +-1``, the sign that makes depth grow away from the
    camera) gives

    .. math:: u = \frac{d - s n_z}{s (f_z - n_z) + d (1 - f_w)}

    and the point ``H_{xyz}(u) / H_w(u)``: perspective and orthographic cameras,
    finite or infinite far planes, one formula.
    """
    u = (d - s * n[2]) / (s * (f[2] - n[2]) + d * (1.0 - f[3]))
    w = 1.0 - u + u * f[3]
    return (
        ((1.0 - u) * n[0] + u * f[0]) / w,
        ((1.0 - u) * n[1] + u * f[1]) / w,
        ((1.0 - u) * n[2] + u * f[2]) / w,
    )


def affine(m: tuple[Scalar, ...], x: Scalar, y: Scalar, z: Scalar) -> tuple[Scalar, Scalar, Scalar]:
    """``m[:3] @ (x, y, z, 1)`` for a 4x4 affine matrix given as 12 row-major entries."""
    return (
        m[0] * x + m[1] * y + m[2] * z + m[3],
        m[4] * x + m[5] * y + m[6] * z + m[7],
        m[8] * x + m[9] * y + m[10] * z + m[11],
    )


def camera_values(
    pv: tuple[Scalar, ...], x: Scalar, y: Scalar, z: Scalar
) -> tuple[Scalar, Scalar, Scalar, Scalar, Scalar]:
    """The camera's four side values ``w - x, w + x, w - y, w + y`` (clip) and ``w``'s row ``z``.

    ``pv``: the 16 row-major entries of ``projection @ view``; the fifth value is
    the view-space ``z`` row's value, filled in by the caller (see :func:`slice_values`).
    """
    cx = pv[0] * x + pv[1] * y + pv[2] * z + pv[3]
    cy = pv[4] * x + pv[5] * y + pv[6] * z + pv[7]
    cw = pv[12] * x + pv[13] * y + pv[14] * z + pv[15]
    return cw - cx, cw + cx, cw - cy, cw + cy, cw


def slice_values(
    sides: tuple[Scalar, ...], depth: Scalar, a: Scalar, b: Scalar
) -> tuple[Scalar, ...]:
    """The slice's six half-space values at a point, all ``>= 0`` inside.

    ``sides``: :func:`camera_values` (its first four); ``depth``: the point's view
    depth; ``[a, b]``: the slice. The camera's side planes in clip space hold
    for every graphics API (each clips ``-w <= x, y <= w``), and together they
    imply ``w >= 0``: only the half of the pyramid in front of the eye.
    """
    return sides[0], sides[1], sides[2], sides[3], depth - a, b - depth


def box_values(
    x: Scalar, y: Scalar, z: Scalar, lo: tuple[Scalar, ...], hi: tuple[Scalar, ...]
) -> tuple[Scalar, ...]:
    """The scene box's six half-space values at a point, all ``>= 0`` inside."""
    return x - lo[0], hi[0] - x, y - lo[1], hi[1] - y, z - lo[2], hi[2] - z


def clip_segment(g0: tuple[Scalar, ...], g1: tuple[Scalar, ...]) -> tuple[Scalar, Scalar, Truth]:
    r"""Liang–Barsky: the part ``[t_0, t_1]`` of a segment inside six half-spaces, and whether any.

    ``g0``, ``g1``: the six affine half-space values at the segment's ends, so
    ``g(t) = g_0 + t (g_1 - g_0)``; each plane is one :func:`clip_plane` step.
    """
    t0 = g0[0] * 0.0
    t1 = t0 + 1.0
    ok = t0 == t0
    for j in range(6):
        t0, t1, ok = clip_plane(t0, t1, ok, g0[j], g1[j])
    return t0, t1, ok & (t0 <= t1)


def clip_plane(
    t0: Scalar, t1: Scalar, ok: Truth, a: Scalar, b: Scalar
) -> tuple[Scalar, Scalar, Truth]:
    """One half-space of :func:`clip_segment`, with values ``a``, ``b`` at the ends.

    A plane crossed from outside to inside raises ``t_0`` to ``a / (a - b)``, one
    crossed the other way lowers ``t_1`` to it, and a segment outside it at both ends
    is empty (``ok`` false). A plane with both ends inside changes nothing, so the
    compiled loop calls this only for the planes an end is outside of.
    """
    d = a - b
    t = a / where(d != 0, d, 1.0)
    entering = (a < 0) & (b >= 0)
    leaving = (a >= 0) & (b < 0)
    t0 = where(entering & (t > t0), t, t0)
    t1 = where(leaving & (t < t1), t, t1)
    return t0, t1, ok & ((a >= 0) | (b >= 0))


def slice_sphere(
    corners: tuple[Scalar, ...],
) -> tuple[Scalar, Scalar, Scalar, Scalar]:
    r"""A sphere around a slice's eight corners (24 numbers, view space): centre and ``r^2``.

    With ``m_n``, ``m_f`` the centres of the near and far rectangles and ``r_n``,
    ``r_f`` their half-diagonals, the centre is ``m_n + t (m_f - m_n)`` with

    .. math:: t = \mathrm{clamp}\left(\tfrac12 + \frac{r_f^2 - r_n^2}{2 |m_f - m_n|^2}, 0, 1\right)

    (equal distances to both rectangles' corners, the minimal enclosing sphere of
    a slice whose rectangles are centred on one axis, as for every symmetric
    projection) and ``r`` the largest distance to a corner. Computed in view
    space, it depends on the projection and the two depths only: the camera's
    pose moves the sphere without changing its size.
    """
    mn = [0.25 * (corners[c] + corners[c + 3] + corners[c + 6] + corners[c + 9]) for c in range(3)]
    mf = [
        0.25 * (corners[c + 12] + corners[c + 15] + corners[c + 18] + corners[c + 21])
        for c in range(3)
    ]
    dx, dy, dz = mf[0] - mn[0], mf[1] - mn[1], mf[2] - mn[2]
    length2 = dx * dx + dy * dy + dz * dz
    rn2 = _far2(corners, 0, mn)
    rf2 = _far2(corners, 4, mf)
    t = 0.5 + (rf2 - rn2) / (2.0 * where(length2 > 0, length2, 1.0))
    t = where(t < 0, 0.0 * t, where(t > 1, 0.0 * t + 1.0, t))
    c = (mn[0] + t * dx, mn[1] + t * dy, mn[2] + t * dz)
    return c[0], c[1], c[2], where(_far2(corners, 0, c) >= _far2(corners, 4, c),
                                   _far2(corners, 0, c), _far2(corners, 4, c))  # fmt: skip


def _mean4(corners: tuple[Scalar, ...], first: int) -> tuple[Scalar, Scalar, Scalar]:
    """The mean of the four corners from ``first``."""
    k = 3 * first
    return (
        0.25 * (corners[k] + corners[k + 3] + corners[k + 6] + corners[k + 9]),
        0.25 * (corners[k + 1] + corners[k + 4] + corners[k + 7] + corners[k + 10]),
        0.25 * (corners[k + 2] + corners[k + 5] + corners[k + 8] + corners[k + 11]),
    )


def _far2(corners: tuple[Scalar, ...], first: int, c: Row) -> Scalar:
    """The largest squared distance from ``c`` to the four corners from ``first``."""
    best = c[0] * 0.0
    for k in range(first, first + 4):
        dx = corners[3 * k] - c[0]
        dy = corners[3 * k + 1] - c[1]
        dz = corners[3 * k + 2] - c[2]
        r2 = dx * dx + dy * dy + dz * dz
        best = where(r2 > best, r2, best)
    return best


def cascade_box(
    bounds: tuple[Scalar, Scalar, Scalar, Scalar, Scalar, Scalar],
) -> tuple[Scalar, Scalar, Scalar, Scalar, Scalar, Scalar]:
    """The map's box ``(h_x, h_y, c_x, c_y, near, far)`` from light-space bounds, origin-free.

    ``bounds = (lo_x, hi_x, lo_y, hi_y, z_lo, z_hi)`` in light coordinates about
    the world origin. The frame's origin is then moved back along ``Z`` by
    ``shift = z_lo - pad`` with ``pad = (z_hi - z_lo) + max(h_x, h_y)``, so that
    ``near > 0`` with room to spare; moving along ``Z`` keeps ``x`` and ``y``, so a
    texel grid anchored at the world origin stays anchored. ``near`` and ``far``
    are relative to that origin.
    """
    lo_x, hi_x, lo_y, hi_y, z_lo, z_hi = bounds
    hx, hy = 0.5 * (hi_x - lo_x), 0.5 * (hi_y - lo_y)
    pad = (z_hi - z_lo) + where(hx >= hy, hx, hy)
    return hx, hy, 0.5 * (hi_x + lo_x), 0.5 * (hi_y + lo_y), pad, pad + (z_hi - z_lo)


FUNCTIONS = (
    "split_depth",
    "ladder_up",
    "ladder_hold",
    "depth_hysteresis",
    "edge_point",
    "affine",
    "camera_values",
    "slice_values",
    "box_values",
    "clip_segment",
    "clip_plane",
    "slice_sphere",
    "_mean4",
    "_far2",
    "cascade_box",
)
