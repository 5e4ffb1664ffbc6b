"""``pcss_parameters``' driver: ``(K, d_near)`` of every map, in two forms.

:func:`scalar_maps`, a few NumPy maps through the compiled loop (float64, the ``fast``
extra) or on Python floats, and :func:`array_maps`, whole arrays (JAX, batches, an
atlas); both check the light's size with the same checks (:func:`radius_ok`,
:func:`angle_ok`) and run the formulas of :mod:`shadowmath._math._pcss`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from shadowmath._backends import _kernels
from shadowmath._boundary._validate import Array, Checks, Context, batch_shape, convert
from shadowmath._fits._backend import form
from shadowmath._fits.atlas._result import AtlasFit
from shadowmath._fits.cascades._result import Cascades
from shadowmath._fits.cube._result import CubeDepthRange
from shadowmath._math._specialize import formulas, scalar_formulas

from ._maps import BAD_CUBE, Maps, PcssFit

BAD_RADIUS = "light_radius: expected finite values >= 0"
BAD_ANGLE = "angular_radius: expected radians in [0, pi/2)"


def radius_ok(xp: Any, R: Any) -> Any:
    """``light_radius`` is valid: finite and ``>= 0`` (``xp``: ``math`` for a float, or
    an array namespace); the one check of every path."""
    return xp.isfinite(R) & (R >= 0)


def angle_ok(xp: Any, theta: Any) -> Any:
    """``angular_radius`` is valid: finite radians in ``[0, pi/2)`` (``xp`` as in
    :func:`radius_ok`); the one check of every path."""
    return xp.isfinite(theta) & (theta >= 0) & (theta < math.pi / 2)


WARPED = "fit: a warped cascade (warp='lispsm') has no constant K"


def scalar_maps(m: Maps, R: Any, theta: Any, cascades: bool) -> tuple[Array, Array]:
    """``(K, d_near)`` of a few NumPy maps, compiled by Numba (float64, the ``fast`` extra)
    or one map at a time on Python floats; raises what the checks would."""
    r = 0.0 if R is None else float(R)
    if not radius_ok(math, r):
        raise ValueError(BAD_RADIUS)
    a = 0.0 if theta is None else float(theta)
    if not angle_ok(math, a):
        raise ValueError(BAD_ANGLE)
    M, w, h = m.M, float(m.size[0]), float(m.size[1])
    batch = M.shape[:-2]
    spread = r if m.perspective else math.tan(a)
    toward = _NO_TRAVEL
    if not m.perspective:  # the frame's Z: a view of world_to_light, batch as the maps'
        t: Any = m.toward  # given with every orthographic map of this path
        toward = (t if t.shape[:-1] == batch else np.broadcast_to(t, (*batch, 3))).reshape(-1, 3)
    if form(M.dtype == np.float64) == "compiled":
        out = np.empty((*batch, 3))
        rows = M.reshape(-1, 16)
        bad = _kernels.loops().pcss_loop(rows, (w, h), spread, toward, out.reshape(-1, 3))
    else:
        F = scalar_formulas()
        out = np.empty((*batch, 3), dtype=M.dtype)
        bad = F.pcss_loop(M.reshape(-1, 16).tolist(), (w, h), spread, toward.tolist(),
                          out.reshape(-1, 3))  # fmt: skip
    if cascades and bad:
        raise ValueError(WARPED)
    return out[..., :2], out[..., 2]


#: ``toward`` of perspective maps in :func:`~shadowmath._math._pcss.pcss_loop`.
_NO_TRAVEL = np.zeros((0, 3))


def array_maps(fit: PcssFit, m: Maps, R: Any, theta: Any) -> tuple[Array, Array]:
    """``(K, d_near)`` on whole arrays (JAX, batches, an atlas); invalid entries NaN."""
    ctx, (M, toward, R, theta) = convert(
        fit=m.M, toward=m.toward, light_radius=R, angular_radius=theta
    )
    xp = ctx.xp
    checks = Checks(ctx)
    zero = ctx.constant(0.0)
    if R is not None:
        checks.require(radius_ok(xp, R), BAD_RADIUS)
    if theta is not None:
        checks.require(angle_ok(xp, theta), BAD_ANGLE)
        theta = theta[..., None] if isinstance(fit, Cascades) else theta
    R, T = (zero if R is None else R), (zero if theta is None else theta)
    shape = batch_shape(tuple(M.shape[:-2]), tuple(R.shape), tuple(T.shape),
                        names=("fit", "light_radius", "angular_radius"))  # fmt: skip
    M = xp.broadcast_to(M, (*shape, 4, 4))
    R, T = xp.broadcast_to(R, shape), xp.broadcast_to(T, shape)
    if isinstance(fit, Cascades):
        checks.require(xp.all(M[..., 3, :3] == 0, axis=-1), WARPED)
    if isinstance(fit, CubeDepthRange):
        n, f = (ctx.constant(0.0) + v for v in (fit.near, fit.far))
        checks.require((n > 0) & (f > n), BAD_CUBE)
    K, near = _terms(ctx, m._replace(M=M, toward=toward), R, T)
    if isinstance(fit, AtlasFit):  # a failed light's tiles: near = far = 0
        failed = (fit.near == 0) & (fit.far == 0)
        nan = xp.asarray(math.nan, dtype=ctx.dtype)
        K, near = xp.where(failed[..., None], nan, K), xp.where(failed, nan, near)
    if checks.invalid is not None:  # near is often a constant, whose 0 * NaN XLA folds to 0
        near = xp.where(checks.invalid, xp.asarray(math.nan, dtype=ctx.dtype), near)
    return checks.poison(K, 1), near


def _entries(A: Array) -> tuple[Array, ...]:
    return tuple(A[..., i // 4, i % 4] for i in range(16))


def _terms(ctx: Context, m: Maps, R: Array, T: Array) -> tuple[Array, Array]:
    """``(K, d_near)`` of every map: perspective, orthographic, or an atlas's mix (each
    formula on the other kind's tiles reads a harmless stand-in: no warning, finite
    gradients)."""
    xp, M, F = ctx.xp, m.M, formulas(ctx.xp)
    w, h = float(m.size[0]), float(m.size[1])
    if m.perspective is True:
        Ks, Kt, near = F.pcss_perspective(_entries(M), w, h, R)
        return xp.stack((Ks, Kt), axis=-1), xp.asarray(near, dtype=ctx.dtype)
    persp = None if m.perspective is False else xp.asarray(m.perspective)
    M_o = M if persp is None else xp.where(persp[..., None, None], ctx.constant(_BOX), M)
    sign = -1.0 if m.reversed else 1.0  # without the travel: d_near at reversed_z
    toward = (sign * M_o[..., 2, 0], sign * M_o[..., 2, 1], sign * M_o[..., 2, 2]) if (
        m.toward is None) else (m.toward[..., 0], m.toward[..., 1], m.toward[..., 2])  # fmt: skip
    Ks, Kt, near = F.pcss_orthographic(_entries(M_o), w, h, xp.tan(T), toward)
    if persp is not None:
        M_p = xp.where(persp[..., None, None], M, ctx.constant(_PYRAMID))
        ps, pt, pn = F.pcss_perspective(_entries(M_p), w, h, R)
        Ks, Kt, near = (xp.where(persp, a, b) for a, b in ((ps, Ks), (pt, Kt), (pn, near)))
    return xp.stack((Ks, Kt), axis=-1), xp.asarray(near, dtype=ctx.dtype)


#: Stand-ins for the other kind's tiles: a 90-degree frustum and a unit box.
_PYRAMID = ((1.0, 0.0, 0.0, 0.0), (0.0, 1.0, 0.0, 0.0), (0.0, 0.0, 1.0, -1.0), (0.0, 0.0, 1.0, 0.0))
_BOX = ((1.0, 0.0, 0.0, 0.0), (0.0, 1.0, 0.0, 0.0), (0.0, 0.0, 1.0, 0.0), (0.0, 0.0, 0.0, 1.0))
