"""The cascades' compiled loop: every camera and cascade of :func:`fit_cascades`, one pass.

The same formulas as the array driver (:mod:`._cascade_formulas`, :mod:`._fit_formulas`)
on scalars, compiled by Numba (``fast`` extra) through :func:`._specialize.specialize`.
Value checks set bits of a status word in the order of :data:`CHECKS`; the boundary
raises the first failing one's message. Trusted shapes only: nothing here raises.
"""

from __future__ import annotations

import math
from typing import Any

# Shared formulas and primitives, rebound by specialize().
from ._cascade_formulas import (  # noqa: F401
    EDGES,
    affine,
    box_values,
    camera_values,
    cascade_box,
    clip_plane,
    edge_point,
    slice_sphere,
    split_depth,
)
from ._fit_formulas import fit_axes, fit_rows, placement_ok, safe_box, stable_sides, to_light
from ._formulas import fabs, sqrt, where  # noqa: F401
from ._loops import _tuple16

#: A float buffer of ``n`` zeros: a NumPy array under Numba, a list in Python (whose
#: floats stay Python floats, three times faster than NumPy scalars). Bound by specialize().
alloc: Any = None

#: The loop's checks in report order (bit ``1 << index``); the boundary maps them to messages.
CHECKS = (
    "light_finite",
    "view_finite",
    "projection_finite",
    "bounds_finite",
    "up_finite",
    "view_affine",
    "view_singular",
    "projection_singular",
    "infinite_far",
    "bounds_order",
    "light_zero",
    "up_parallel",
    "far_infinite",
    "max_distance",
    "log_near",
    "splits_increase",
    "splits_range",
)

_E0 = (0, 2, 4, 6, 0, 1, 4, 5, 0, 1, 2, 3)
_E1 = (1, 3, 5, 7, 2, 3, 6, 7, 4, 5, 6, 7)

#: One output row per cascade: world_to_light, world_to_clip, world_to_texture (16 each),
#: the frustum's eight numbers, the band's end, the texel's size along X and Y.
ROW = 48 + 8 + 3


def inverse4(m: tuple[Any, ...]) -> tuple[tuple[Any, ...], Any]:
    """The inverse of a 4x4 matrix (16 row-major entries) by 2x2 minors, and its determinant."""
    s0 = m[0] * m[5] - m[4] * m[1]
    s1 = m[0] * m[6] - m[4] * m[2]
    s2 = m[0] * m[7] - m[4] * m[3]
    s3 = m[1] * m[6] - m[5] * m[2]
    s4 = m[1] * m[7] - m[5] * m[3]
    s5 = m[2] * m[7] - m[6] * m[3]
    c5 = m[10] * m[15] - m[14] * m[11]
    c4 = m[9] * m[15] - m[13] * m[11]
    c3 = m[9] * m[14] - m[13] * m[10]
    c2 = m[8] * m[15] - m[12] * m[11]
    c1 = m[8] * m[14] - m[12] * m[10]
    c0 = m[8] * m[13] - m[12] * m[9]
    det = s0 * c5 - s1 * c4 + s2 * c3 + s3 * c2 - s4 * c1 + s5 * c0
    k = 1.0 / where(det != 0, det, 1.0)
    inv = (
        (m[5] * c5 - m[6] * c4 + m[7] * c3) * k,
        (-m[1] * c5 + m[2] * c4 - m[3] * c3) * k,
        (m[13] * s5 - m[14] * s4 + m[15] * s3) * k,
        (-m[9] * s5 + m[10] * s4 - m[11] * s3) * k,
        (-m[4] * c5 + m[6] * c2 - m[7] * c1) * k,
        (m[0] * c5 - m[2] * c2 + m[3] * c1) * k,
        (-m[12] * s5 + m[14] * s2 - m[15] * s1) * k,
        (m[8] * s5 - m[10] * s2 + m[11] * s1) * k,
        (m[4] * c4 - m[5] * c2 + m[7] * c0) * k,
        (-m[0] * c4 + m[1] * c2 - m[3] * c0) * k,
        (m[12] * s4 - m[13] * s2 + m[15] * s0) * k,
        (-m[8] * s4 + m[9] * s2 - m[11] * s0) * k,
        (-m[4] * c3 + m[5] * c1 - m[6] * c0) * k,
        (m[0] * c3 - m[1] * c1 + m[2] * c0) * k,
        (-m[12] * s3 + m[13] * s1 - m[14] * s0) * k,
        (m[8] * s3 - m[9] * s1 + m[10] * s0) * k,
    )
    return inv, det


def _m16(M: Any) -> Any:
    """A 4x4 matrix's row of 16 numbers as a tuple of floats."""
    return (
        float(M[0]), float(M[1]), float(M[2]), float(M[3]),
        float(M[4]), float(M[5]), float(M[6]), float(M[7]),
        float(M[8]), float(M[9]), float(M[10]), float(M[11]),
        float(M[12]), float(M[13]), float(M[14]), float(M[15]),
    )  # fmt: skip


def _mul16(a: Any, b: Any) -> Any:
    """``a @ b`` for 16 row-major entries each."""
    return (
        a[0] * b[0] + a[1] * b[4] + a[2] * b[8] + a[3] * b[12],
        a[0] * b[1] + a[1] * b[5] + a[2] * b[9] + a[3] * b[13],
        a[0] * b[2] + a[1] * b[6] + a[2] * b[10] + a[3] * b[14],
        a[0] * b[3] + a[1] * b[7] + a[2] * b[11] + a[3] * b[15],
        a[4] * b[0] + a[5] * b[4] + a[6] * b[8] + a[7] * b[12],
        a[4] * b[1] + a[5] * b[5] + a[6] * b[9] + a[7] * b[13],
        a[4] * b[2] + a[5] * b[6] + a[6] * b[10] + a[7] * b[14],
        a[4] * b[3] + a[5] * b[7] + a[6] * b[11] + a[7] * b[15],
        a[8] * b[0] + a[9] * b[4] + a[10] * b[8] + a[11] * b[12],
        a[8] * b[1] + a[9] * b[5] + a[10] * b[9] + a[11] * b[13],
        a[8] * b[2] + a[9] * b[6] + a[10] * b[10] + a[11] * b[14],
        a[8] * b[3] + a[9] * b[7] + a[10] * b[11] + a[11] * b[15],
        a[12] * b[0] + a[13] * b[4] + a[14] * b[8] + a[15] * b[12],
        a[12] * b[1] + a[13] * b[5] + a[14] * b[9] + a[15] * b[13],
        a[12] * b[2] + a[13] * b[6] + a[14] * b[10] + a[15] * b[14],
        a[12] * b[3] + a[13] * b[7] + a[14] * b[11] + a[15] * b[15],
    )


def _camera(V: Any, P: Any, C: Any, nc: Any, fc: Any, eps: float) -> Any:
    """Fill the near corners ``nc`` (4 x 3, flat) and far corners ``fc`` (4 x 4, flat).

    Returns the view depth's sign, the near and far depths and the status bits.
    """
    iP, dp = inverse4(P)
    st = 0
    pn = 1.0
    for r in range(4):
        pn *= math.sqrt(P[4 * r] ** 2 + P[4 * r + 1] ** 2 + P[4 * r + 2] ** 2 + P[4 * r + 3] ** 2)
    if not abs(dp) > 64.0 * eps * pn:
        st |= 1 << 7
    nz = fz = fw = 0.0
    for k in range(4):
        x, y = 2.0 * (k & 1) - 1.0, 2.0 * ((k >> 1) & 1) - 1.0
        for z in (-1.0, 1.0):
            c = (
                C[0] * x + C[1] * y + C[2] * z + C[3],
                C[4] * x + C[5] * y + C[6] * z + C[7],
                C[8] * x + C[9] * y + C[10] * z + C[11],
                C[12] * x + C[13] * y + C[14] * z + C[15],
            )
            h = [iP[4 * r] * c[0] + iP[4 * r + 1] * c[1] + iP[4 * r + 2] * c[2]
                 + iP[4 * r + 3] * c[3] for r in range(4)]  # fmt: skip
            if z < 0:
                nc[3 * k], nc[3 * k + 1], nc[3 * k + 2] = h[0] / h[3], h[1] / h[3], h[2] / h[3]
                nz += 0.25 * nc[3 * k + 2]
            else:
                sg = -1.0 if h[3] < 0 else 1.0
                big = max(abs(h[0]), abs(h[1]), abs(h[2]), abs(h[3]))
                for r in range(4):
                    fc[4 * k + r] = sg * h[r] / big
                fz += 0.25 * fc[4 * k + 2]
                fw += 0.25 * fc[4 * k + 3]
    finite_far = fw > 32.0 * eps
    t = fz / fw - nz if finite_far else nz
    sign = -1.0 if t < 0 else 1.0
    if not (finite_far or sign * nz > 0):
        st |= 1 << 8
    far = sign * fz / fw if finite_far else math.inf
    return sign, sign * nz, far, st


def _splits(near: float, far: float, lam: float, n: int, out: Any) -> None:
    """``out[0..n]``: the splits of :func:`._cascade_formulas.split_depth`, exact ends."""
    out[0] = near
    for i in range(1, n):
        out[i] = split_depth(near, far, lam, i / n)
    out[n] = far


def cascade_loop(
    light: Any, views: Any, projs: Any, boxes: Any, ups: Any, scalars: Any, given: Any,
    opts: Any, out: Any, splits: Any, status: Any,
) -> None:  # fmt: skip
    """Every camera's cascades. Operands ``(count or 1, ...)`` are read at ``i % len``.

    ``scalars``: ``(count or 1, 3)`` rows ``(lam, max_distance, overlap)``; ``given``:
    ``(count or 1, n + 1)`` custom splits (read when ``opts[2]``); ``opts``: has_up,
    stable, has_splits, has_dmax, m_x, m_y, width, height, eps, slack, cols, rows,
    then the camera's C, the maps' C and T C (16 each). ``out``: ``(count, n, ROW)``;
    ``splits``: ``(count, n + 1)``; ``status``: ``(count,)``.
    """
    n = len(splits[0]) - 1
    eps = opts[8]
    C, api = _tuple16(opts, 12), (_tuple16(opts, 28), _tuple16(opts, 44))
    nc, fc, bl, bg = alloc(12), alloc(16), alloc(24), alloc(40)
    for i in range(len(out)):
        V, P = _m16(views[i % len(views)]), _m16(projs[i % len(projs)])
        sign, near, far, st = _camera(V, P, C, nc, fc, eps)
        st |= _entry_checks(light[i % len(light)], (V, P), boxes[i % len(boxes)],
                            ups[i % len(ups)], opts, eps)  # fmt: skip
        sc = scalars[i % len(scalars)]
        st |= _split_range(near, far, sc, given[i % len(given)], opts, splits[i])
        Lr, Ur = light[i % len(light)], ups[i % len(ups)]
        box = boxes[i % len(boxes)]
        coords = max(abs(box[0]), abs(box[1]), abs(box[2]),
                     abs(box[3]), abs(box[4]), abs(box[5]))  # fmt: skip
        a, ok_light, _, ok_up = fit_axes(
            (-float(Lr[0]), -float(Lr[1]), -float(Lr[2])),
            (float(Ur[0]), float(Ur[1]), float(Ur[2])), opts[0] != 0, coords, eps,
        )  # fmt: skip
        if not ok_light:
            st |= 1 << 10
        if not ok_up:
            st |= 1 << 11
        status[i] = st
        _box_pass(V, P, box, a, sign, bl, bg)
        iV = inverse4(V)[0]
        s = splits[i]
        for j in range(n):
            s0, s1 = s[j], s[j + 1]
            end = min(s1 + sc[2] * (s1 - s0), s[n])
            row = out[i][j]
            _cascade(iV, a, (sign, s0, end), (nc, fc), (bl, bg), box, opts, api, row, j)
            row[56] = end


def _entry_checks(L: Any, VP: Any, box: Any, U: Any, opts: Any, eps: float) -> int:
    """The finiteness, affinity and order checks of one entry's inputs."""
    V, P = VP
    st = 0
    ptotal = 0.0
    for v in P:
        ptotal += v
    if not math.isfinite(ptotal):
        st |= 4
    if not math.isfinite(float(L[0]) + float(L[1]) + float(L[2])):
        st |= 1
    total = 0.0
    for v in V:
        total += v
    if not math.isfinite(total):
        st |= 2
    bsum = 0.0
    for c in range(3):
        bsum += box[c] + box[3 + c]
        if box[3 + c] < box[c]:
            st |= 1 << 9
    if not math.isfinite(bsum):
        st |= 8
    if opts[0] != 0 and not math.isfinite(float(U[0]) + float(U[1]) + float(U[2])):
        st |= 16
    if not (V[12] == 0 and V[13] == 0 and V[14] == 0 and V[15] == 1):
        st |= 1 << 5
    if not placement_ok(V, eps):  # the linear part's Hadamard test, as the array driver's
        st |= 1 << 6
    return st


def _split_range(near: float, far: float, sc: Any, given: Any, opts: Any, out: Any) -> int:
    """The splits into ``out`` (given, or from the scheme over [near, far or max_distance])."""
    n = len(out) - 1
    st = 0
    if opts[2] != 0:
        tol = math.sqrt(opts[8])
        for k in range(n + 1):
            out[k] = given[k]
            if k > 0 and not given[k] > given[k - 1]:
                st |= 1 << 15
        if not (given[0] >= near - tol * abs(near) and given[n] <= far * (1 + tol)):
            st |= 1 << 16
        return st
    end = far
    if opts[3] != 0:
        if not (sc[1] > near and sc[1] <= far):
            st |= 1 << 13
        end = min(sc[1], far) if sc[1] > near else near + 1.0
    elif not math.isfinite(far):
        st |= 1 << 12
    if not math.isfinite(end):
        end = near + 1.0
    if sc[0] != 0 and not near > 0:
        st |= 1 << 14
    _splits(near, end, sc[0], n, out)
    return st


def _box_pass(V: Any, P: Any, box: Any, a: Any, sign: float, bl: Any, bg: Any) -> None:
    """The scene box's corners (``box``: min then max, 6 numbers): light coordinates
    (``bl``, 8 x 3), camera side values and view depth (``bg``, 8 x 5)."""
    PV = _mul16(P, V)
    for k in range(8):
        x = float(box[3 * (k & 1)])
        y = float(box[3 * ((k >> 1) & 1) + 1])
        z = float(box[3 * (k >> 2) + 2])
        p = to_light(x, y, z, a)
        bl[3 * k], bl[3 * k + 1], bl[3 * k + 2] = p[0], p[1], p[2]
        sides = camera_values(PV, x, y, z)
        for c in range(4):
            bg[5 * k + c] = sides[c]
        bg[5 * k + 4] = sign * (V[8] * x + V[9] * y + V[10] * z + V[11])


def _cascade(
    iV: Any, a: Any, d: Any, cam: Any, boxp: Any, box: Any, opts: Any, api: Any, row: Any, j: int
) -> None:
    """One cascade's fit into ``row`` (:data:`ROW` numbers)."""
    sign, s0, s1 = d
    nc, fc = cam
    bl, bg = boxp
    vc, lc, gs = alloc(24), alloc(24), alloc(48)
    lo = (float(box[0]), float(box[1]), float(box[2]))
    hi = (float(box[3]), float(box[4]), float(box[5]))
    m12 = (iV[0], iV[1], iV[2], iV[3], iV[4], iV[5], iV[6], iV[7], iV[8], iV[9], iV[10], iV[11])
    for k in range(8):
        depth = s0 if k < 4 else s1
        e = k % 4
        near = (nc[3 * e], nc[3 * e + 1], nc[3 * e + 2])
        far = (fc[4 * e], fc[4 * e + 1], fc[4 * e + 2], fc[4 * e + 3])
        p = edge_point(near, far, sign, depth)
        vc[3 * k], vc[3 * k + 1], vc[3 * k + 2] = p[0], p[1], p[2]
        w = affine(m12, p[0], p[1], p[2])
        q = to_light(w[0], w[1], w[2], a)
        lc[3 * k], lc[3 * k + 1], lc[3 * k + 2] = q[0], q[1], q[2]
        g = box_values(w[0], w[1], w[2], lo, hi)
        for c in range(6):
            gs[6 * k + c] = g[c]
    b = _bounds(lc, gs, bl, bg, s0, s1)
    if opts[1] != 0:
        hx, hy, cx, cy, z_lo, z_hi = _stable(vc, m12, a, b, opts)
        pad = (z_hi - z_lo) + max(hx, hy)
        near, far = pad, pad + (z_hi - z_lo)
    else:
        hx, hy, cx, cy, near, far = cascade_box((b[0], b[1], b[2], b[3], b[4], b[5]))
        z_lo = b[4]
    _store_cascade(a, (hx, hy, cx, cy, near, far), z_lo, opts, api, row, j)


def _bounds(lc: Any, gs: Any, bl: Any, bg: Any, s0: float, s1: float) -> Any:
    """Light-space bounds of the slice intersected with the box (with the slice's fallback).

    Each corner's outcode (bit ``j``: outside half-space ``j``, Cohen and Sutherland)
    settles most edges without clipping: a common bit puts the edge outside, no bit at
    either end inside; :func:`clip_segment` gives the same answers, only slower.
    """
    inf = math.inf
    lx, hx_, ly, hy_, lz, hz = inf, -inf, inf, -inf, inf, -inf
    cs, cb = alloc(8), alloc(8)
    whole = True  # every slice corner in the (convex) box: the intersection is the slice
    for k in range(8):
        c = 0
        for j in range(6):
            if gs[6 * k + j] < 0:
                c |= 1 << j
        cs[k] = c
        if c != 0:
            whole = False
        d = bg[5 * k + 4]
        c = (16 if d - s0 < 0 else 0) | (32 if s1 - d < 0 else 0)
        for j in range(4):
            if bg[5 * k + j] < 0:
                c |= 1 << j
        cb[k] = c
    seen = False
    for e in range(0 if whole else 24):
        k0, k1 = _E0[e % 12], _E1[e % 12]
        codes = cs if e < 12 else cb
        c0, c1 = int(codes[k0]), int(codes[k1])
        if c0 & c1:
            continue
        pts = lc if e < 12 else bl
        if c0 | c1:  # clip by the planes an end is outside of (the others change nothing)
            t0, t1, ok, crossed = 0.0, 1.0, True, c0 | c1
            for j in range(6):
                if crossed & (1 << j):
                    if e < 12:
                        a, b = gs[6 * k0 + j], gs[6 * k1 + j]
                    elif j < 4:
                        a, b = bg[5 * k0 + j], bg[5 * k1 + j]
                    elif j == 4:
                        a, b = bg[5 * k0 + 4] - s0, bg[5 * k1 + 4] - s0
                    else:
                        a, b = s1 - bg[5 * k0 + 4], s1 - bg[5 * k1 + 4]
                    t0, t1, ok = clip_plane(t0, t1, ok, a, b)
            ok = ok and t0 <= t1
        else:
            t0, t1, ok = 0.0, 1.0, True
        p0 = (pts[3 * k0], pts[3 * k0 + 1], pts[3 * k0 + 2])
        p1 = (pts[3 * k1], pts[3 * k1 + 1], pts[3 * k1 + 2])
        if ok:
            seen = True
            dx, dy, dz = p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]
            for t in (t0, t1):
                x, y, z = p0[0] + t * dx, p0[1] + t * dy, p0[2] + t * dz
                # Comparisons, not min()/max(): the Python run of this loop calls nothing.
                if x < lx:
                    lx = x
                if x > hx_:
                    hx_ = x
                if y < ly:
                    ly = y
                if y > hy_:
                    hy_ = y
                if z < lz:
                    lz = z
                if z > hz:
                    hz = z
    if whole or not seen:
        for k in range(8):
            x, y, z = lc[3 * k], lc[3 * k + 1], lc[3 * k + 2]
            lx, hx_, ly, hy_ = min(lx, x), max(hx_, x), min(ly, y), max(hy_, y)
            lz, hz = min(lz, z), max(hz, z)
    zb = zt = bl[2]
    for k in range(8):
        zb, zt = min(zb, bl[3 * k + 2]), max(zt, bl[3 * k + 2])
    return lx, hx_, ly, hy_, min(min(zb, lz), hz), hz, zb, zt


def _stable(vc: Any, m12: Any, a: Any, b: Any, opts: Any) -> Any:
    """The stable box of one cascade: sphere, snapped centre, depth range."""
    corners = (
        vc[0], vc[1], vc[2], vc[3], vc[4], vc[5], vc[6], vc[7], vc[8], vc[9], vc[10], vc[11],
        vc[12], vc[13], vc[14], vc[15], vc[16], vc[17], vc[18], vc[19], vc[20], vc[21],
        vc[22], vc[23],
    )  # fmt: skip
    vx, vy, vz, r2 = slice_sphere(corners)
    c = affine(m12, vx, vy, vz)
    r = math.sqrt(r2)
    hx, hy, ox, oy, _ = stable_sides(r2, c, a, (opts[4], opts[5], opts[6], opts[7]), r, opts[8])
    cx = c[0] * a[0] + c[1] * a[1] + c[2] * a[2] + ox
    cy = c[0] * a[3] + c[1] * a[4] + c[2] * a[5] + oy
    cz = c[0] * a[6] + c[1] * a[7] + c[2] * a[8]
    z_hi = min(cz + r, b[7])
    z_lo = min(b[6], z_hi - r)
    return hx, hy, cx, cy, z_lo, z_hi


def _store_cascade(a: Any, box6: Any, z_lo: float, opts: Any, api: Any, row: Any, j: int) -> None:
    """The cascade's matrices, frustum and texel size into ``row``."""
    hx, hy, cx, cy, near, far = box6
    shift = z_lo - near
    origin = (shift * a[6], shift * a[7], shift * a[8])
    slack = opts[9]
    near, far = near * (1 - slack), far * (1 + slack)
    mx, my = opts[4], opts[5]
    w, clip, tex = fit_rows(origin, a, safe_box(hx, hy, cx, cy, near, far), (mx, my), True, api)
    cols, rows = max(int(opts[10]), 1), max(int(opts[11]), 1)  # 0: texture layers, no tiles
    col, rw = float(j % cols), float(j // cols) if opts[10] > 0 else 0.0
    for k in range(12):
        row[k] = w[k]
    row[12], row[13], row[14], row[15] = 0.0, 0.0, 0.0, 1.0
    for k in range(16):
        row[16 + k] = clip[k]
        row[32 + k] = tex[k]
    for k in range(4):
        row[32 + k] = (tex[k] + col * tex[12 + k]) / cols
        row[36 + k] = (tex[4 + k] + rw * tex[12 + k]) / rows
    row[48], row[49], row[50], row[51] = hx, hy, near, far
    row[52], row[53], row[54], row[55] = mx, my, cx, cy
    row[57] = 2.0 * hx / (mx * opts[6])
    row[58] = 2.0 * hy / (my * opts[7])


FUNCTIONS = (
    "inverse4",
    "_m16",
    "_mul16",
    "_camera",
    "_splits",
    "cascade_loop",
    "_entry_checks",
    "_split_range",
    "_box_pass",
    "_cascade",
    "_bounds",
    "_stable",
    "_store_cascade",
)
