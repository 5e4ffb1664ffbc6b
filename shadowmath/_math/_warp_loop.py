r"""LiSPSM per entry (Python or Numba floats): the loop form of the warp.

The array form is :mod:`shadowmath._fits.cascades._lispsm` (its docstring and
``docs/lispsm.md`` derive every formula); this form runs the same steps on one cascade
at a time inside :func:`._cascade_steps.cascade_loop`: the camera seen in the light frame
(:func:`warp_view`), the receiver samples (:func:`warp_samples`), the warp frustum with
its cap (:func:`warp_frustum`: weighted quantiles by :func:`_quantile_loop`, Newton steps by
:func:`_capped_loop`) and the clip rows (:func:`warp_rows`). Samples of zero weight are
dropped (a zero weight splits no quantile: the same value to rounding). The two forms
agree to rounding. Trusted inputs: nothing here raises.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

from shadowmath._boundary._shapes import Row, Scalar, Truth

from ._cascade_formulas import alloc

# The warp's constants (the array form, shadowmath._fits.cascades._lispsm, reads them here).

#: The warp falls back to the orthographic cascade where ``sin(gamma) <= WARP_MIN_SIN``
#: (the view within about 1.15 degrees of the light's direction, either way): the
#: warp's axis ``u`` is then undefined or ill-conditioned (Filament's threshold).
WARP_MIN_SIN = 0.02

#: The cascade is not warped where the strength ``lambda = d / n`` (the warp frustum's depth
#: over its near distance) falls below this: the warp is then within about 1 % of an
#: orthographic map, and the map's rows would lose precision to ``n >> d``.
WARP_MIN_STRENGTH = 0.01

#: The cap's first check: the warped map is no coarser than the orthographic one up to the
#: point of the view axis at view depth ``z_0 (z_1 / z_0)^WARP_CHECK_DEPTH`` (``[z_0, z_1]``:
#: the cascade's depths), ``docs/lispsm.md``.
WARP_CHECK_DEPTH = 0.9

#: The cap's second check: the quantiles (shares) of the texel area per pixel footprint, over
#: each cascade's receiver samples (:func:`warp_samples`), that the warp must not raise: the
#: median and the 90th percentile (:func:`_check_loop`).
WARP_SHARES = (0.5, 0.9)

#: The margin for the samples standing in for the pixels: a quantile ``q`` of
#: :data:`WARP_SHARES` holds on the share ``q + WARP_SHARE_MARGIN`` of the samples (the
#: pose sweep's figures vary by about 2 % with the grid's size without it).
WARP_SHARE_MARGIN = 0.05

#: The receiver samples: one ray through the centre of each cell of a ``G x G`` grid over
#: the screen (``G = WARP_RAYS``), where the ray leaves the scene box.
WARP_RAYS = 16

#: A sample's weight in a cascade ramps from 0 to 1 over this fraction of the slice's depth
#: about each end (half outside, half inside), so that the weights move continuously as a
#: sample crosses a split (and, without a blend band, the two cascades' weights add to 1).
WARP_SAMPLE_RAMP = 0.05

#: The quantile's prior, in samples: ``WARP_PRIOR`` spread evenly over ``[0, 1]`` (it makes
#: the quantile a continuous function of the samples) and as much at 1 (a cascade without
#: samples is checked at its far end: never coarser anywhere).
WARP_PRIOR = 0.5

#: Rounds of ``kappa`` (from the samples, at the strength ``lambda``) and ``lambda`` (capped
#: at ``kappa``): the first takes ``kappa`` at the uncapped strength.
WARP_ROUNDS = 2

#: Newton steps toward the strongest warp within the cap (:func:`_capped_loop`).
NEWTON_STEPS = 8


class WarpView(NamedTuple):
    """The camera in the cascade's light frame (:class:`._lispsm._View`, per entry)."""

    ux: Any  # the warp axis u = (ux, uy, 0)
    uy: Any
    sin: Any  # sin(gamma) (1 where not ok)
    g0: Any  # view depth = g0 x + g1 y + g2 z + g3 in light coordinates
    g1: Any
    g2: Any
    g3: Any
    eye_s: Any  # the eye along w = (-uy, ux, 0)
    eye_t: Any  # and along u
    ok: Any


class WarpFrustum(NamedTuple):
    """The warp frustum (:class:`._lispsm._Warp`, per cascade)."""

    t0: Any  # t = u . l - t0
    n: Any
    f: Any
    z0: Any  # the scene box's z nearest the light
    ok: Any


def warp_view(iV: Row, sign: Scalar, VP: tuple[Row, Row], a: Row) -> WarpView:
    """The :class:`WarpView` of the camera (``iV``: view to world, 16; ``VP = (V, P)``, 16
    each, row-major; ``a``: the light frame's axes, 9)."""
    V, P = VP
    c0, c1, c2 = iV[2], iV[6], iV[10]
    length = math.sqrt(c0 * c0 + c1 * c1 + c2 * c2)
    v0, v1, v2 = sign * c0 / length, sign * c1 / length, sign * c2 / length
    vx, vy = v0 * a[0] + v1 * a[1] + v2 * a[2], v0 * a[3] + v1 * a[4] + v2 * a[5]
    s2 = vx * vx + vy * vy
    persp = False
    for c in range(3):
        w = P[12] * V[c] + P[13] * V[4 + c] + P[14] * V[8 + c] + P[15] * V[12 + c]
        persp = persp or abs(w) > 0
    ok = s2 > WARP_MIN_SIN * WARP_MIN_SIN and persp
    sin = math.sqrt(s2 if ok else 1.0)
    ux, uy = (vx if ok else 0.0) / sin, (vy if ok else 1.0) / sin
    r0, r1, r2 = sign * V[8], sign * V[9], sign * V[10]
    g0, g1 = r0 * a[0] + r1 * a[1] + r2 * a[2], r0 * a[3] + r1 * a[4] + r2 * a[5]
    g2 = r0 * a[6] + r1 * a[7] + r2 * a[8]
    e0, e1, e2 = iV[3], iV[7], iV[11]
    ex, ey = e0 * a[0] + e1 * a[1] + e2 * a[2], e0 * a[3] + e1 * a[4] + e2 * a[5]
    return WarpView(ux, uy, sin, g0, g1, g2, sign * V[11], -uy * ex + ux * ey,
                    ux * ex + uy * ey, ok)  # fmt: skip


def _sample_frame(lc: Row, bl: Row, a: Row) -> Row:
    """What every ray of a slice reads: the slice's corners in world coordinates (24),
    then the box's world bounds ``lo_k, hi_k`` (6), the faces' light weights
    ``c = clamp(-/+10 Z_k, 0, 1)`` (6) and ``|Z_k|`` (3), from the slice's and the box's
    corners ``lc``, ``bl`` in light coordinates (8 x 3 each)."""
    out = alloc(39)
    for k in range(3):
        ak, bk, ck = a[k], a[3 + k], a[6 + k]
        lo, hi = math.inf, -math.inf
        for i in range(8):
            out[3 * i + k] = ak * lc[3 * i] + bk * lc[3 * i + 1] + ck * lc[3 * i + 2]
            w = ak * bl[3 * i] + bk * bl[3 * i + 1] + ck * bl[3 * i + 2]
            lo, hi = min(lo, w), max(hi, w)
        out[24 + 2 * k], out[25 + 2 * k] = lo, hi
        out[30 + 2 * k] = min(max(-10.0 * ck, 0.0), 1.0)
        out[31 + 2 * k] = min(max(10.0 * ck, 0.0), 1.0)
        out[36 + k] = abs(ck)
    return out


def warp_samples(lc: Row, bl: Row, a: Row, out: Row) -> int:
    """The receiver samples of a slice (:func:`._lispsm._receivers`): for each ray of
    positive weight, ``(x, y, z, weight, slope)`` into ``out`` (5 entries each); returns
    their count. ``lc``: the slice's corners, ``bl``: the box's (8 x 3, light coordinates).
    Along a row of the grid (``b`` fixed) the rays' ends are ``A + a B``."""
    fr = _sample_frame(lc, bl, a)
    m, ab = 0, alloc(12)
    for row in range(WARP_RAYS):
        fb = (row + 0.5) / WARP_RAYS
        for h in range(6):  # A: the blend at a = 0, B: its change per unit of a
            k = 12 * (h // 3) + h % 3
            ab[h] = (1 - fb) * fr[k] + fb * fr[k + 6]
            ab[6 + h] = (1 - fb) * (fr[k + 3] - fr[k]) + fb * (fr[k + 9] - fr[k + 6])
        m = _row_samples((lc, fr), ab, fb, out, m)
    return m


def _row_samples(frame: tuple[Row, Row], ab: Row, fb: Scalar, out: Row, m: int) -> int:
    """The samples of one row of rays (``ab``: its ``A, B``; ``frame = (lc, fr)``) after
    the first ``m``; returns the new count. Along axis ``k`` a ray leaves the box through
    the face its end moves toward, at ``g_k / D_k`` (``g_k``: that face's half-space value
    at ``p_0``, ``D_k = |p_1 - p_0|``), and enters through the other, at ``-e_k / D_k``; it
    misses where it enters after it leaves (compared by products: one division a ray)."""
    lc, fr = frame
    inv_r = 1.0 / WARP_SAMPLE_RAMP
    for col in range(WARP_RAYS):
        fa = (col + 0.5) / WARP_RAYS
        g_out, d_out, k_out, miss = 1.0, 0.0, -1, False
        for k in range(3):  # the first face it leaves: least g / D, by g D' < g' D
            p0, lo, hi = ab[k] + fa * ab[6 + k], fr[24 + 2 * k], fr[25 + 2 * k]
            d = p0 - (ab[3 + k] + fa * ab[9 + k])
            g = p0 - lo if d > 0 else hi - p0
            miss = miss or (d == 0 and (p0 - lo < 0 or hi - p0 < 0))
            if d != 0 and (k_out < 0 or g * d_out < g_out * abs(d)):
                g_out, d_out, k_out = g, abs(d), k
        for k in range(3):  # entering after leaving: -e / D > g_out / d_out
            p0, lo, hi = ab[k] + fa * ab[6 + k], fr[24 + 2 * k], fr[25 + 2 * k]
            d = p0 - (ab[3 + k] + fa * ab[9 + k])
            e = hi - p0 if d > 0 else p0 - lo
            miss = miss or (d != 0 and -e * d_out > g_out * abs(d))
        if miss or k_out < 0:
            continue
        t_out = g_out / d_out
        ramp = min(max((t_out + 0.5 * WARP_SAMPLE_RAMP) * inv_r, 0.0), 1.0)
        ramp = ramp * min(max((1.0 + 0.5 * WARP_SAMPLE_RAMP - t_out) * inv_r, 0.0), 1.0)
        side = 0 if ab[k_out] + fa * ab[6 + k_out] > ab[3 + k_out] + fa * ab[9 + k_out] else 1
        face = fr[30 + 2 * k_out + side]  # toward the low face (side 0) or the high one
        if ramp * face > 0:
            cos = fr[36 + k_out]
            _store_sample(lc, (fa, fb, t_out), (ramp * face, d_out / (cos if cos > 0 else 1.0)),
                          out, m)  # fmt: skip
            m += 1
    return m


def _store_sample(
    lc: Row, at: tuple[Scalar, Scalar, Scalar], ws: tuple[Scalar, Scalar], out: Row, m: int
) -> None:
    """Sample ``m`` into ``out``: the point at ``tau`` of the ray through ``(a, b)``
    (``at = (a, b, tau)``) in light coordinates, its weight and slope (``ws``)."""
    fa, fb, t = at
    b0, b1, b2, b3 = (1 - fa) * (1 - fb), fa * (1 - fb), (1 - fa) * fb, fa * fb
    for c in range(3):
        p0 = b0 * lc[c] + b1 * lc[c + 3] + b2 * lc[c + 6] + b3 * lc[c + 9]
        p1 = b0 * lc[c + 12] + b1 * lc[c + 15] + b2 * lc[c + 18] + b3 * lc[c + 21]
        out[5 * m + c] = p0 + t * (p1 - p0)
    out[5 * m + 3], out[5 * m + 4] = ws


def _depth(vw: WarpView, x: Scalar, y: Scalar, z: Scalar) -> Scalar:
    """The view depth of a point in light coordinates."""
    return vw.g0 * x + vw.g1 * y + vw.g2 * z + vw.g3


def warp_frustum(
    vw: WarpView, body: tuple[Row, int, Row], smp: tuple[Row, int], cap: tuple[Scalar, Scalar]
) -> WarpFrustum:
    """The :class:`WarpFrustum` (:func:`._lispsm._warp`): ``body = (pts, m, bl)`` the
    body's ``m`` vertices and the box's corners, ``smp = (samples, k)`` from
    :func:`warp_samples`, ``cap = (budget, texels)``: the orthographic texel's area times
    ``m_x m_y W H``."""
    pts, m, bl = body
    tau_lo, tau_hi, z_near, z_far = math.inf, -math.inf, math.inf, -math.inf
    for i in range(m):
        x, y, z = pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]
        tau = vw.ux * x + vw.uy * y
        dz = _depth(vw, x, y, z)
        tau_lo, tau_hi = min(tau_lo, tau), max(tau_hi, tau)
        z_near, z_far = min(z_near, dz), max(z_far, dz)
    d = tau_hi - tau_lo
    z0 = bl[2]
    for i in range(8):
        z0 = min(z0, bl[3 * i + 2])
    if not (vw.ok and m > 0 and z_near > 0 and d > 0):
        return WarpFrustum(0.0, 1.0, 2.0, z0, False)
    n_opt = (z_near + math.sqrt(z_near * (z_near + d * vw.sin))) / vw.sin
    lam = max(1.0 - WARP_MIN_SIN / vw.sin, 0.0) * d / n_opt
    z_check = z_near * (z_far / z_near) ** WARP_CHECK_DEPTH
    axis = min(max((vw.eye_t + z_check * vw.sin - tau_lo) / d, 0.0), 1.0)
    sv = alloc(2 * m)
    for i in range(m):
        x, y = pts[3 * i], pts[3 * i + 1]
        sv[2 * i] = -vw.uy * x + vw.ux * y - vw.eye_s
        sv[2 * i + 1] = (vw.ux * x + vw.uy * y - tau_lo) / d
    sa = _sample_values(vw, smp, tau_lo, d)
    sx = (sa, _reference(sa, smp[1]))
    strongest, check = lam, axis
    for _ in range(WARP_ROUNDS):
        check = max(_check_loop(sx, smp[1], lam), check)
        lam = _capped_loop((sv, m), strongest, cap[0] / d, check)
    if not lam > WARP_MIN_STRENGTH:
        return WarpFrustum(0.0, 1.0, 2.0, z0, False)
    n = d / lam
    return WarpFrustum(tau_lo - n, n, n + d, z0, True)


def _sample_values(vw: WarpView, smp: tuple[Row, int], tau_lo: Scalar, d: Scalar) -> Row:
    """The samples' ``(alpha, weight, rho, rho^(1/3))`` (4 entries each,
    :func:`._lispsm._check`)."""
    buf, k = smp
    out = alloc(4 * k + 1)
    for i in range(k):
        x, y, z = buf[5 * i], buf[5 * i + 1], buf[5 * i + 2]
        dz = _depth(vw, x, y, z)
        rho = buf[5 * i + 4] / (dz * dz if dz > 0 else 1.0)
        out[4 * i], out[4 * i + 1] = (vw.ux * x + vw.uy * y - tau_lo) / d, buf[5 * i + 3]
        out[4 * i + 2], out[4 * i + 3] = rho, rho ** (1.0 / 3.0)
    return out


def _check_loop(sx: tuple[Row, Row], k: int, lam: Scalar) -> Scalar:
    """``kappa`` from the samples (``sx = (samples, Q)``: :func:`_sample_values`, ``k`` of
    them, and :func:`_reference`) at the strength ``lam`` (:func:`._lispsm._check`)."""
    sa, xq = sx
    lv = max(lam, 1e-3)
    out = 0.0
    a, wa = alloc(k + 1), alloc(k + 1)
    for c in range(len(WARP_SHARES)):
        cb = xq[c] ** (1.0 / 3.0)  # b_i^(1/3) = cb / rho_i^(1/3)
        for i in range(k):
            v = ((1.0 + lv * sa[4 * i]) * sa[4 * i + 3] / cb - 1.0) / lv
            a[i], wa[i] = min(max(v, 0.0), 1.0), sa[4 * i + 1]
        out = max(out, _quantile_loop((a, wa), k, min(WARP_SHARES[c] + WARP_SHARE_MARGIN, 1.0)))
    return out


def _reference(sa: Row, k: int) -> Row:
    """The unwarped quantiles ``Q_q`` of ``rho`` over the samples, for each ``q`` of
    :data:`WARP_SHARES` (:func:`._lispsm._check`: through ``x = rho / (rho + rho_mean)``)."""
    total, wr = 0.0, 0.0
    for i in range(k):
        total += sa[4 * i + 1]
        wr += sa[4 * i + 1] * sa[4 * i + 2]
    ref = wr / (total if total > 0 else 1.0)
    ref = ref if ref > 0 else 1.0
    xs, ws = alloc(k + 1), alloc(k + 1)
    for i in range(k):
        rho = sa[4 * i + 2]
        xs[i], ws[i] = rho / (rho + ref), sa[4 * i + 1]
    out = alloc(len(WARP_SHARES))
    for c in range(len(WARP_SHARES)):
        x = _quantile_loop((xs, ws), k, WARP_SHARES[c])
        out[c] = ref * x / (1.0 - x) if x < 1 else ref * 1e30
    return out


def _sort_pairs(a: Row, w: Row, k: int) -> None:
    """Heapsort of the first ``k`` values ``a`` (ascending), ``w`` moved along."""
    for start in range(k // 2 - 1, -1, -1):
        _sift(a, w, start, k)
    for end in range(k - 1, 0, -1):
        a[0], a[end] = a[end], a[0]
        w[0], w[end] = w[end], w[0]
        _sift(a, w, 0, end)


def _sift(a: Row, w: Row, i: int, k: int) -> None:
    """Sift entry ``i`` down the max-heap of the first ``k`` values."""
    while True:
        c = 2 * i + 1
        if c >= k:
            return
        if c + 1 < k and a[c + 1] > a[c]:
            c += 1
        if not a[c] > a[i]:
            return
        a[i], a[c] = a[c], a[i]
        w[i], w[c] = w[c], w[i]
        i = c


#: The buckets that :func:`_quantile_loop` spreads the samples over (a power of 2: a
#: sample's bucket ``floor(a B)`` is exact).
QUANTILE_BUCKETS = 32


def _quantile_loop(aw: tuple[Row, Row], k: int, share: float) -> Scalar:
    """The ``share`` quantile of ``k`` samples ``aw = (a, w)`` (values in ``[0, 1]`` and
    weights, any order) with the prior (:func:`._lispsm._quantile`): ``k*``, where
    ``C(k) + m k`` (``C(k)``: the weight of the samples ``<= k``, ``m = WARP_PRIOR``)
    first reaches ``share T``. The samples are counted into buckets of width ``1 / B``; the
    bucket where it is reached is sorted and walked."""
    a, w = aw
    nb = QUANTILE_BUCKETS
    bw, total = alloc(nb), 0.0
    for i in range(k):
        bw[min(int(a[i] * nb), nb - 1)] += w[i]
        total += w[i]
    target = share * (total + 2.0 * WARP_PRIOR)
    c, b = 0.0, 0
    while b < nb - 1 and c + bw[b] + WARP_PRIOR * ((b + 1) / nb) < target:
        c += bw[b]
        b += 1
    ga, gw = alloc(k + 1), alloc(k + 1)
    n = 0
    for i in range(k):
        if min(int(a[i] * nb), nb - 1) == b:
            ga[n], gw[n], n = a[i], w[i], n + 1
    _sort_pairs(ga, gw, n)
    lo = b / nb
    for i in range(n):
        kk = (target - c) / WARP_PRIOR
        if kk < ga[i]:
            return max(kk, lo)
        c, lo = c + gw[i], ga[i]
    return max(min((target - c) / WARP_PRIOR, 1.0), lo)


def _area_loop(sv: tuple[Row, int], lam: Scalar, check: Scalar) -> tuple[Scalar, Scalar]:
    """``A(lambda)`` and ``A'(lambda)`` (:func:`._lispsm._area`); ``sv = (values, m)``:
    each vertex's ``s`` and ``alpha``."""
    v_, m = sv
    hi, lo = -math.inf, math.inf
    for i in range(m):
        v = v_[2 * i] * (1.0 + lam) / (1.0 + lam * v_[2 * i + 1])
        hi, lo = max(hi, v), min(lo, v)
    d_hi, d_lo = -math.inf, math.inf
    for i in range(m):
        s, al = v_[2 * i], v_[2 * i + 1]
        v = s * (1.0 + lam) / (1.0 + lam * al)
        dv = s * (1.0 - al) / ((1.0 + lam * al) * (1.0 + lam * al))
        if v == hi:
            d_hi = max(d_hi, dv)
        if v == lo:
            d_lo = min(d_lo, dv)
    g, dg = (1.0 + lam) * (hi - lo), (hi - lo) + (1.0 + lam) * (d_hi - d_lo)
    k = (1.0 + lam * check) / (1.0 + lam)
    dk = (check - 1.0) / ((1.0 + lam) * (1.0 + lam))
    return g * k**3, dg * k**3 + 3.0 * g * k * k * dk


def _capped_loop(sv: tuple[Row, int], lam: Scalar, target: Scalar, check: Scalar) -> Scalar:
    """The strongest warp within the cap (:func:`._lispsm._capped`)."""
    v_, m = sv
    up, down = 0.0, 0.0
    for i in range(m):
        s = v_[2 * i]
        up, down = max(up, abs(s) + s), max(down, abs(s) - s)
    spread = 0.5 * (up + down)
    floor = math.sqrt(target / (spread if spread > 0 else target)) - 1.0
    for _ in range(NEWTON_STEPS):
        a, da = _area_loop(sv, lam, check)
        if a > target:
            step = lam - (a - target) / (da if da > 0 else math.inf)
            lam = max(step, floor)
    a, _ = _area_loop(sv, lam, check)
    return min(floor, lam) if a > target * (1.0 + 1e-9) else lam


def warp_rows(
    vw: WarpView, wp: WarpFrustum, body: tuple[Row, int], margins: tuple[float, float, float]
) -> tuple[Row, Scalar, Truth]:
    """The OpenGL clip rows over light coordinates (16), the half width ``h`` and ok
    (:func:`._lispsm._rows`); ``body = (pts, m)``, ``margins = (m_x, m_y, slack)``
    (``slack``: ``NEAR_FAR_SLACK``)."""
    pts, m = body
    lo, hi, top = math.inf, -math.inf, -math.inf
    for i in range(m):
        x, y = pts[3 * i], pts[3 * i + 1]
        t = vw.ux * x + vw.uy * y - wp.t0
        xs = (-vw.uy * x + vw.ux * y - vw.eye_s) / t
        lo, hi, top = min(lo, xs), max(hi, xs), max(top, (pts[3 * i + 2] - wp.z0) / t)
    ok = hi > lo and top > 0
    if not ok:
        lo, hi, top = -1.0, 1.0, 1.0
    h, c = 0.5 * (hi - lo), 0.5 * (hi + lo)
    a, b = -margins[2] * top, (1.0 + margins[2]) * top
    t_row = (vw.ux, vw.uy, 0.0, -wp.t0)
    s_row = (-vw.uy, vw.ux, 0.0, -vw.eye_s)
    sx, sy, sz = margins[0] / h, margins[1] / (wp.f - wp.n), 2.0 / (b - a)
    fn, k = wp.f + wp.n, -(sz * a + 1.0)
    rows = (
        sx * (s_row[0] - c * t_row[0]), sx * (s_row[1] - c * t_row[1]),
        sx * (s_row[2] - c * t_row[2]), sx * (s_row[3] - c * t_row[3]),
        sy * (fn * t_row[0]), sy * (fn * t_row[1]), sy * (fn * t_row[2]),
        sy * (fn * t_row[3] - 2.0 * wp.f * wp.n),
        k * t_row[0], k * t_row[1], sz, sz * (-wp.z0) + k * t_row[3],
        t_row[0], t_row[1], t_row[2], t_row[3],
    )  # fmt: skip
    return rows, h, ok


def warp_world(rows: Row, a: Row) -> Row:
    """Rows over light coordinates as rows over world ``(X, Y, Z, 1)`` (``l = R p``)."""
    out = alloc(16)
    for i in range(4):
        r0, r1, r2 = rows[4 * i], rows[4 * i + 1], rows[4 * i + 2]
        for j in range(3):
            out[4 * i + j] = r0 * a[j] + r1 * a[3 + j] + r2 * a[6 + j]
        out[4 * i + 3] = rows[4 * i + 3]
    return (out[0], out[1], out[2], out[3], out[4], out[5], out[6], out[7], out[8], out[9],
            out[10], out[11], out[12], out[13], out[14], out[15])  # fmt: skip


FUNCTIONS = (
    "warp_view",
    "_sample_frame",
    "warp_samples",
    "_store_sample",
    "_row_samples",
    "_depth",
    "warp_frustum",
    "_sample_values",
    "_check_loop",
    "_reference",
    "_sort_pairs",
    "_sift",
    "_quantile_loop",
    "_area_loop",
    "_capped_loop",
    "warp_rows",
    "warp_world",
)
