"""Percentage-closer soft shadows from every fit: the doors of :func:`pcss_parameters` and
:func:`pcss_widths`.

``pcss_parameters`` reads each fit's maps (:mod:`._maps`: ``world_to_texture`` and the
texture's size), checks that the light's size each map needs is given, and runs the
driver (:mod:`._driver`): on Python floats (or compiled) for a few NumPy maps (one
light's map, its cascades), on whole arrays otherwise. ``docs/pcss.md`` derives the
formulas (:mod:`shadowmath._math._pcss`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from shadowmath._boundary._shapes import ArrayLike, BoolLike, MapSize, Real
from shadowmath._boundary._validate import Checks, batch_shape, convert, is_tracer, non_finite
from shadowmath._fits._spec import ShadowMapSpec
from shadowmath._fits.cascades._result import Cascades
from shadowmath._math._pcss import kernel_widths

from ._driver import array_maps, scalar_maps
from ._maps import Maps, PcssFit, fit_maps, switch
from ._result import PcssParameters, PcssWidths

__all__ = ["PcssParameters", "PcssWidths", "pcss_parameters", "pcss_widths"]

#: At most this many NumPy maps run on Python floats (about 2 us a map).
_SCALAR_MAPS = 8


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
        K, near = scalar_maps(m, light_radius, angular_radius, cascades)
    else:
        K, near = array_maps(fit, m, light_radius, angular_radius)
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
