"""The fits' passes over the vertices, as loops: the per-entry backend of :mod:`._fit_entry`.

Plain Python over scalars in the subset that Numba compiles (tuples, ``len``,
``a[i]`` indexing, ``math``): :func:`shadowmath._backends._kernels.loops` compiles them, or they run
on Python floats for one small fit. Each pass reads the vertices once, placing
each through ``b`` on the fly (``vs = (V, b, has_b)``: one entry's vertices as one
flat row ``x0, y0, z0, x1, ...`` of ``3 N`` numbers, its placement's 16 entries, and
whether it has one). The same passes on whole arrays are reductions over the last
axis (:class:`._passes.ArrayPasses`); both call the per-vertex
formulas of :mod:`._fit_formulas`. Sums are accumulated in float64 whatever the
input dtype.

The loops are written so that Numba compiles them to vector instructions: the
vertices as a flat row (a constant stride of 3 numbers, which the compiler loads as
interleaved vectors; a 2D array's row stride is known only at run time), no branch
per vertex, and the running bounds and sums through the primitives ``lower``,
``upper`` and ``accumulate``: Python's ``min``, ``max`` and ``+`` here, and in the
compiled loops instructions that may be reordered (a sum in any order, IEEE
``minimum``/``maximum`` that propagate NaN), which the compiler keeps in vector
lanes (:mod:`shadowmath._backends._kernels`). So each pass runs near the speed of
one read of the array.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Callable
from typing import Any

from shadowmath._boundary._shapes import Array, ArrayLike, Float, Options, Real, Row, Scalar, Truth
from shadowmath._boundary._status import OVERFLOW, PROJECTIVE, VERTICES

from ._fit_formulas import place, receiver_counted, sphere_through, to_light, triangle_far
from ._formulas import fabs, sqrt  # primitives, rebound by specialize()

# The reductions' steps: primitives, rebound by specialize() (Python's by default).
lower: Callable[[Any, Any], Any] = min
upper: Callable[[Any, Any], Any] = max
accumulate: Callable[[Any, Any], Any] = operator.add


def _vertex(V: Row, k: int, b: tuple[float, ...], has_b: bool) -> tuple[float, float, float, float]:
    """Vertex ``k`` of a flat row in world coordinates and its ``w`` (1 without a placement)."""
    vx, vy, vz = float(V[3 * k]), float(V[3 * k + 1]), float(V[3 * k + 2])
    if has_b:
        return place(b, vx, vy, vz)
    return vx, vy, vz, 1.0


def count(V: Row) -> int:
    """The number of vertices in a flat row of ``3 N`` numbers."""
    return len(V) // 3


def spread(
    vs: tuple[Row, tuple[float, ...], bool], o: tuple[float, float, float]
) -> tuple[
    tuple[float, float, float], tuple[float, float, float], tuple[float, float, float], int, int
]:
    """Pass 1 about the point ``o``: sums of ``p - o``, bounds of the world points ``p``
    (:func:`._fit_formulas.bounds_about` turns them into the bounds of ``p - o``, the
    reach and the coordinates' size), status (non-finite, projective, overflow), count."""
    V, b, has_b = vs
    n = count(V)
    sx = sy = sz = raw = 0.0
    lo_x = lo_y = lo_z = lo_w = math.inf
    hi_x = hi_y = hi_z = -math.inf
    for k in range(n):
        raw = accumulate(raw, float(V[3 * k]) + float(V[3 * k + 1]) + float(V[3 * k + 2]))
        px, py, pz, w = _vertex(V, k, b, has_b)
        lo_w = lower(lo_w, w)
        sx, sy, sz = accumulate(sx, px - o[0]), accumulate(sy, py - o[1]), accumulate(sz, pz - o[2])
        lo_x, lo_y, lo_z = lower(lo_x, px), lower(lo_y, py), lower(lo_z, pz)
        hi_x, hi_y, hi_z = upper(hi_x, px), upper(hi_y, py), upper(hi_z, pz)
    st = 0 if lo_w > 0 else PROJECTIVE
    if not math.isfinite(raw):
        st |= VERTICES
    elif not (math.isfinite(sx) and math.isfinite(sy) and math.isfinite(sz)):
        st |= OVERFLOW
    return (sx, sy, sz), (lo_x, lo_y, lo_z), (hi_x, hi_y, hi_z), st, n


def light_pass(
    vs: tuple[Row, tuple[float, ...], bool],
    o: tuple[float, float, float],
    a: tuple[float, ...],
    ratios: bool,
) -> tuple[float, float, float, float, float, float]:
    """Pass 2: bounds ``(hi_x, lo_x, hi_y, lo_y, hi_z, lo_z)`` of ``x, y`` (or ``x / z,
    y / z``) and ``z`` in the frame ``a`` about ``o``."""
    V, b, has_b = vs
    hx = hy = hz = -math.inf
    lx = ly = lz = math.inf
    for k in range(count(V)):
        px, py, pz, _ = _vertex(V, k, b, has_b)
        x, y, z = to_light(px - o[0], py - o[1], pz - o[2], a)
        if ratios:
            inv_z = 1.0 / z if z > 0 else 1.0
            x, y = x * inv_z, y * inv_z
        hx, lx, hy, ly = upper(hx, x), lower(lx, x), upper(hy, y), lower(ly, y)
        hz, lz = upper(hz, z), lower(lz, z)
    return hx, lx, hy, ly, hz, lz


def receiver_far(
    R: Real[ArrayLike, "M k"],
    o: tuple[float, float, float],
    a: tuple[float, ...],
    sides: tuple[float, float, float, float],
    opts: Options,
) -> tuple[float, bool, float]:
    """The farthest receiver depth inside the sides (``-inf`` if none), their finite
    flag, and the link of :func:`._fit_entry.receivers_far` (0: the loop's fit raises).

    Receiver rows are points (3) or, ``opts.triangles``, triangles (9 numbers: three
    corners, clipped exactly by the side planes); ``sides`` as in :func:`receiver_counted`.
    """
    directional, triangles, eps = opts.directional, opts.triangles, opts.eps
    z_hi = -math.inf
    raw = 0.0
    for k in range(len(R)):
        r = R[k]
        if triangles:
            # The finite flag sums the given numbers, not their light-space images:
            # a non-finite up= makes those NaN, and must be reported as up's.
            for j in range(9):
                raw += float(r[j])
            p0 = to_light(float(r[0]) - o[0], float(r[1]) - o[1], float(r[2]) - o[2], a)
            p1 = to_light(float(r[3]) - o[0], float(r[4]) - o[1], float(r[5]) - o[2], a)
            p2 = to_light(float(r[6]) - o[0], float(r[7]) - o[1], float(r[8]) - o[2], a)
            p9 = (p0[0], p0[1], p0[2], p1[0], p1[1], p1[2], p2[0], p2[1], p2[2])
            z_hi = max(z_hi, triangle_far(p9, sides, directional, eps))
        else:
            rx, ry, rz = float(r[0]), float(r[1]), float(r[2])
            raw += rx + ry + rz
            x, y, z = to_light(rx - o[0], ry - o[1], rz - o[2], a)
            if receiver_counted(x, y, z, sides, directional):
                z_hi = max(z_hi, z)
    return z_hi, math.isfinite(raw), 0.0


#: Welzl's algorithm visits the vertices in the order ``k * _STRIDE mod n`` (a prime
#: stride: every vertex once), which breaks up a mesh's ordered rows; its expected
#: time is linear for a random order. The result does not depend on the order.
_STRIDE = 1000003


def _nth(
    V: Row, b: tuple[float, ...], has_b: bool, k: int, stride: int
) -> tuple[int, tuple[float, float, float]]:
    """The ``k``-th vertex in Welzl's order: its index and world coordinates."""
    i = (k * stride) % count(V)
    p = _vertex(V, i, b, has_b)
    return i, (p[0], p[1], p[2])


def _ball(
    V: Row, b: tuple[float, ...], has_b: bool, sup: tuple[int, int, int, int], k: int
) -> tuple[float, float, float, float]:
    """:func:`sphere_through` the support vertices ``sup`` (indices), ``k`` of them."""
    p0, p1 = _vertex(V, sup[0], b, has_b), _vertex(V, sup[1], b, has_b)
    p2, p3 = _vertex(V, sup[2], b, has_b), _vertex(V, sup[3], b, has_b)
    q = (p0[0], p0[1], p0[2], p1[0], p1[1], p1[2], p2[0], p2[1], p2[2], p3[0], p3[1], p3[2])
    return sphere_through(q, k)


def _outside(
    p: tuple[Scalar, ...] | Float[Array, " 3 ..."],
    ball: tuple[Scalar, ...] | Float[Array, " 4 ..."],
) -> Truth:
    """``p`` outside the ball by more than the rounding of its coordinates (float64).

    (A point within rounding of the sphere, such as a repeated vertex far from the
    origin, must not become a support point: two equal support points make the
    sphere through them ill-posed.) On scalars or, specialized to arrays, elementwise
    (:mod:`._ball_support`).
    """
    dx, dy, dz = p[0] - ball[0], p[1] - ball[1], p[2] - ball[2]
    tau = 64.0 * 2.220446049250313e-16 * (fabs(p[0]) + fabs(p[1]) + fabs(p[2]))
    return sqrt(dx * dx + dy * dy + dz * dz) > sqrt(ball[3]) * (1.0 + 1e-14) + tau


def enclosing_ball(vs: tuple[Row, tuple[float, ...], bool]) -> tuple[float, float, float, float]:
    """The minimal enclosing sphere of the vertices: centre (3) and squared radius."""
    V, b, has_b = vs
    sup, k = enclosing_support(V, b, has_b)
    return _ball(V, b, has_b, sup, k)


def enclosing_support(
    V: Row, b: tuple[float, ...], has_b: bool
) -> tuple[tuple[int, int, int, int], int]:
    """The minimal enclosing sphere's support: vertex indices (4, repeated) and their count.

    Welzl's algorithm (1991) in its iterative form: a vertex outside the current
    sphere lies on the boundary of the sphere of the vertices before it, so each
    level fixes one more boundary point (at most 4 in 3D) and restarts over the
    vertices before it. The sphere is unique, so it depends on the point set only:
    not on the order, the tessellation or the orientation.
    """
    n = count(V)
    stride = _STRIDE if n % _STRIDE != 0 else 1
    sup, k = (0, 0, 0, 0), 1
    ball = _ball(V, b, has_b, sup, k)
    for t in range(1, n):
        i, pi = _nth(V, b, has_b, t, stride)
        if not _outside(pi, ball):
            continue
        sup, k = (i, i, i, i), 1
        ball = (pi[0], pi[1], pi[2], 0.0)
        for u in range(t):
            j, pj = _nth(V, b, has_b, u, stride)
            if not _outside(pj, ball):
                continue
            sup, k = (i, j, j, j), 2
            ball = _ball(V, b, has_b, sup, k)
            for v in range(u):
                m, pm = _nth(V, b, has_b, v, stride)
                if not _outside(pm, ball):
                    continue
                sup, k = (i, j, m, m), 3
                ball = _ball(V, b, has_b, sup, k)
                for w in range(v):
                    r, pr = _nth(V, b, has_b, w, stride)
                    if _outside(pr, ball):
                        sup, k = (i, j, m, r), 4
                        ball = _ball(V, b, has_b, sup, k)
    return sup, k


FUNCTIONS = (
    "_vertex",
    "count",
    "spread",
    "light_pass",
    "receiver_far",
    "_nth",
    "_ball",
    "_outside",
    "enclosing_ball",
    "enclosing_support",
)
