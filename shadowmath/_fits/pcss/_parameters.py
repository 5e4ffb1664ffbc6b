r"""Percentage-closer soft shadows from every fit: :func:`pcss_parameters`, :func:`pcss_widths`.

The door reads each fit's maps (:mod:`._pcss_maps`: ``world_to_texture`` and the texture's
size), checks the light's size, and runs the formulas of :mod:`shadowmath._math._pcss`: on
Python floats for a few NumPy maps (one light's map, its cascades), on whole arrays
otherwise. ``docs/pcss.md`` derives them.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np

from shadowmath._backends import _kernels
from shadowmath._boundary._shapes import ArrayLike, BoolLike, Float, MapSize, Real
from shadowmath._boundary._validate import (
    Array,
    Checks,
    Context,
    batch_shape,
    convert,
    is_tracer,
    non_finite,
)
from shadowmath._fits._backend import form
from shadowmath._fits._spec import ShadowMapSpec
from shadowmath._fits.atlas._fit import AtlasFit
from shadowmath._fits.cascades._fit import Cascades
from shadowmath._fits.cube._depth_range import CubeDepthRange
from shadowmath._math._pcss import kernel_widths
from shadowmath._math._specialize import formulas, scalar_formulas

from ._maps import BAD_CUBE, Maps, PcssFit, fit_maps, switch

__all__ = ["PcssParameters", "PcssWidths", "pcss_parameters", "pcss_widths"]

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

#: At most this many NumPy maps run on Python floats (about 2 us a map).
_SCALAR_MAPS = 8


class PcssParameters(NamedTuple):
    """What a PCSS shader needs of one shadow map (:func:`pcss_parameters`).

    Attributes:
        texels_per_depth: ``(*maps, 2)`` ``K``: the blocker search radius and the penumbra
            width in texels (along the texture's ``s`` and ``t``) per unit of stored depth.
        near_depth: ``(*maps,)`` ``d_near``: the depth stored at the map's near plane, 0
            (or 1 with reversed Z): no caster is nearer the light.
    """

    texels_per_depth: Float[Array, "*maps 2"]
    near_depth: Float[Array, "*maps"]


class PcssWidths(NamedTuple):
    """The blocker search radius and the penumbra width in texels (:func:`pcss_widths`).

    Attributes:
        search: ``(*batch, 2)`` the blocker search radius along ``s`` and ``t``: the light
            as the receiver sees it, on the near plane (the light's size in texels at the
            receiver's depth).
        penumbra: ``(*batch, 2)`` the penumbra's half-width (the PCF filter's radius).
    """

    search: Float[Array, "*batch 2"]
    penumbra: Float[Array, "*batch 2"]


def pcss_parameters(
    fit: PcssFit,
    *,
    light_radius: Real[ArrayLike, "*#lights"] | None = None,
    angular_radius: Real[ArrayLike, "*#lights"] | None = None,
    map_size: MapSize | ShadowMapSpec | None = None,
    border_texels: int = 0,
    reversed_z: BoolLike | None = None,
) -> PcssParameters:
    r"""The texels per unit of stored depth ``K`` and the near plane's depth of PCSS.

    A light disk of radius ``R`` facing the map's axis (a point or spot light; each
    cube face) or a sun of angular radius ``theta`` (a directional map, each cascade)
    casts, by similar triangles, a penumbra of half-width

    .. math::

        w = R \left(\frac{1}{z_B} - \frac{1}{z_R}\right) s \quad\text{(perspective)},
        \qquad w = \frac{\tan\theta\,(z_R - z_B)}{h} \quad\text{(orthographic)}

    texels (``s`` texels per unit of ``x / z``, ``h`` a texel's world size). A
    perspective map stores ``d = a + b / z``, an orthographic one ``d`` affine in ``z``,
    so both are ``K (d_R - d_B)`` with ``K = R s / |b|`` or ``tan(theta) (f - n) / h``
    per axis, and the blocker search (the light seen from the receiver, on the near
    plane) is ``K |d_R - d_near|``. A shader needs ``K`` and ``d_near`` only::

        search = K * abs(dR - dNear);  penumbra = K * max(sign * (dR - dBlocker), 0)

    with ``sign = 1 - 2 dNear`` (:func:`pcss_widths` computes both; ``docs/pcss.md``).
    ``K`` is the same world penumbra in every cascade, tile and face.

    Arguments:
        fit: a :class:`ShadowSetup` (:func:`fit_shadow`'s records its map size),
            :class:`Cascades` (one entry per cascade), :class:`AtlasFit` (one per tile),
            or :class:`CubeDepthRange` (every face alike: give ``map_size`` and the
            ``border_texels`` and ``reversed_z`` of :func:`cube_face_projection`).
        light_radius: ``(*lights,)`` the radius of a point or spot light (world units).
        angular_radius: ``(*lights,)`` a sun's angular radius in radians, ``[0, pi/2)``.
        map_size: the map's ``size`` or ``(width, height)`` in texels, or its
            :class:`ShadowMapSpec`: for a cube, or a :class:`ShadowSetup` that does not
            record its size (made by hand). Given for a setup that records one, it must
            be that size.
        border_texels: a cube face's border ring.
        reversed_z: a cube's, or an atlas's of directional lights only (the other fits
            show it in their matrices; given anyway, it must agree).

    Returns:
        :class:`PcssParameters` ``(texels_per_depth (*maps, 2), near_depth (*maps,))``:
        ``*maps`` is the fit's batch broadcast with the sizes' (``(*batch, n)`` for
        cascades, whose sizes are per light ``(*batch,)``; ``(T,)`` for an atlas).

    Raises:
        ValueError: a negative or non-finite size, an angular radius outside
            ``[0, pi/2)``, the wrong size for the light (``light_radius`` for a
            directional map, ``angular_radius`` for a perspective one, neither given),
            a missing ``map_size``, a ``map_size`` other than the one the fit records,
            a warped (``warp="lispsm"``) cascade, a ``reversed_z``
            the fit contradicts. Under JAX transformations the affected entries are NaN.
            An atlas tile whose light failed to fit (``near == far == 0``) is NaN.

    Example:
        >>> import numpy as np, shadowmath as sm
        >>> box = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (4, 5)], float)
        >>> fit = sm.fit_shadow([0.0, 0.0, 0.0], box, 512)
        >>> p = sm.pcss_parameters(fit, light_radius=0.1)  # the fit records its 512x512
        >>> p.texels_per_depth.shape, float(p.near_depth)
        ((2,), 0.0)
    """
    rev = switch(reversed_z)
    m = fit_maps(fit, map_size, border_texels, rev)
    _require_sizes(m, light_radius, angular_radius)
    cascades = type(fit) is Cascades
    if _few(m, light_radius, angular_radius):
        K, near = _scalar_maps(m, light_radius, angular_radius, cascades)
    else:
        K, near = _array_maps(fit, m, light_radius, angular_radius)
    if rev is not None and not is_tracer(near) and bool(np.any(np.asarray(near) == float(not rev))):
        raise ValueError(
            f"reversed_z: the fit's matrices store depth {'without' if rev else 'with'} reversed Z"
        )
    return PcssParameters(K, near)


def _require_sizes(m: Maps, R: Any, theta: Any) -> None:
    """The size each map's light needs is given, and no other."""
    persp = m.perspective
    if isinstance(persp, bool):
        needs = (persp, not persp)
    else:
        needs = (bool(persp.any()), not bool(persp.all()))
    named = (
        ("light_radius", R, needs[0], "a point or spot light's", "the light's radius"),
        ("angular_radius", theta, needs[1], "a directional light's", "the sun's angular radius"),
    )
    for i, (name, given, need, _, what) in enumerate(named):  # the wrong size first
        if given is not None and not need:
            other, other_given, _, kind, other_what = named[1 - i]
            raise ValueError(
                f"{name}: the fit's maps are all {kind}, which take {other_what} "
                f"({other}), not {what}; give {other} "
                f"{'only' if other_given is not None else 'instead'}"
            )
    for name, given, need, kind, what in named:
        if given is None and need:
            raise ValueError(f"{name}: the fit has {kind} map, which needs {what}: give {name}")


#: The sizes the Python-float path takes as they are (no bool: it is an int).
_NUMBERS = (float, int, np.float64, np.float32, np.int64, type(None))


def _few(m: Maps, R: Any, theta: Any) -> bool:
    """A few NumPy maps of one kind and sizes given as numbers: the Python-float path."""
    M = m.M
    return (
        type(M) is np.ndarray
        and M.dtype.char in "fd"
        and M.size <= 16 * _SCALAR_MAPS
        and type(m.perspective) is bool
        and (m.toward is None or type(m.toward) is np.ndarray)
        and type(R) in _NUMBERS
        and type(theta) in _NUMBERS
    )


def _scalar_maps(m: Maps, R: Any, theta: Any, cascades: bool) -> tuple[Array, Array]:
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


def _array_maps(fit: PcssFit, m: Maps, R: Any, theta: Any) -> tuple[Array, Array]:
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


def pcss_widths(
    parameters: PcssParameters,
    receiver_depth: Real[ArrayLike, "*#batch"],
    blocker_depth: Real[ArrayLike, "*#batch"],
) -> PcssWidths:
    r"""The blocker search radius and the penumbra width in texels, as a PCSS shader
    computes them from :func:`pcss_parameters` and the stored depths.

    .. math::

        \mathrm{search} = K\,|d_R - d_\mathrm{near}|, \qquad
        \mathrm{penumbra} = K \max(\sigma (d_R - d_B), 0), \quad \sigma = 1 - 2 d_\mathrm{near}

    Arguments:
        parameters: :class:`PcssParameters` of the maps, fields ``(*maps, 2)`` and
            ``(*maps,)``, broadcasting with the depths' ``*batch``.
        receiver_depth: ``(*batch,)`` ``d_R``, the receiver's depth as the map stores it
            (``r`` of ``world_to_texture``).
        blocker_depth: ``(*batch,)`` ``d_B``, the blockers' average depth found by the search.

    Returns:
        :class:`PcssWidths` ``(search, penumbra)``, each ``(*batch, 2)`` texels along ``s``
        and ``t``.

    Raises:
        ValueError: wrong shapes or non-finite depths (NaN under JAX transformations).

    Example:
        >>> p = PcssParameters(np.array([8.0, 4.0]), np.array(0.0))
        >>> w = pcss_widths(p, 0.75, 0.5)
        >>> w.search.tolist(), w.penumbra.tolist()
        ([6.0, 3.0], [2.0, 1.0])
    """
    if not isinstance(parameters, PcssParameters):
        raise ValueError(f"parameters: expected PcssParameters, got {type(parameters).__name__}")
    ctx, (K, near, dR, dB) = convert(
        parameters=parameters.texels_per_depth, near_depth=parameters.near_depth,
        receiver_depth=receiver_depth, blocker_depth=blocker_depth,
    )  # fmt: skip
    xp = ctx.xp
    shapes = (tuple(K.shape[:-1]), tuple(near.shape), tuple(dR.shape), tuple(dB.shape))
    names = ("parameters", "parameters", "receiver_depth", "blocker_depth")
    shape = batch_shape(*shapes, names=names)
    checks = Checks(ctx)
    checks.require(xp.isfinite(dR), non_finite("receiver_depth"))
    checks.require(xp.isfinite(dB), non_finite("blocker_depth"))
    b = (xp.broadcast_to(v, shape) for v in (near, dR, dB))
    search, penumbra = kernel_widths(xp, xp.broadcast_to(K, (*shape, 2)), *b)
    return PcssWidths(checks.poison(search, 1), checks.poison(penumbra, 1))
