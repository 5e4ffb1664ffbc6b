r"""A spot light's caster triangles clipped to its square pyramid in one loop (Numba).

The loop form of :func:`._spot_casters.clip_triangles` for one light (no batch axes):
plain Python over scalars in the subset that Numba compiles, specialized and compiled
with the other loops (:func:`shadowmath._backends._kernels.loops`; the disk cache is
keyed on every source of the package). It reads each triangle once and, from the
plane values ``g_ik = pi_k . c_i`` of its corners ``c_i`` on the four side planes
``pi_k`` (:func:`._spot_casters.pyramid_planes`), with the triangle's tolerance
``tau = 64 eps sum_ik |g_ik|`` (finite), decides:

* **inside** (every ``g_ik >= -tau``): the corners are valid candidates and every
  other valid candidate lies on the triangle (a convex combination), so the three
  corners are written and nothing is clipped;
* **outside a side** (for some ``k`` every ``g_ik < -2 tau``) or **behind the light**
  (every corner's ``sum_k g_ik < -8 tau``; the four sides sum to ``4 t z``): every
  candidate is a convex combination of the corners, so one of its values lies below
  ``-2 tau`` (up to rounding, far below ``tau``): none is valid, nothing is written;
* **straddling** (the rest, and every triangle with a non-finite ``tau``): its 19
  candidates, exactly as :func:`._spot_casters.clip_triangles` computes them
  (the same weights, validity and ``tau``), the valid and the non-finite ones written.

So the points written are the array form's kept candidates (as a set, the inside
triangles' candidates on their edges aside, which change no extreme), compacted: a
triangle is *kept* when it writes a point, as the array form counts it. Sums are
computed in float64 whatever the input dtype.
"""

from __future__ import annotations

import math

from shadowmath._boundary._shapes import Array, Float


def _spot_sides(P: Float[Array, "_ 4"]) -> tuple[float, ...]:
    """The four side planes ``(n_k, d_k)`` of ``P`` (rows of 4) as 16 floats."""
    return (
        float(P[0][0]), float(P[0][1]), float(P[0][2]), float(P[0][3]),
        float(P[1][0]), float(P[1][1]), float(P[1][2]), float(P[1][3]),
        float(P[2][0]), float(P[2][1]), float(P[2][2]), float(P[2][3]),
        float(P[3][0]), float(P[3][1]), float(P[3][2]), float(P[3][3]),
    )  # fmt: skip


def _spot_values(
    x: float, y: float, z: float, S: tuple[float, ...]
) -> tuple[float, float, float, float]:
    """The four side planes' values ``n_k . p + d_k`` at ``p = (x, y, z)``."""
    return (
        x * S[0] + y * S[1] + z * S[2] + S[3],
        x * S[4] + y * S[5] + z * S[6] + S[7],
        x * S[8] + y * S[9] + z * S[10] + S[11],
        x * S[12] + y * S[13] + z * S[14] + S[15],
    )


def _spot_put(out: Float[Array, "_ 3"], at: int, x: float, y: float, z: float) -> int:
    """Point ``(x, y, z)`` stored in row ``at`` of ``out``; the next row."""
    out[at, 0], out[at, 1], out[at, 2] = x, y, z
    return at + 1


def _spot_candidate(
    w: tuple[float, float, float],
    ok: bool,
    tri: tuple[tuple[float, ...], tuple[tuple[float, ...], ...], float],
    out: Float[Array, "_ 3"],
    at: int,
) -> int:
    """One candidate of barycentric weights ``w`` (3), which exists when ``ok``, of the
    triangle ``tri = (c, g, tau)`` (corners, values, tolerance): stored when valid (its
    four values ``sum_i w_i g_ik >= -tau``) or not finite; the next row."""
    c, g, tau = tri
    w0, w1, w2 = w[0], w[1], w[2]
    g0, g1, g2 = g[0], g[1], g[2]
    valid = ok
    for k in range(4):
        valid = valid and w0 * g0[k] + w1 * g1[k] + w2 * g2[k] >= -tau
    x = w0 * c[0] + w1 * c[3] + w2 * c[6]
    y = w0 * c[1] + w1 * c[4] + w2 * c[7]
    z = w0 * c[2] + w1 * c[5] + w2 * c[8]
    if valid or not (math.isfinite(x) and math.isfinite(y) and math.isfinite(z)):
        return _spot_put(out, at, x, y, z)
    return at


def _spot_edge(gi: float, gj: float) -> tuple[float, bool]:
    """Where an edge crosses a plane (values ``gi``, ``gj`` at its ends): ``s`` and whether
    it does (``0 <= s <= 1``)."""
    den = gi - gj
    s = gi / (den if den != 0 else 1.0)
    return s, den != 0 and s >= 0 and s <= 1


def _spot_lateral(
    g: tuple[tuple[float, ...], ...], k: int, m: int
) -> tuple[float, float, float, bool]:
    """Where the pyramid's edge on planes ``k``, ``m`` pierces the triangle: barycentric
    ``n_i / det`` (Cramer), and whether it does (every ``n_i`` of ``det``'s sign)."""
    a0, a1, a2 = g[0][k], g[1][k], g[2][k]
    b0, b1, b2 = g[0][m], g[1][m], g[2][m]
    n0 = a1 * b2 - a2 * b1
    n1 = a2 * b0 - a0 * b2
    n2 = a0 * b1 - a1 * b0
    det = n0 + n1 + n2
    inv = 1.0 / (det if det != 0 else 1.0)
    ok = n0 * det >= 0 and n1 * det >= 0 and n2 * det >= 0 and det != 0
    return n0 * inv, n1 * inv, n2 * inv, ok


def _spot_clip(
    c: tuple[float, ...],
    g: tuple[tuple[float, ...], ...],
    tau: float,
    out: Float[Array, "_ 3"],
    at: int,
) -> int:
    """A straddling triangle's 19 candidates (corners ``c``, 9 floats; values ``g``, three
    4-tuples), the kept ones stored from row ``at``; the next row."""
    tri = (c, g, tau)
    at = _spot_candidate((1.0, 0.0, 0.0), True, tri, out, at)
    at = _spot_candidate((0.0, 1.0, 0.0), True, tri, out, at)
    at = _spot_candidate((0.0, 0.0, 1.0), True, tri, out, at)
    for k in range(4):  # edge 0 -> 1
        s, ok = _spot_edge(g[0][k], g[1][k])
        at = _spot_candidate((1.0 - s, s, 0.0), ok, tri, out, at)
    for k in range(4):  # edge 1 -> 2
        s, ok = _spot_edge(g[1][k], g[2][k])
        at = _spot_candidate((0.0, 1.0 - s, s), ok, tri, out, at)
    for k in range(4):  # edge 2 -> 0
        s, ok = _spot_edge(g[2][k], g[0][k])
        at = _spot_candidate((s, 0.0, 1.0 - s), ok, tri, out, at)
    for k, m in ((0, 2), (0, 3), (1, 2), (1, 3)):
        w0, w1, w2, ok = _spot_lateral(g, k, m)
        at = _spot_candidate((w0, w1, w2), ok, tri, out, at)
    return at


def _spot_dropped(g: tuple[tuple[float, ...], ...], tau: float) -> bool:
    """Every corner outside one side plane by ``2 tau``, or behind the light (the sides'
    sum, ``4 t z``, below ``-8 tau`` at every corner)."""
    g0, g1, g2 = g[0], g[1], g[2]
    for k in range(4):
        if g0[k] < -2.0 * tau and g1[k] < -2.0 * tau and g2[k] < -2.0 * tau:
            return True
    behind = -8.0 * tau
    s0: float = g0[0] + g0[1] + g0[2] + g0[3]
    s1: float = g1[0] + g1[1] + g1[2] + g1[3]
    s2: float = g2[0] + g2[1] + g2[2] + g2[3]
    return s0 < behind and s1 < behind and s2 < behind


def spot_clip_loop(
    T: Float[Array, " t"],
    P: Float[Array, "_ 4"],
    eps: float,
    out: Float[Array, "_ 3"],
    cursor: tuple[int, int],
) -> tuple[int, int, int]:
    """Triangles ``start, start + 1, ...`` of ``T`` (a flat row of ``9 M`` numbers:
    corners ``x0, y0, z0, x1, ...`` per triangle) clipped by the side planes ``P``
    (rows ``(n_k, d_k)``, the first four used), their kept points stored in
    ``out`` ``(capacity, 3)`` from row ``at``, ``cursor = (start, at)`` (see the module).

    Returns ``(stop, at, kept)``: the first triangle not done (``M`` when all are; the
    loop stops before a triangle when fewer than 19 rows are left), the next free row
    and the number of triangles of this call that stored a point.

    Example (run by Python; :func:`shadowmath._backends._kernels.loops` compiles it):
        >>> from shadowmath._math._spot_casters import pyramid_planes
        >>> planes = pyramid_planes(np, np.zeros(3), np.eye(3), np.array(1.0))  # |x|, |y| <= z
        >>> tri = np.array([0.0, 1.0, -1.0, 0.5, 1.0, 3.0, -0.5, 1.0, 3.0])  # y = 1, across y = z
        >>> out = np.empty((19, 3))
        >>> stop, at, kept = spot_clip_loop(tri, planes, 2.0**-52, out, (0, 0))
        >>> stop, kept, float(out[:at, 2].min()), float(out[:at, 2].max())  # clipped at z = 1
        (1, 1, 1.0, 3.0)
    """
    start, at = cursor
    S = _spot_sides(P)
    M = len(T) // 9
    cap = len(out)
    kept = 0
    for m in range(start, M):
        if at + 19 > cap:
            return m, at, kept
        b = 9 * m
        c = (
            float(T[b]), float(T[b + 1]), float(T[b + 2]),
            float(T[b + 3]), float(T[b + 4]), float(T[b + 5]),
            float(T[b + 6]), float(T[b + 7]), float(T[b + 8]),
        )  # fmt: skip
        g0 = _spot_values(c[0], c[1], c[2], S)
        g1 = _spot_values(c[3], c[4], c[5], S)
        g2 = _spot_values(c[6], c[7], c[8], S)
        total = 0.0
        low = math.inf
        for k in range(4):
            total += abs(g0[k]) + abs(g1[k]) + abs(g2[k])
            low = min(low, g0[k], g1[k], g2[k])
        tau = 64.0 * eps * total
        g = (g0, g1, g2)
        if math.isfinite(tau):
            if low >= -tau:  # inside: its corners
                at = _spot_put(out, at, c[0], c[1], c[2])
                at = _spot_put(out, at, c[3], c[4], c[5])
                at = _spot_put(out, at, c[6], c[7], c[8])
                kept += 1
                continue
            if _spot_dropped(g, tau):
                continue
        before = at
        at = _spot_clip(c, g, tau, out, at)
        if at > before:
            kept += 1
    return M, at, kept


FUNCTIONS = (
    "_spot_sides",
    "_spot_values",
    "_spot_put",
    "_spot_candidate",
    "_spot_edge",
    "_spot_lateral",
    "_spot_clip",
    "_spot_dropped",
    "spot_clip_loop",
)
