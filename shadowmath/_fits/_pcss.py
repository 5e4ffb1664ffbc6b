r"""Percentage-closer soft shadows from every fit: :func:`pcss_parameters`, :func:`pcss_widths`.

The door reads each fit's map (its ``world_to_texture`` and texture size), checks the
light's size, and runs the cores of :mod:`shadowmath._math._pcss`; ``docs/pcss.md``
derives them.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np

from shadowmath._api._adaptive_frustum import texel_counts
from shadowmath._api._cube_faces import face_scale
from shadowmath._boundary._shapes import ArrayLike, BoolLike, Float, MapSize, Real
from shadowmath._boundary._validate import (
    Array,
    Checks,
    Context,
    batch_shape,
    convert,
    non_finite,
)
from shadowmath._math import _cube
from shadowmath._math._frustum import OrthographicBox
from shadowmath._math._pcss import kernel_widths, orthographic_terms, perspective_terms

from ._atlas_fit import AtlasFit
from ._cascades import Cascades
from ._cube_depth import CubeDepthRange
from ._shadow_setup import ShadowSetup
from ._spec import ShadowMapSpec

__all__ = ["PcssParameters", "PcssWidths", "pcss_parameters", "pcss_widths"]

PcssFit = ShadowSetup | Cascades | AtlasFit | CubeDepthRange


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


class _Map(NamedTuple):
    """A fit's maps as the cores read them."""

    M: Array
    size: tuple[float, float]
    perspective: Any  # a Python bool, or an (*b,) NumPy bool array (an atlas's tiles)
    toward: Array | None  # the light's travel (orthographic maps), or None: see reversed
    reversed: bool = False  # an orthographic map's reversed Z where toward is None


def pcss_parameters(
    fit: PcssFit,
    *,
    light_radius: Real[ArrayLike, "*#batch"] | None = None,
    angular_radius: Real[ArrayLike, "*#batch"] | None = None,
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
        fit: a :class:`ShadowSetup` (:func:`fit_shadow`: give ``map_size``),
            :class:`Cascades` (one entry per cascade), :class:`AtlasFit` (one per tile),
            or :class:`CubeDepthRange` (every face alike: give ``map_size`` and the
            ``border_texels`` and ``reversed_z`` of :func:`cube_face_projection`).
        light_radius: ``(*batch,)`` the radius of a point or spot light (world units).
        angular_radius: ``(*batch,)`` a sun's angular radius in radians, ``[0, pi/2)``.
        map_size: the map's ``size`` or ``(width, height)`` in texels, or its
            :class:`ShadowMapSpec`: for a :class:`ShadowSetup` or a cube.
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
            a missing ``map_size``, a warped (``warp="lispsm"``) cascade, a ``reversed_z``
            the fit contradicts. Under JAX transformations the affected entries are NaN.
            An atlas tile whose light failed to fit (``near == far == 0``) is NaN.

    Example:
        >>> import numpy as np, shadowmath as sm
        >>> box = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (4, 5)], float)
        >>> fit = sm.fit_shadow([0.0, 0.0, 0.0], box, 512)
        >>> p = sm.pcss_parameters(fit, light_radius=0.1, map_size=512)
        >>> p.texels_per_depth.shape, float(p.near_depth)
        ((2,), 0.0)
    """
    rev = _switch(reversed_z)
    m = _maps(fit, map_size, border_texels, rev)
    ctx, (M, R, theta) = convert(fit=m.M, light_radius=light_radius, angular_radius=angular_radius)
    xp = ctx.xp
    checks = Checks(ctx)
    R, T = _sizes(ctx, checks, m, R, theta, isinstance(fit, Cascades))
    shape = batch_shape(tuple(M.shape[:-2]), tuple(R.shape), tuple(T.shape),
                        names=("fit", "light_radius", "angular_radius"))  # fmt: skip
    M = xp.broadcast_to(M, (*shape, 4, 4))
    R, T = xp.broadcast_to(R, shape), xp.broadcast_to(T, shape)
    if isinstance(fit, Cascades):
        flat = xp.all(M[..., 3, :3] == 0, axis=-1)
        checks.require(flat, "fit: a warped cascade (warp='lispsm') has no constant K")
    K, near = _terms(ctx, m, M, R, T)
    if isinstance(fit, AtlasFit):  # a failed light's tiles: near = far = 0
        failed = (fit.near == 0) & (fit.far == 0)
        nan = xp.asarray(math.nan, dtype=ctx.dtype)
        K, near = xp.where(failed[..., None], nan, K), xp.where(failed, nan, near)
    if rev is not None and not ctx.lazy and bool(np.any(np.asarray(near) == float(not rev))):
        raise ValueError(
            f"reversed_z: the fit's matrices store depth {'without' if rev else 'with'} reversed Z"
        )
    return PcssParameters(checks.poison(K, 1), checks.poison(near, 0))


def _terms(ctx: Context, m: _Map, M: Array, R: Array, T: Array) -> tuple[Array, Array]:
    """``(K, d_near)`` of every map: perspective, orthographic, or an atlas's mix (each
    core on the other kind's tiles reads a harmless stand-in: no warning, finite
    gradients)."""
    xp = ctx.xp
    if m.perspective is True:
        return perspective_terms(xp, M, m.size, R)
    persp = None if m.perspective is False else xp.asarray(m.perspective)
    M_o = M if persp is None else xp.where(persp[..., None, None], ctx.constant(_BOX), M)
    # without the light's travel, the one that puts d_near at reversed_z
    toward = -M_o[..., 2, :3] if m.reversed else M_o[..., 2, :3]
    toward = toward if m.toward is None else xp.broadcast_to(m.toward, toward.shape)
    K, near = orthographic_terms(xp, M_o, m.size, xp.tan(T), toward)
    if persp is None:
        return K, near
    M_p = xp.where(persp[..., None, None], M, ctx.constant(_PYRAMID))
    K_p, near_p = perspective_terms(xp, M_p, m.size, R)
    return xp.where(persp[..., None], K_p, K), xp.where(persp, near_p, near)


#: Stand-ins for the other kind's tiles: a 90-degree frustum and a unit box.
_PYRAMID = ((1.0, 0.0, 0.0, 0.0), (0.0, 1.0, 0.0, 0.0), (0.0, 0.0, 1.0, -1.0), (0.0, 0.0, 1.0, 0.0))
_BOX = ((1.0, 0.0, 0.0, 0.0), (0.0, 1.0, 0.0, 0.0), (0.0, 0.0, 1.0, 0.0), (0.0, 0.0, 0.0, 1.0))


def _switch(reversed_z: object) -> bool | None:
    if reversed_z is None or isinstance(reversed_z, bool | np.bool_):
        return None if reversed_z is None else bool(reversed_z)
    raise ValueError(f"reversed_z: expected True, False or None, got {reversed_z!r}")


def _texels(map_size: object, what: str) -> tuple[int, int]:
    """``(W, H)`` of a ``map_size`` or a spec's, which ``what`` does not record."""
    if map_size is None:
        raise ValueError(
            f"map_size: {what} does not record its texel counts: give the fit's map_size"
        )
    if isinstance(map_size, ShadowMapSpec):
        return map_size.size
    return texel_counts("map_size", map_size)


def _maps(fit: object, map_size: Any, border_texels: Any, rev: bool | None) -> _Map:
    """The maps of ``fit``: their ``world_to_texture``, texture size and kind."""
    if not isinstance(fit, CubeDepthRange) and border_texels != 0:
        raise ValueError(
            "border_texels: only a CubeDepthRange takes it (the other fits' matrices hold "
            "their borders)"
        )
    if isinstance(fit, ShadowSetup):
        size = _texels(map_size, "a ShadowSetup")
        if not isinstance(fit.frustum, OrthographicBox):
            return _Map(fit.world_to_texture, size, True, None)
        return _Map(fit.world_to_texture, size, False, fit.world_to_light[..., 2, :3])
    if isinstance(fit, Cascades | AtlasFit) and map_size is not None:
        raise ValueError(f"map_size: a {type(fit).__name__} records its texture size: leave it out")
    if isinstance(fit, Cascades):
        return _Map(fit.world_to_texture, fit.texture_size, False, fit.world_to_light[..., 2, :3])
    if isinstance(fit, AtlasFit):
        return _atlas_maps(fit, rev)
    if isinstance(fit, CubeDepthRange):
        return _cube_maps(fit, map_size, border_texels, bool(rev))
    raise ValueError(
        "fit: expected a ShadowSetup, Cascades, AtlasFit or CubeDepthRange, "
        f"got {type(fit).__name__}"
    )


def _atlas_maps(fit: AtlasFit, rev: bool | None) -> _Map:
    """An atlas's tiles: perspective where ``q`` varies; ``reversed_z`` given or read from
    its perspective tiles (``beta > 0`` reversed), needed for its directional ones."""
    M = np.asarray(fit.world_to_texture)
    persp = np.any(M[:, 3, :3] != 0, axis=-1)
    fitted = ~((np.asarray(fit.near) == 0) & (np.asarray(fit.far) == 0))
    if rev is None and bool(np.any(~persp & fitted)):
        shown = persp & fitted
        if not shown.any():
            raise ValueError(
                "reversed_z: an atlas of directional lights only does not show its depth "
                "direction: give fit_atlas's reversed_z"
            )
        _, near = perspective_terms(np, M[shown], (1.0, 1.0), np.ones(int(shown.sum())))
        rev = bool(near[0] == 1)
    return _Map(fit.world_to_texture, fit.texture_size, persp, None, bool(rev))


def _cube_maps(fit: CubeDepthRange, map_size: Any, border_texels: Any, rev: bool) -> _Map:
    """A cube face's ``world_to_texture`` (every face has the same ``K``): face ``+x``
    of a light at the origin, depth in ``[0, 1]``."""
    if map_size is None:
        raise ValueError(
            "map_size: a CubeDepthRange does not record its texel counts: give the faces' map_size"
        )
    k = face_scale(map_size, border_texels)
    ctx, (n, f) = convert(near=fit.near, far=fit.far)
    xp = ctx.xp
    P = _cube.cube_face_projection(xp, n, f, k, zero_to_one=True, flip_y=False, reversed_z=rev)
    T = ctx.constant(
        ((0.5, 0.0, 0.0, 0.5), (0.0, 0.5, 0.0, 0.5), (0.0, 0.0, 1.0, 0.0), (0.0, 0.0, 0.0, 1.0))
    )
    N = float(map_size)
    return _Map(T @ P, (N, N), True, None)


def _sizes(
    ctx: Context, checks: Checks, m: _Map, R: Array | None, theta: Array | None, cascades: bool
) -> tuple[Array, Array]:
    """The light's radius and the sun's angular radius, checked (zero where not used)."""
    xp = ctx.xp
    persp = np.asarray(m.perspective)
    needs = (bool(persp.any()), not bool(persp.all()))
    named = (
        ("light_radius", R, needs[0], "a point or spot light's", "angular_radius"),
        ("angular_radius", theta, needs[1], "a directional light's", "light_radius"),
    )
    for name, given, need, kind, other in named:  # the wrong size first: it says which
        if given is not None and not need:
            raise ValueError(f"{name}: the fit has no {kind} map (give {other})")
    for name, given, need, kind, _ in named:
        if given is None and need:
            raise ValueError(f"{name}: {kind} map needs it")
    if R is not None:
        checks.require(xp.isfinite(R) & (R >= 0), "light_radius: expected finite values >= 0")
    if theta is not None:
        ok = xp.isfinite(theta) & (theta >= 0) & (theta < math.pi / 2)
        checks.require(ok, "angular_radius: expected radians in [0, pi/2)")
        theta = theta[..., None] if cascades else theta
    zero = ctx.constant(0.0)
    return (zero if R is None else R), (zero if theta is None else theta)


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
