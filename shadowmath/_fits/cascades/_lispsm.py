r"""Light-space perspective warping (LiSPSM, Wimmer, Scherzer and Purgathofer 2004) of a cascade.

The orthographic map of a directional light spends its texels evenly over the
region it covers, while a perspective camera needs them densest near the eye.
LiSPSM inserts a perspective warp between the light's frame and the map: a
frustum in light space whose axis ``u`` is the camera's view direction projected
perpendicular to the light. Its apex sits at the distance ``n`` before the
region's nearest point along ``u``; the light's rays (along ``Z``) stay parallel
in the warped space because the warp divides by ``t``, a function of the light's
``x`` and ``y`` only. The orthographic fit is then done on the warped points.

Conventions: column vectors (``p' = M p``), light coordinates ``(x, y, z)`` of the
cascade's frame about the world origin, ``+Z`` away from the light. With ``w`` the
map's first axis (``u`` turned by +90 degrees in the light's ``XY`` plane), a point
of light coordinates ``l`` has

.. math::

    s = w \cdot l - s_e, \qquad t = u \cdot l - (\tau_0 - n), \qquad
    (x', y', d') = \Bigl(\frac{s}{t},\; \frac{f + n}{f - n} - \frac{2 f n}{(f - n)\, t},\;
    \frac{z - z_0}{t}\Bigr)

(``s_e``: the eye's ``w`` coordinate, ``tau_0``: the region's smallest ``u`` coordinate,
``f = n + d``, ``z_0``: the scene box's ``z`` nearest the light), with OpenGL clip
``w = t``: the shader divides by ``q = t``. ``n`` is Wimmer's optimum in the form of
Scherzer's and Filament's general case (derivation in ``docs/lispsm.md``):

.. math:: n_\mathrm{opt} = \frac{z_0 + \sqrt{z_0 z_1}}{\sin\gamma}, \qquad z_1 = z_0 + d \sin\gamma

with ``z_0`` the region's nearest view depth, ``d`` its extent along ``u`` and ``gamma``
the angle between the view and light directions. The warp's strength ``lambda = d / n``
is that optimum faded to 0 at the threshold, ``lambda_opt = (1 - m / sin gamma) d / n_opt``
(``m``: :data:`WARP_MIN_SIN`), and capped (:func:`_capped`) so that the warped texels are
no larger than the orthographic ones up to ``t_c = n + kappa d``: ``kappa`` is the larger of
the view axis's point at view depth ``z_0 (z_1' / z_0)^0.9`` (``[z_0, z_1']``: the region's
view depths) and the point that keeps the median and the 90th percentile of texel area per
pixel footprint from growing over the receiver samples, where the rays of a 16 x 16 grid
over the screen leave the scene box (:func:`_receivers`, :func:`_check`). Trusted inputs
only: nothing here raises except :func:`check_warp`, on the options.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np

from shadowmath._fits._spec import ShadowMapSpec, api_rows
from shadowmath._math._frustum import NEAR_FAR_SLACK
from shadowmath._math._warp_loop import (
    NEWTON_STEPS,
    WARP_CHECK_DEPTH,
    WARP_MIN_SIN,
    WARP_MIN_STRENGTH,
    WARP_PRIOR,
    WARP_RAYS,
    WARP_ROUNDS,
    WARP_SAMPLE_RAMP,
    WARP_SHARE_MARGIN,
    WARP_SHARES,
)

__all__ = ["WARP_MIN_SIN", "WARP_MIN_STRENGTH", "check_warp", "warp_cascades"]

Rows = tuple[Any, ...]


def check_warp(warp: object, stable: bool) -> None:
    """Refuse an unknown ``warp`` and ``warp="lispsm"`` with stable cascades."""
    if warp is not None and warp != "lispsm":
        raise ValueError(f"warp: expected None or 'lispsm', got {warp!r}")
    if warp is not None and stable:
        raise ValueError(
            "warp: 'lispsm' cannot be combined with stable=True: the warp follows the "
            "camera, so its texel grid cannot stay anchored and the map would shimmer "
            "(use stable=False, or warp=None)"
        )


class _View(NamedTuple):
    """The camera seen in the cascade's light frame (arrays ``(*b, 1)``)."""

    ux: Any  # the warp axis u = (ux, uy, 0), unit (safe where not ok)
    uy: Any
    sin: Any  # sin(gamma), safe (1) where not ok
    depth: tuple[Any, Any, Any, Any]  # view depth = g . l + g3 in light coordinates
    eye_s: Any  # the eye's coordinate along w = (-uy, ux, 0)
    eye_t: Any  # the eye's coordinate along u
    ok: Any  # sin(gamma) > WARP_MIN_SIN and a perspective camera


def _view(xp: Any, F: Any, cam: Any, V: Any, a: tuple[Any, ...]) -> _View:
    r"""The view direction ``v`` in light coordinates, the warp axis and the depth row.

    ``v = sign * view_to_world[:3, 2] / |.|`` (view depth grows along it); in light
    coordinates ``(X . v, Y . v, Z . v)``; ``sin(gamma) = |(X . v, Y . v)|`` and
    ``u = (X . v, Y . v) / sin(gamma)``. View depth ``sign (V_2 . p + V_23)`` of a point
    ``p = R^T l`` is ``g . l + g_3`` with ``g = sign R V_2``, ``g_3 = sign V_23``.
    """
    m = cam.view_to_world
    s = cam.sign[..., None]
    c = [m[..., i, 2][..., None] for i in range(3)]
    length = F.sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2])
    v = [s * ci / length for ci in c]
    vx, vy, _ = F.to_light(v[0], v[1], v[2], a)
    s2 = vx * vx + vy * vy
    persp = xp.max(xp.abs(cam.clip_rows[..., 3, :3]), axis=-1) > 0
    ok = (s2 > WARP_MIN_SIN * WARP_MIN_SIN) & persp[..., None]
    sin = F.sqrt(F.where(ok, s2, 1.0 + 0.0 * s2))
    ux, uy = F.where(ok, vx, 0.0 * vx) / sin, F.where(ok, vy, 1.0 + 0.0 * vy) / sin
    r = [s * V[..., 2, j][..., None] for j in range(4)]
    g = F.to_light(r[0], r[1], r[2], a)
    e = [m[..., i, 3][..., None] for i in range(3)]
    ex, ey, _ = F.to_light(e[0], e[1], e[2], a)
    return _View(ux, uy, sin, (g[0], g[1], g[2], r[3]), -uy * ex + ux * ey, ux * ex + uy * ey, ok)


class _Warp(NamedTuple):
    """The warp frustum of each cascade (arrays ``(*b, n)``, safe where not ``ok``)."""

    t0: Any  # t = u . l - t0 (t0 = tau_lo - n)
    n: Any  # near distance n_opt
    f: Any  # far distance n + d
    z0: Any  # the scene box's z nearest the light
    ok: Any


def _warp(
    xp: Any, F: Any, body: tuple[Any, ...], view: _View, cap: tuple[Any, tuple[Any, ...]]
) -> _Warp:
    r"""The warp frustum along ``u`` from the body's vertices (light coordinates).

    ``d = max(u . l) - min(u . l)`` over the vertices, ``z_0`` their smallest view depth,
    ``z_1 = z_0 + d sin(gamma)``, ``n_opt = (z_0 + sqrt(z_0 z_1)) / sin(gamma)``; the
    strength ``lambda = d / n`` is ``(1 - m / sin(gamma)) d / n_opt`` (``m``:
    :data:`WARP_MIN_SIN`) capped by :func:`_capped` at ``t_c = n + kappa d``: ``kappa`` is
    the larger of the view axis's point (:func:`_axis_check`) and the receiver samples'
    (:func:`_check`), in :data:`WARP_ROUNDS` rounds. ``cap = (budget, receivers)``: the
    orthographic texel's area times ``m_x m_y W H`` (``(*b, n)``) and :func:`_receivers`.
    Not warped (``ok`` False) where ``lambda <= WARP_MIN_STRENGTH``.
    """
    ends, ok2, _, bl = body
    inf = xp.asarray(float("inf"), dtype=ends[0].dtype)
    ux, uy = view.ux[..., None], view.uy[..., None]
    tau = ux * ends[0] + uy * ends[1]
    tau_lo = xp.min(xp.where(ok2, tau, inf), axis=-1)
    d = xp.max(xp.where(ok2, tau, -inf), axis=-1) - tau_lo
    depth = _depth(view, ends)
    z_near = xp.min(xp.where(ok2, depth, inf), axis=-1)
    ok = view.ok & xp.any(ok2, axis=-1) & (z_near > 0) & (d > 0)
    one = 1.0 + 0.0 * view.sin
    tau_lo, d, z_near = (F.where(ok, v, one) for v in (tau_lo, d, z_near))
    z1 = z_near + d * view.sin
    n_opt = (z_near + F.sqrt(z_near * z1)) / view.sin
    lam = xp.maximum(1.0 - WARP_MIN_SIN / view.sin, 0.0) * d / n_opt
    z_far = F.where(ok, xp.max(xp.where(ok2, depth, -inf), axis=-1), one)
    axis = _axis_check(xp, view, (z_near, z_far), (tau_lo, d))
    budget, (points, weights, slope) = cap
    z = _depth(view, points)
    alpha = (ux * points[0] + uy * points[1] - tau_lo[..., None]) / d[..., None]
    samples = (alpha, weights, slope / F.where(z > 0, z * z, 1.0 + 0.0 * z))
    s = -uy * ends[0] + ux * ends[1] - view.eye_s[..., None]
    vertices = (s, (tau - tau_lo[..., None]) / d[..., None], ok2 & ok[..., None])
    strongest, check = lam, axis
    for _ in range(WARP_ROUNDS):
        check = xp.maximum(_check(xp, F, samples, lam), check)
        lam = _capped(xp, F, vertices, strongest, (budget / d, check))
    ok = ok & (lam > WARP_MIN_STRENGTH)
    n = d / F.where(ok, lam, one)
    z0 = xp.min(bl[2], axis=-1)
    return _Warp(tau_lo - n, n, n + d, z0, ok)


def _depth(view: _View, points: tuple[Any, ...]) -> Any:
    """The view depth ``g . l + g_3`` of points in light coordinates (``(*b, n, m)`` each)."""
    g = view.depth
    out = g[0][..., None] * points[0] + g[1][..., None] * points[1]
    return out + g[2][..., None] * points[2] + g[3][..., None]


def _axis_check(xp: Any, view: _View, depths: tuple[Any, Any], span: tuple[Any, Any]) -> Any:
    r"""``kappa`` of the view axis's point at depth ``z_c = z_0 (z_1' / z_0)^beta``
    (``beta``: :data:`WARP_CHECK_DEPTH`, ``depths = (z_0, z_1')``): it lies at
    ``u . l = u . l_eye + z_c sin(gamma)``, so ``kappa = (u . l - tau_0) / d``, clamped to
    ``[0, 1]`` (``span = (tau_0, d)``)."""
    z_near, z_far = depths
    z_check = z_near * (z_far / z_near) ** WARP_CHECK_DEPTH
    check = (view.eye_t + z_check * view.sin - span[0]) / span[1]
    return xp.minimum(xp.maximum(check, 0.0), 1.0)


def _receivers(xp: Any, F: Any, body: tuple[Any, ...], a: tuple[Any, ...]) -> tuple[Any, ...]:
    r"""Where the pixels' rays leave the scene box in each slice: ``(points, weights)``, three
    ``(*b, n, N)`` light coordinates and ``(*b, n, N)`` weights (``N = G^2``,
    ``G``: :data:`WARP_RAYS`).

    A ray through the screen point ``(a, b)`` (cell centres of a ``G x G`` grid) meets the
    slice's near and far faces at the bilinear blends ``p_0, p_1`` of their corners, and
    ``p(tau) = p_0 + tau (p_1 - p_0)`` spans the slice's depths for ``tau`` in ``[0, 1]``.
    With the box's half-space values ``g(tau)`` (world ``p = R^T l``), the ray leaves the
    box at ``tau_out = min g_0 / (g_0 - g_1)`` over the faces it leaves through: a receiver
    the pixel may see (the ground under a box's floor). Its weight is
    ``r(tau_out) c``: ``r`` ramps over :data:`WARP_SAMPLE_RAMP` about each end of the
    slice, ``c = clamp(-10 n . L, 0, 1)`` (``n``: the face's outward normal, ``L``: toward
    the light) keeps only faces whose receiver the light can reach (not the box's top),
    and 0 where the ray misses the box.
    """
    _, _, sl, bc = body
    dtype = sl[0].dtype
    grid = (np.arange(WARP_RAYS) + 0.5) / WARP_RAYS
    fa, fb = (v.ravel() for v in np.meshgrid(grid, grid))
    corners = ((1 - fa) * (1 - fb), fa * (1 - fb), (1 - fa) * fb, fa * fb)  # i + 2 j: x, y
    blend = [xp.asarray(v, dtype=dtype) for v in corners]
    ends = [[sum(blend[c] * v[..., 4 * e + c, None] for c in range(4)) for v in sl] for e in (0, 1)]
    ax = [v[..., None] for v in a]

    def world(v: Any) -> list[Any]:
        return [ax[k] * v[0] + ax[3 + k] * v[1] + ax[6 + k] * v[2] for k in range(3)]

    p0, p1, box = world(ends[0]), world(ends[1]), world(bc)
    inf = xp.asarray(float("inf"), dtype=dtype)
    zero = 0.0 * p0[0]
    t_out, t_in, miss = inf + zero, -inf + zero, zero != zero
    face, slope = zero, zero + 1.0
    for k in range(3):
        lo, hi = xp.min(box[k], axis=-1)[..., None], xp.max(box[k], axis=-1)[..., None]
        lit = [xp.minimum(xp.maximum(sign * 10.0 * ax[6 + k], 0.0), 1.0) for sign in (-1, 1)]
        for g0, g1, c in ((p0[k] - lo, p1[k] - lo, lit[0]), (hi - p0[k], hi - p1[k], lit[1])):
            t = g0 / F.where(g0 != g1, g0 - g1, 1.0 + 0.0 * g0)
            leaves = (g1 < g0) & (t < t_out)
            t_out, face = F.where(leaves, t, t_out), F.where(leaves, c + zero, face)
            cos = xp.abs(ax[6 + k]) + zero
            slope = F.where(leaves, (g0 - g1) / F.where(cos > 0, cos, 1.0 + zero), slope)
            t_in = F.where((g1 > g0) & (t > t_in), t, t_in)
            miss = miss | ((g0 == g1) & (g0 < 0))
    hit = (t_in <= t_out) & ~miss & (t_out < inf)
    t_out = F.where(hit, t_out, 0.0 * t_out)
    r = WARP_SAMPLE_RAMP
    ramp = xp.minimum(xp.maximum((t_out + 0.5 * r) / r, 0.0), 1.0)
    ramp = ramp * xp.minimum(xp.maximum((1.0 + 0.5 * r - t_out) / r, 0.0), 1.0)
    points = [e0 + t_out * (e1 - e0) for e0, e1 in zip(ends[0], ends[1], strict=True)]
    return points, F.where(hit, ramp * face, 0.0 * ramp), slope


def _check(xp: Any, F: Any, samples: tuple[Any, Any, Any], lam: Any) -> Any:
    r"""``kappa``: where the cap checks the warped texel (``t_c = n + kappa d``), so that the
    samples' median and 90th percentile of texel area per pixel footprint do not grow.

    ``samples = (alpha, w, rho)``: each receiver sample's ``alpha``, weight and
    ``rho ~ 1 / (footprint (n . L))`` (the unwarped ratio over the cascade's texel area);
    sample ``i`` stays below the unwarped share-``q`` quantile ``Q_q`` of ``rho`` while
    ``A(t_i) <= A_o Q_q / rho_i``; with ``A(t_c) <= A_o`` and ``A ~ t^3`` that holds where
    ``t_i / t_c <= b_i^{1/3}``, ``b_i = Q_q / rho_i``, i.e. (``t = n (1 + lambda alpha)``)
    ``kappa >= alpha'_i = ((1 + lambda alpha_i) b_i^{-1/3} - 1) / lambda`` at this round's
    ``lam`` (``(*b, n)``); ``kappa`` is the largest share-``(q + WARP_SHARE_MARGIN)``
    quantile of ``alpha'`` over ``q`` in :data:`WARP_SHARES` (``Q_q`` found through
    ``x = rho / (rho + rho_mean)``, monotone and in ``[0, 1]``, by :func:`_quantile`).
    """
    alpha, w, rho = samples
    total = xp.sum(w, axis=-1, keepdims=True)
    ref = xp.sum(w * rho, axis=-1, keepdims=True) / F.where(total > 0, total, 1.0 + 0.0 * total)
    ref = F.where(ref > 0, ref, 1.0 + 0.0 * ref)
    x = rho / (rho + ref)
    lv = xp.maximum(lam, 1e-3)[..., None]
    out = 0.0 * lam
    for q in WARP_SHARES:
        xq = _quantile(xp, x, w, q)[..., None]
        b = F.where(xq < 1, ref * xq / (1.0 - xq), ref * 1e30) / rho
        a = ((1.0 + lv * alpha) / b ** (1.0 / 3.0) - 1.0) / lv
        share = min(q + WARP_SHARE_MARGIN, 1.0)
        out = xp.maximum(out, _quantile(xp, xp.minimum(xp.maximum(a, 0.0), 1.0), w, share))
    return out


def _quantile(xp: Any, alpha: Any, weights: Any, share: float) -> Any:
    r"""The ``share`` quantile of the weighted samples ``alpha`` (in ``[0, 1]``, last axis)
    with the prior :data:`WARP_PRIOR` (``m``): ``m`` spread evenly over ``[0, 1]`` and ``m``
    at 1.

    The distribution function ``Phi(k) = (C(k) + m k) / T`` (``C(k)``: the weight of the
    samples ``<= k``, ``T = W + 2 m``) rises strictly, so its inverse
    ``k* = integral_0^1 [Phi(k) < share] dk`` is continuous in the samples and weights;
    between consecutive sorted samples ``a_j <= k < a_(j+1)`` (``a_0 = 0``, ``a_(N+1) = 1``)
    ``Phi < share`` where ``k < k_j = (share T - C_j) / m``, so
    ``k* = sum_j clamp(k_j - a_j, 0, a_(j+1) - a_j)``.
    """
    order = xp.argsort(alpha, axis=-1)
    a = xp.take_along_axis(alpha, order, axis=-1)
    c = xp.cumsum(xp.take_along_axis(weights, order, axis=-1), axis=-1)
    zero = 0.0 * a[..., :1]
    lo, hi = xp.concat([zero, a], axis=-1), xp.concat([a, zero + 1.0], axis=-1)
    c = xp.concat([zero, c], axis=-1)
    total = c[..., -1:] + 2.0 * WARP_PRIOR
    k = (share * total - c) / WARP_PRIOR
    return xp.sum(xp.minimum(xp.maximum(k - lo, 0.0), hi - lo), axis=-1)


def _area(xp: Any, vertices: tuple[Any, Any, Any], lam: Any, check: Any) -> tuple[Any, Any]:
    r"""``A(lambda)`` and ``A'(lambda)``: the warped texel's area at ``t_c = n + check d``, in
    units of ``d / (m_x m_y W H)``, and its right derivative.

    With ``t_i = n + alpha_i d`` and ``c_i = f / t_i = (1 + lambda) / (1 + lambda alpha_i)``,
    ``2 f h = max_i s_i c_i - min_i s_i c_i = R`` and ``f / n = 1 + lambda``, so the texel
    at ``t = f``, ``(2 f h / (m_x W)) (f d / (m_y H n))``, is ``G d / (m_x m_y W H)`` with
    ``G = (1 + lambda) R``; the area grows like ``t^3``, so
    ``A = G k^3``, ``k = t_c / f = (1 + lambda check) / (1 + lambda)``;
    ``dc_i / dlambda = (1 - alpha_i) / (1 + lambda alpha_i)^2``.
    """
    s, alpha, valid = vertices
    inf = xp.asarray(float("inf"), dtype=s.dtype)
    lv = lam[..., None]
    v = s * (1.0 + lv) / (1.0 + lv * alpha)
    dv = s * (1.0 - alpha) / ((1.0 + lv * alpha) * (1.0 + lv * alpha))
    hi = xp.max(xp.where(valid, v, -inf), axis=-1)
    lo = xp.min(xp.where(valid, v, inf), axis=-1)
    d_hi = xp.max(xp.where(valid & (v == hi[..., None]), dv, -inf), axis=-1)
    d_lo = xp.min(xp.where(valid & (v == lo[..., None]), dv, inf), axis=-1)
    g, dg = (1.0 + lam) * (hi - lo), (hi - lo) + (1.0 + lam) * (d_hi - d_lo)
    k = (1.0 + lam * check) / (1.0 + lam)
    dk = (check - 1.0) / ((1.0 + lam) * (1.0 + lam))
    return g * k**3, dg * k**3 + 3.0 * g * k * k * dk


def _capped(xp: Any, F: Any, vertices: tuple[Any, Any, Any], lam: Any, cap: tuple[Any, Any]) -> Any:
    r"""The strongest warp ``lambda' <= lambda`` with ``A(lambda') <= target`` (:func:`_area`,
    ``cap = (target, check)``): no coarser than the orthographic map at ``t_c``.

    A warped texel's area in the plane across the light grows like ``t^3`` (the Jacobian of
    ``(s / t, -2 f n / ((f - n) t))`` is ``2 f n / ((f - n) t^3)``), so the cap holds at
    every ``t <= t_c``. ``A <= G <= (1 + lambda)^2 (max s_i^+ + max (-s_i)^+)``
    (``1 <= c_i <= 1 + lambda``), so ``lambda_c = sqrt(target / (max s^+ + max (-s)^+)) - 1``
    always satisfies it; Newton steps from ``lambda`` (where ``A > target``) go down toward
    the root, kept in ``[lambda_c, lambda]``; a result still above the target (Newton not
    converged) becomes ``lambda_c``.
    """
    s, _, valid = vertices
    target, check = cap
    spread = xp.max(xp.where(valid, xp.abs(s) + s, 0.0), axis=-1)
    spread = 0.5 * (spread + xp.max(xp.where(valid, xp.abs(s) - s, 0.0), axis=-1))
    floor = F.sqrt(target / F.where(spread > 0, spread, target)) - 1.0
    inf = xp.asarray(float("inf"), dtype=s.dtype)

    def newton(lam: Any) -> Any:
        a, da = _area(xp, vertices, lam, check)
        step = lam - (a - target) / F.where(da > 0, da, inf)
        return F.where(a > target, xp.maximum(step, floor), lam)

    lam = newton(lam)  # the first step gives lam its final shape and dtype
    if xp is np:
        for _ in range(NEWTON_STEPS - 1):
            lam = newton(lam)
    else:  # JAX: the same steps traced once (a loop, not NEWTON_STEPS copies to compile)
        from jax import lax

        lam = lax.fori_loop(1, NEWTON_STEPS, lambda _, x: newton(x), lam)
    a, _ = _area(xp, vertices, lam, check)
    return F.where(a > target * (1.0 + 1e-9), xp.minimum(floor, lam), lam)


def _rows(
    xp: Any, F: Any, body: tuple[Any, ...], view: _View, wp: _Warp, *, margins: tuple[float, float]
) -> tuple[Rows, Any, Any]:
    r"""The OpenGL clip rows in light coordinates (16 entries), the half width ``h``, and ok.

    Over the body's vertices ``x' = s / t`` spans ``[c - h, c + h]`` and
    ``d' = (z - z_0) / t`` reaches ``D``; ``y'`` spans ``[-1, 1]`` exactly. Rows
    (each ``(l_x, l_y, l_z, 1)``): ``x = m_x (s - c t) / h``,
    ``y = m_y ((f + n) t - 2 f n) / (f - n)``,
    ``z = 2 (z - z_0 - a t) / (b - a) - t`` with ``[a, b] = [-k D, (1 + k) D]``
    (``k``: ``NEAR_FAR_SLACK``), ``w = t``.
    """
    ends, ok2 = body[0], body[1]
    inf = xp.asarray(float("inf"), dtype=ends[0].dtype)
    ux, uy = view.ux[..., None], view.uy[..., None]
    t = ux * ends[0] + uy * ends[1] - wp.t0[..., None]
    valid = ok2 & wp.ok[..., None]
    t = F.where(valid, t, 1.0 + 0.0 * t)
    s = -uy * ends[0] + ux * ends[1] - view.eye_s[..., None]
    x, dz = s / t, (ends[2] - wp.z0[..., None]) / t
    one = 1.0 + 0.0 * wp.n
    lo = xp.min(xp.where(valid, x, inf), axis=-1)
    hi = xp.max(xp.where(valid, x, -inf), axis=-1)
    top = xp.max(xp.where(valid, dz, -inf), axis=-1)
    ok = wp.ok & (hi > lo) & (top > 0)
    lo, hi, top = F.where(ok, lo, -one), F.where(ok, hi, one), F.where(ok, top, one)
    h, c = 0.5 * (hi - lo), 0.5 * (hi + lo)
    a, b = -NEAR_FAR_SLACK * top, (1.0 + NEAR_FAR_SLACK) * top
    zero = 0.0 * one
    t_row = (ux[..., 0] + zero, uy[..., 0] + zero, zero, -wp.t0)
    s_row = (-uy[..., 0] + zero, ux[..., 0] + zero, zero, -view.eye_s + zero)
    sx, sy, sz = margins[0] / h, margins[1] / (wp.f - wp.n), 2.0 / (b - a)
    rows = (
        *(sx * (si - c * ti) for si, ti in zip(s_row, t_row, strict=True)),
        *(sy * ((wp.f + wp.n) * ti) for ti in t_row[:3]),
        sy * ((wp.f + wp.n) * t_row[3] - 2.0 * wp.f * wp.n),
        -(sz * a + 1.0) * t_row[0], -(sz * a + 1.0) * t_row[1], sz + zero,
        sz * (-wp.z0) - (sz * a + 1.0) * t_row[3],
        *t_row,
    )  # fmt: skip
    return rows, h, ok


def _to_world(rows: Rows, a: tuple[Any, ...]) -> Rows:
    """Rows over light coordinates ``(x, y, z, 1)`` as rows over world ``(X, Y, Z, 1)``.

    ``l = R p`` with ``R``'s rows the axes ``a``, so a row ``r`` becomes ``(r_{:3} R, r_3)``.
    """
    out: list[Any] = []
    for i in range(4):
        r = rows[4 * i : 4 * i + 4]
        out.extend(r[0] * a[j] + r[1] * a[3 + j] + r[2] * a[6 + j] for j in range(3))
        out.append(r[3])
    return tuple(out)


def warp_cascades(
    xp: Any,
    F: Any,
    body: tuple[Any, ...],
    cam: Any,
    V: Any,
    *,
    a: tuple[Any, ...],
    spec: ShadowMapSpec,
    ortho: tuple[Rows, Rows, Any],
    tile: Callable[[Rows], Rows],
) -> tuple[Rows, Rows, Any]:
    r"""Each cascade's ``world_to_clip``, ``world_to_texture`` (16 entries) and texel sizes, warped.

    Arguments:
        body: ``cascade_body(...)`` (:mod:`shadowmath._math._cascade_bounds`) of the
            cascades in the light frame ``a``: three ``(*b, n, 48)`` vertex coordinates,
            their ``(*b, n, 48)`` mask, the slices' and the box's corners.
        cam: the camera (``_cascades._WarpCamera``); ``V``: ``(*b, 4, 4)`` its view matrix;
            ``a``: the light frame's axes, 9 arrays ``(*b, 1)``.
        ortho: the orthographic cascade's clip and texture rows (texture already
            in its tile) and ``(*b, n, 2)`` texel sizes: kept where the warp falls back.
        tile: moves texture rows into the cascade's tile.

    Returns:
        ``(clip, texture, texel_size)``: where the warp applies, ``C W_gl`` and
        ``T C W_gl`` of the API (``W_gl`` the warped OpenGL clip matrix, ``q = t``), and
        the world size of one texel along the map's axes ``w`` and ``u`` at the far end
        of the warp frustum (``t = f``, the largest texel of the cascade):
        ``(2 f h / (m_x W), f (f - n) / (m_y H n))``.
    """
    view = _view(xp, F, cam, V, a)
    texels = spec.margins[0] * spec.margins[1] * spec.size[0] * spec.size[1]
    budget = ortho[2][..., 0] * ortho[2][..., 1] * texels
    wp = _warp(xp, F, body, view, (budget, _receivers(xp, F, body, a)))
    rows, h, ok = _rows(xp, F, body, view, wp, margins=spec.margins)
    gl = _to_world(rows, a)
    C, TC = api_rows(spec.api, spec.reversed_z)
    clip, tex = F.const_times(C, gl), tile(F.const_times(TC, gl))
    size_w = 2.0 * wp.f * h / (spec.margins[0] * spec.size[0])
    size_u = wp.f * (wp.f - wp.n) / (spec.margins[1] * spec.size[1] * wp.n)
    size = xp.stack([size_w, size_u], axis=-1)
    clip = tuple(F.where(ok, w, o) for w, o in zip(clip, ortho[0], strict=True))
    tex = tuple(F.where(ok, w, o) for w, o in zip(tex, ortho[1], strict=True))
    return clip, tex, F.where(ok[..., None], size, ortho[2])
