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
(``m``: :data:`WARP_MIN_SIN`), and capped so that the warped texels are no larger than the
orthographic ones along the view axis up to the view depth ``z_0 (z_1' / z_0)^0.9``
(``[z_0, z_1']``: the region's view depths; :func:`_capped`). Trusted inputs only: nothing
here raises except :func:`check_warp`, on the options.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, NamedTuple

from shadowmath._math._frustum import NEAR_FAR_SLACK

from ._spec import ShadowMapSpec, api_rows

__all__ = ["WARP_MIN_SIN", "WARP_MIN_STRENGTH", "check_warp", "warp_cascades"]

#: The warp falls back to the orthographic cascade where ``sin(gamma) <= WARP_MIN_SIN``
#: (the view within about 1.15 degrees of the light's direction, either way): the
#: warp's axis ``u`` is then undefined or ill-conditioned (Filament's threshold).
WARP_MIN_SIN = 0.02

#: The cascade is not warped where the strength ``lambda = d / n`` (the warp frustum's depth
#: over its near distance) falls below this: the warp is then within about 1 % of an
#: orthographic map, and the map's rows would lose precision to ``n >> d``.
WARP_MIN_STRENGTH = 0.01

#: The warped map is no coarser than the orthographic one up to the point of the view
#: axis at view depth ``z_0 (z_1 / z_0)^WARP_CHECK_DEPTH`` (``[z_0, z_1]``: the cascade's
#: depths): chosen by the pose sweep of ``benchmarks/bench_cascades.py`` (0.85 lets the
#: median get coarser in some poses, 1 leaves almost no warp), ``docs/lispsm.md``.
WARP_CHECK_DEPTH = 0.9

#: Newton steps toward the strongest warp within the cap (:func:`_capped`).
NEWTON_STEPS = 8

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


def _warp(xp: Any, F: Any, body: tuple[Any, ...], view: _View, budget: Any) -> _Warp:
    r"""The warp frustum along ``u`` from the body's vertices (light coordinates).

    ``d = max(u . l) - min(u . l)`` over the vertices, ``z_0, z_1'`` their smallest and
    largest view depths, ``z_1 = z_0 + d sin(gamma)``,
    ``n_opt = (z_0 + sqrt(z_0 z_1)) / sin(gamma)``; the strength ``lambda = d / n`` is
    ``(1 - m / sin(gamma)) d / n_opt`` (``m``: :data:`WARP_MIN_SIN`) capped by
    :func:`_capped` at the view axis's point of depth ``z_0 (z_1' / z_0)^beta``
    (``beta``: :data:`WARP_CHECK_DEPTH`) with ``budget``, the orthographic texel's area
    times ``m_x m_y W H`` (``(*b, n)``). Not warped (``ok`` False) where
    ``lambda <= WARP_MIN_STRENGTH``.
    """
    ends, ok2, _, bl = body
    seen = xp.any(ok2, axis=-1)
    inf = xp.asarray(float("inf"), dtype=ends[0].dtype)
    tau = view.ux[..., None] * ends[0] + view.uy[..., None] * ends[1]
    g = view.depth
    depth = g[0][..., None] * ends[0] + g[1][..., None] * ends[1] + g[2][..., None] * ends[2]
    depth = depth + g[3][..., None]
    tau_lo = xp.min(xp.where(ok2, tau, inf), axis=-1)
    tau_hi = xp.max(xp.where(ok2, tau, -inf), axis=-1)
    z_near = xp.min(xp.where(ok2, depth, inf), axis=-1)
    z_far = xp.max(xp.where(ok2, depth, -inf), axis=-1)
    d = tau_hi - tau_lo
    ok = view.ok & seen & (z_near > 0) & (d > 0)
    one = 1.0 + 0.0 * view.sin
    tau_lo, d, z_near, z_far = (F.where(ok, v, one) for v in (tau_lo, d, z_near, z_far))
    # The view axis's point at depth z_c = z_0 (z_1' / z_0)^beta lies at u = u_eye + z_c sin(gamma).
    z_check = z_near * (z_far / z_near) ** WARP_CHECK_DEPTH
    check = (view.eye_t + z_check * view.sin - tau_lo) / d
    check = xp.minimum(xp.maximum(check, 0.0), 1.0)
    z1 = z_near + d * view.sin
    n_opt = (z_near + F.sqrt(z_near * z1)) / view.sin
    lam = xp.maximum(1.0 - WARP_MIN_SIN / view.sin, 0.0) * d / n_opt
    s = -view.uy[..., None] * ends[0] + view.ux[..., None] * ends[1] - view.eye_s[..., None]
    alpha = (tau - tau_lo[..., None]) / d[..., None]
    lam = _capped(xp, F, (s, alpha, ok2 & ok[..., None]), lam, (budget / d, check))
    ok = ok & (lam > WARP_MIN_STRENGTH)
    n = d / F.where(ok, lam, one)
    z0 = xp.min(bl[2], axis=-1)
    return _Warp(tau_lo - n, n, n + d, z0, ok)


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
    for _ in range(NEWTON_STEPS):
        a, da = _area(xp, vertices, lam, check)
        step = lam - (a - target) / F.where(da > 0, da, inf)
        lam = F.where(a > target, xp.maximum(step, floor), lam)
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
    wp = _warp(xp, F, body, view, ortho[2][..., 0] * ortho[2][..., 1] * texels)
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
