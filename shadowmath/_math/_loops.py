"""The loops over the batch: the fits' steps per entry, for Numba or plain Python.

Every function here is plain Python over scalars, written in the subset that
Numba compiles (tuples, ``len``, ``a[i][j]`` indexing, ``math``). Like the
formulas, they are specialized (:func:`._specialize.specialize`): compiled by
Numba through :func:`._kernels.loops` (whose cache folder is keyed on every
source of the package, so the machine code on disk can never be older than the
formulas it inlines), or bound to Python floats for one small NumPy fit without
Numba (:func:`._specialize.scalar_formulas`), where a Python loop over a few
vertices beats hundreds of NumPy calls.

Per entry, the passes that the fit needs, each reading the vertices once, then
the frame, sides, depth range and matrices from the formulas of
:mod:`._fit_formulas` and :mod:`._formulas`: the same functions that the array
path (:mod:`._fit_arrays`) runs on whole arrays. Sums are accumulated in float64
whatever the input dtype. Validity is reported per entry as the bits of
:mod:`._status`; the boundary raises the message of the first failing one.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from shadowmath._boundary._status import (
    FORMULA_BITS,
    LIGHT,
    NEAR_ROUNDING,
    OUTSIDE_CONE,
    OVERFLOW,
    PLACEMENT,
    PROJECTIVE,
    RECEIVERS,
    SINGULAR_PLACEMENT,
    SPOT,
    SPOT_ANGLE,
    TOO_WIDE,
    UP,
    VERTICES,
    WIDE_WARNING,
)

from ._fit_formulas import (
    box_sides,
    depth_range,
    directional_origin,
    fit_axes,
    fit_rows,
    fov_ok,
    near_clear,
    place,
    placement_ok,
    point_sides,
    receiver_counted,
    safe_box,
    sphere_through,
    spot_angle_ok,
    spot_sides,
    stable_sides,
    to_light,
    triangle_far,
)
from ._formulas import axes_from_z, compose_rows, normalize3, planar_entries

_BITS = FORMULA_BITS


def planar_loop(plane: Any, light: Any, eps: float, out: Any, status: Any) -> None:
    splitter = 134217729.0  # 2^27 + 1: the loop computes in float64
    for i in range(len(out)):
        P, L = plane[i % len(plane)], light[i % len(light)]
        pi = (float(P[0]), float(P[1]), float(P[2]), float(P[3]))
        li = (float(L[0]), float(L[1]), float(L[2]), float(L[3]))
        st = 0
        for v in pi:
            if not math.isfinite(v):
                st |= 1
        for v in li:
            if not math.isfinite(v):
                st |= 2
        e = planar_entries(pi, li, splitter)
        if not e[18] > 0:
            st |= 4
        if li[0] == 0 and li[1] == 0 and li[2] == 0 and li[3] == 0:
            st |= 8
        if not abs(e[16]) > 16 * eps * e[17]:
            st |= 16
        status[i] = st
        for j in range(16):
            out[i, j] = e[j]


def _vertex(V: Any, k: int, b: Any, has_b: bool) -> Any:
    """Vertex ``k`` in world coordinates and its ``w`` (1 without a placement)."""
    vx, vy, vz = float(V[k][0]), float(V[k][1]), float(V[k][2])
    if has_b:
        return place(b, vx, vy, vz)
    return vx, vy, vz, 1.0


def _spread(V: Any, b: Any, has_b: bool, o: Any) -> tuple[Any, ...]:
    """Pass 1 about the point ``o``: sums and bounds of ``p - o``, reach, coords, status."""
    sx = sy = sz = reach = coords = raw = 0.0
    lo_x = lo_y = lo_z = math.inf
    hi_x = hi_y = hi_z = -math.inf
    st = 0
    for k in range(len(V)):
        raw += float(V[k][0]) + float(V[k][1]) + float(V[k][2])
        px, py, pz, w = _vertex(V, k, b, has_b)
        if not w > 0:
            st |= PROJECTIVE
        x, y, z = px - o[0], py - o[1], pz - o[2]
        sx, sy, sz = sx + x, sy + y, sz + z
        lo_x, lo_y, lo_z = min(lo_x, x), min(lo_y, y), min(lo_z, z)
        hi_x, hi_y, hi_z = max(hi_x, x), max(hi_y, y), max(hi_z, z)
        reach = max(reach, abs(x), abs(y), abs(z))
        coords = max(coords, abs(px), abs(py), abs(pz))
    if not math.isfinite(raw):
        st |= VERTICES
    elif not (math.isfinite(sx) and math.isfinite(sy) and math.isfinite(sz)):
        st |= OVERFLOW
    return (sx, sy, sz), (lo_x, lo_y, lo_z), (hi_x, hi_y, hi_z), reach, coords, st


def _light_pass(V: Any, b: Any, has_b: bool, o: Any, a: Any, ratios: bool) -> Any:
    """Pass 2: bounds of ``x, y`` (or ``x / z, y / z``) and ``z`` about ``o``; max ``|p - o|^2``."""
    hx = hy = hz = -math.inf
    lx = ly = lz = math.inf
    r2 = reach = 0.0
    for k in range(len(V)):
        px, py, pz, _ = _vertex(V, k, b, has_b)
        ox, oy, oz = px - o[0], py - o[1], pz - o[2]
        x, y, z = to_light(ox, oy, oz, a)
        if ratios:
            inv_z = 1.0 / z if z > 0 else 1.0
            x, y = x * inv_z, y * inv_z
        hx, lx, hy, ly = max(hx, x), min(lx, x), max(hy, y), min(ly, y)
        hz, lz = max(hz, z), min(lz, z)
        r2 = max(r2, ox * ox + oy * oy + oz * oz)
        reach = max(reach, abs(ox), abs(oy), abs(oz))
    return (hx, lx, hy, ly, hz, lz), r2, reach


def _receiver_far(R: Any, o: Any, a: Any, sides: Any, z_hi: Any, o9: Any) -> Any:
    """The far end widened over the receivers inside the sides; their finite flag.

    ``o9 = (directional, triangles, eps)``: receiver rows are points (3) or
    triangles (9 numbers: three corners). Receivers only ever push ``far``: one
    nearer than every caster can never be shadowed, so ``near`` stays the casters'.
    """
    directional, triangles, eps = o9
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
    return z_hi, math.isfinite(raw)


#: Welzl's algorithm visits the vertices in the order ``k * _STRIDE mod n`` (a prime
#: stride: every vertex once), which breaks up a mesh's ordered rows; its expected
#: time is linear for a random order. The result does not depend on the order.
_STRIDE = 1000003


def _nth(V: Any, b: Any, has_b: bool, k: int, stride: int) -> Any:
    """The ``k``-th vertex in Welzl's order: its index and world coordinates."""
    i = (k * stride) % len(V)
    p = _vertex(V, i, b, has_b)
    return i, (p[0], p[1], p[2])


def _ball(V: Any, b: Any, has_b: bool, sup: Any, k: int) -> Any:
    """:func:`sphere_through` the support vertices ``sup`` (indices), ``k`` of them."""
    p0, p1 = _vertex(V, sup[0], b, has_b), _vertex(V, sup[1], b, has_b)
    p2, p3 = _vertex(V, sup[2], b, has_b), _vertex(V, sup[3], b, has_b)
    q = (p0[0], p0[1], p0[2], p1[0], p1[1], p1[2], p2[0], p2[1], p2[2], p3[0], p3[1], p3[2])
    return sphere_through(q, k)


def _outside(p: Any, ball: Any) -> bool:
    """``p`` outside the ball by more than the rounding of its coordinates (float64).

    (A point within rounding of the sphere, such as a repeated vertex far from the
    origin, must not become a support point: two equal support points make the
    sphere through them ill-posed.)
    """
    dx, dy, dz = p[0] - ball[0], p[1] - ball[1], p[2] - ball[2]
    tau = 64.0 * 2.220446049250313e-16 * (abs(p[0]) + abs(p[1]) + abs(p[2]))
    return bool(math.sqrt(dx * dx + dy * dy + dz * dz) > math.sqrt(ball[3]) * (1.0 + 1e-14) + tau)


def _enclosing_sphere(V: Any, b: Any, has_b: bool) -> Any:
    """The minimal enclosing sphere's support: vertex indices (4, repeated) and their count.

    Welzl's algorithm (1991) in its iterative form: a vertex outside the current
    sphere lies on the boundary of the sphere of the vertices before it, so each
    level fixes one more boundary point (at most 4 in 3D) and restarts over the
    vertices before it. The sphere is unique, so it depends on the point set only:
    not on the order, the tessellation or the orientation.
    """
    n = len(V)
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


def support_loop(verts: Any, out: Any) -> None:
    """The enclosing sphere's support of every entry of ``(count, N, 3)`` world vertices:
    ``out[i] = (i_0, i_1, i_2, i_3, k)``."""
    none = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    for e in range(len(out)):
        sup, k = _enclosing_sphere(verts[e], none, False)
        out[e, 0], out[e, 1], out[e, 2], out[e, 3], out[e, 4] = sup[0], sup[1], sup[2], sup[3], k


def _sides(hx: float, hy: float, margins: Any, cx: float, cy: float) -> Any:
    """``(s_x, s_y, c_x, c_y)`` of :func:`receiver_counted` with safe half-widths."""
    return (margins[0] / (hx if hx > 0 else 1.0), margins[1] / (hy if hy > 0 else 1.0), cx, cy)


def _flags(ok: Any, first: int) -> int:
    """Status bits of the formula checks ``ok`` (starting at ``FORMULA_BITS[first]``)."""
    st = 0
    for j in range(len(ok)):
        if not ok[j]:
            st |= _BITS[first + j]
    return st


def _point_entry(L: Any, V: Any, b: Any, R: Any, U: Any, o: Any, S: Any) -> Any:
    """One point (or spot) light's fit. ``o``: the options of :func:`fit_loop`; ``S``: a
    spot light's axis, ``tan(angle)`` and angle."""
    aim_bbox, has_b, has_r, has_up, single, margins, eps = o[0], o[1], o[2], o[3], o[4], o[5], o[6]
    spot = o[12]
    s, lo, hi, reach, coords, st = _spread(V, b, has_b, L)
    n = len(V)
    if spot:
        d = (S[0], S[1], S[2])
        if not spot_angle_ok(S[4]):
            st |= SPOT_ANGLE
    elif aim_bbox:
        d = (0.5 * (hi[0] + lo[0]), 0.5 * (hi[1] + lo[1]), 0.5 * (hi[2] + lo[2]))
    else:
        d = (s[0] / n, s[1] / n, s[2] / n)
    coords = max(coords, abs(L[0]), abs(L[1]), abs(L[2]))
    a, ok_nonzero, ok_dir, ok_up = fit_axes(d, U, has_up, coords, eps)
    if spot:
        if not ok_nonzero:
            st |= SPOT
        ok_dir = True
    if single and not has_up:
        # The helper axis is decided on Z as returned (rounded to float32), as the
        # float32 array path decides it, so the documented rule holds for that frame.
        zx, zy, zz, _ = normalize3(d[0], d[1], d[2])
        zx, zy, zz = float(np.float32(zx)), float(np.float32(zy)), float(np.float32(zz))
        a = axes_from_z(zx, zy, zz) + (zx, zy, zz)  # noqa: RUF005 (Numba: tuple concatenation)
    st |= _flags((ok_dir, ok_up), 1)
    bounds, _, _ = _light_pass(V, b, has_b, L, a, True)
    hx, lx, hy, ly, zb_max, zb_min = bounds
    if spot:
        half_x, half_y, cx, cy, ok_behind, ok_cone, ok_sil = spot_sides(
            (hx, lx, hy, ly), S[3], zb_min, reach, eps
        )
        if not ok_cone:
            st |= OUTSIDE_CONE
    else:
        half_x, half_y, ok_behind, ok_sil = point_sides(hx, lx, hy, ly, zb_min, reach, eps)
        cx = cy = 0.0
    st |= _flags((ok_behind, ok_sil), 3)
    if not near_clear(zb_min, coords, eps):
        st |= NEAR_ROUNDING
    ok_fov, calm = fov_ok((half_x, half_y, cx, cy), margins)
    if not ok_fov:
        st |= TOO_WIDE
    elif not calm:
        st |= WIDE_WARNING
    z_hi, ok_r = zb_max, True
    if has_r:
        sides = _sides(half_x, half_y, margins, cx, cy)
        z_hi, ok_r = _receiver_far(R, L, a, sides, zb_max, (False, o[13], eps))
    if not ok_r:
        st |= RECEIVERS
    box = (half_x, half_y, cx, cy)
    return st, (L[0], L[1], L[2]), a, box, (zb_min, z_hi, zb_min, zb_max)


def _directional_entry(L: Any, V: Any, b: Any, R: Any, U: Any, o: Any) -> Any:
    """One directional light's fit. ``o``: the options tuple of :func:`fit_loop`."""
    has_b, has_r, has_up, stable, margins, eps, texels = o[1], o[2], o[3], o[7], o[5], o[6], o[8]
    zero3 = (0.0, 0.0, 0.0)
    _, lo, hi, _, coords, st = _spread(V, b, has_b, zero3)
    a, ok_light, _, ok_up = fit_axes((-L[0], -L[1], -L[2]), U, has_up, coords, eps)
    st |= _flags((ok_light,), 0) | _flags((ok_up,), 2)
    sphere = (0.0, 0.0, 0.0, 0.0)
    if stable:  # the minimal enclosing sphere: the shape's, whatever its vertices
        sup, k = _enclosing_sphere(V, b, has_b)
        sphere = _ball(V, b, has_b, sup, k)
        c = (sphere[0], sphere[1], sphere[2])
    else:
        c = (0.5 * (hi[0] + lo[0]), 0.5 * (hi[1] + lo[1]), 0.5 * (hi[2] + lo[2]))
    bounds, _, reach = _light_pass(V, b, has_b, c, a, False)
    hx, lx, hy, ly, zb_max, zb_min = bounds
    if stable:
        texels4 = (margins[0], margins[1], texels[0], texels[1])
        half_x, half_y, cx, cy, ok_sil = stable_sides(sphere[3], c, a, texels4, reach, eps)
    else:
        half_x, half_y, cx, cy, ok_sil = box_sides(hx, lx, hy, ly, reach, eps)
    st |= _flags((ok_sil,), 4)
    z_hi, ok_r = zb_max, True
    if has_r:
        sides = _sides(half_x, half_y, margins, cx, cy)
        z_hi, ok_r = _receiver_far(R, c, a, sides, zb_max, (True, o[13], eps))
    if not ok_r:
        st |= RECEIVERS
    ox, oy, oz, shift = directional_origin(zb_min, z_hi, half_x, half_y, c, a)
    z = (zb_min - shift, z_hi - shift, zb_min - shift, zb_max - shift)
    return st, (ox, oy, oz), a, (half_x, half_y, cx, cy), z


def _row(V: Any, i: int) -> Any:
    return V[i % len(V)]


def _entries(M: Any, i: int) -> Any:
    """Batch entry ``i`` of ``(count or 1, 4, 4)`` matrices as 16 floats."""
    m = M[i % len(M)]
    return (
        float(m[0][0]), float(m[0][1]), float(m[0][2]), float(m[0][3]),
        float(m[1][0]), float(m[1][1]), float(m[1][2]), float(m[1][3]),
        float(m[2][0]), float(m[2][1]), float(m[2][2]), float(m[2][3]),
        float(m[3][0]), float(m[3][1]), float(m[3][2]), float(m[3][3]),
    )  # fmt: skip


def _spot(Lr: Any, spot: bool) -> Any:
    """A spot light's axis, ``tan(angle)`` and angle (columns 3 to 7 of its row), or zeros."""
    if spot:
        return (float(Lr[3]), float(Lr[4]), float(Lr[5]), float(Lr[6]), float(Lr[7]))
    return (0.0, 0.0, 0.0, 0.0, 0.0)


def _check_spot(S: Any, spot: bool) -> int:
    if spot:
        for v in S:
            if not math.isfinite(v):
                return LIGHT
    return 0


def _check_finite(L: Any, U: Any, b: Any, o: Any) -> int:
    st = 0
    if not (math.isfinite(L[0]) and math.isfinite(L[1]) and math.isfinite(L[2])):
        st |= LIGHT
    if o[3] and not (math.isfinite(U[0]) and math.isfinite(U[1]) and math.isfinite(U[2])):
        st |= UP
    if o[1]:
        for e in b:
            if not math.isfinite(e):
                st |= PLACEMENT
        if not placement_ok(b, o[6]):
            st |= SINGULAR_PLACEMENT
    return st


def _tuple16(v: Any, k: int) -> Any:
    return (
        v[k], v[k + 1], v[k + 2], v[k + 3], v[k + 4], v[k + 5], v[k + 6], v[k + 7],
        v[k + 8], v[k + 9], v[k + 10], v[k + 11], v[k + 12], v[k + 13], v[k + 14], v[k + 15],
    )  # fmt: skip


def _unpack(opts: Any) -> Any:
    """The static options from their float64 array (one array: the cheapest to dispatch).

    Layout (:func:`._compiled.options`): aim_bbox, has_b, has_r, has_up, single, m_x,
    m_y, eps, stable, width, height, directional, has_near, has_far, slack, C (16), T C (16),
    spot, triangles (receiver rows of three corners).
    """
    o = (
        opts[0] != 0, opts[1] != 0, opts[2] != 0, opts[3] != 0, opts[4] != 0,
        (opts[5], opts[6]), opts[7], opts[8] != 0, (opts[9], opts[10]), opts[11] != 0,
        (opts[12] != 0, opts[13] != 0), opts[14], opts[47] != 0, opts[48] != 0,
    )  # fmt: skip
    return o, (_tuple16(opts, 15), _tuple16(opts, 31))


def fit_loop(
    light: Any, verts: Any, placement: Any, recv: Any, ups: Any, near: Any, far: Any,
    opts: Any, out: Any, mats: Any, status: Any,
) -> None:  # fmt: skip
    """Every batch entry's fit; operands are ``(count or 1, ...)``, read at ``i % len``.

    ``near``, ``far``: ``(count or 1,)`` (ignored unless given); ``opts``: see :func:`_unpack`.
    """
    o, api = _unpack(opts)
    directional, has_nf, slack = o[9], o[10], o[11]
    for i in range(len(out)):
        Lr, Ur = _row(light, i), _row(ups, i)
        L = (float(Lr[0]), float(Lr[1]), float(Lr[2]))
        S = _spot(Lr, o[12])
        U = (float(Ur[0]), float(Ur[1]), float(Ur[2]))
        b = _entries(placement, i)
        V, R = _row(verts, i), _row(recv, i)
        if directional:
            st, origin, a, sides, z = _directional_entry(L, V, b, R, U, o)
        else:
            st, origin, a, sides, z = _point_entry(L, V, b, R, U, o, S)
        st |= _check_finite(L, U, b, o) | _check_spot(S, o[12])
        nf = (float(_row(near, i)), float(_row(far, i)))
        n, f, ok = depth_range(z, nf, has_nf, slack)
        st |= _flags(ok, 5)
        status[i] = st
        hx, hy, cx, cy = sides
        safe = safe_box(hx, hy, cx, cy, n, f)
        W, clip, tex = fit_rows(origin, a, safe, o[5], directional, api)
        if o[1]:
            clip = compose_rows(clip, b)
        _store(out[i], mats[i], (origin, a, (hx, hy, n, f), o[5], (cx, cy)), (W, clip, tex, b))


def _store(row: Any, mat: Any, fields: Any, matrices: Any) -> None:
    """One entry's output row (frame, frustum) and its four matrices."""
    origin, a, box, margins, offsets = fields
    W, clip, tex, b = matrices
    for j in range(3):
        row[j] = origin[j]
    for j in range(9):
        row[3 + j] = a[j]
    for j in range(4):
        row[12 + j] = box[j]
    row[16], row[17], row[18], row[19] = margins[0], margins[1], offsets[0], offsets[1]
    for j in range(12):
        mat[0, j // 4, j % 4] = W[j]
    mat[0, 3, 0], mat[0, 3, 1], mat[0, 3, 2], mat[0, 3, 3] = 0.0, 0.0, 0.0, 1.0
    for j in range(16):
        mat[1, j // 4, j % 4] = clip[j]
        mat[2, j // 4, j % 4] = tex[j]
        mat[3, j // 4, j % 4] = b[j]


FUNCTIONS = (
    "planar_loop",
    "_vertex",
    "_spread",
    "_light_pass",
    "_receiver_far",
    "_nth",
    "_ball",
    "_outside",
    "_enclosing_sphere",
    "support_loop",
    "_sides",
    "_flags",
    "_point_entry",
    "_directional_entry",
    "_row",
    "_entries",
    "_check_finite",
    "_spot",
    "_check_spot",
    "_tuple16",
    "_unpack",
    "fit_loop",
    "_store",
)
