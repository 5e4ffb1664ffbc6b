"""Depth bias at the door: a texel's world size, the slope-scaled bias and the normal
offset (argument checks; the gradients and formulas are :mod:`shadowmath._math._bias`'s)."""

from __future__ import annotations

import math
from types import ModuleType
from typing import Any

import numpy as np

from shadowmath._boundary._renamed import renamed_keywords
from shadowmath._boundary._shapes import ArrayLike, Float, IntLike, MapSize, Real
from shadowmath._boundary._validate import (
    Array,
    Checks,
    all_finite,
    batch_shape,
    convert,
    non_finite,
    require_last,
    require_matrix,
)
from shadowmath._math import _bias
from shadowmath._math._bias import DEFAULT_CONSTANT_BIAS, PcfFilter
from shadowmath._math._vector import cross, dot


def _map_size(map_size: object) -> tuple[int, int]:
    """``(W, H)`` from ``size`` or ``(width, height)``; ``ValueError`` otherwise."""
    sizes = list(map_size) if isinstance(map_size, tuple | list) else [map_size, map_size]
    ints = [int(v) for v in sizes if isinstance(v, int | np.integer) and not isinstance(v, bool)]
    if len(sizes) != 2 or len(ints) != 2 or min(ints) < 1:
        raise ValueError(
            f"map_size: expected an integer >= 1 or (width, height) of them, got {map_size!r}"
        )
    return ints[0], ints[1]


def check_kernel(
    radius: object, filter: object, names: tuple[str, str] = ("pcf_radius", "pcf_filter")
) -> tuple[int, PcfFilter]:
    """The kernel checked; ``names`` are the caller's argument names for the messages."""
    if not isinstance(radius, int | np.integer) or isinstance(radius, bool) or radius < 0:
        raise ValueError(f"{names[0]}: expected an integer >= 0, got {radius!r}")
    if filter == "box" or filter == "bilinear":
        return int(radius), filter
    raise ValueError(f"{names[1]}: expected 'box' or 'bilinear', got {filter!r}")


def _prepare(
    world_to_texture: Any, points: Any, normals: Any
) -> tuple[Checks, ModuleType, Array, Array, Array | None, tuple[int, ...]]:
    """Convert once, check shapes and values; unit normals (``None`` stays ``None``)."""
    ctx, (M, p, n) = convert(world_to_texture=world_to_texture, points=points, normals=normals)
    xp = ctx.xp
    require_matrix("world_to_texture", M)
    require_last("points", p, 3)
    shapes = [tuple(M.shape[:-2]), tuple(p.shape[:-1])]
    names = ["world_to_texture", "points"]
    if n is not None:
        require_last("normals", n, 3)
        shapes.append(tuple(n.shape[:-1]))
        names.append("normals")
    shape = batch_shape(*shapes, names=names)
    checks = Checks(ctx)
    checks.require(all_finite(xp, M, 2), non_finite("world_to_texture"))
    checks.require(all_finite(xp, p, 1), non_finite("points"))
    q = xp.sum(M[..., 3, :3] * p, axis=-1) + M[..., 3, 3]
    checks.require(q > 0, "points: a receiver point is at or behind the light (q <= 0)")
    # (Invalid entries are computed anyway, then poisoned: the batch entries are
    # independent, so their NaNs reach neither the valid values nor their derivatives.)
    gs, gt, _ = _bias.texture_gradients(xp, M, p)
    D = cross(xp, gs, gt)
    checks.require(
        xp.max(xp.abs(D), axis=-1) > 0,  # not D . D: its square leaves float32's range
        "world_to_texture: s and t do not vary across the ray there (a singular matrix)",
    )
    unit_n = None
    if n is not None:
        checks.require(all_finite(xp, n, 1), non_finite("normals"))
        n_sq = dot(xp, n, n)
        checks.require(n_sq > 0, "normals: a normal is zero")
        unit_n = n / xp.sqrt(xp.where(n_sq > 0, n_sq, xp.ones_like(n_sq)))[..., None]
    p_b = xp.broadcast_to(p, (*shape, 3))
    M_b = xp.broadcast_to(M, (*shape, 4, 4))
    n_b = None if unit_n is None else xp.broadcast_to(unit_n, (*shape, 3))
    return checks, xp, M_b, p_b, n_b, shape


def texel_world_size(
    world_to_texture: Real[ArrayLike, "*#batch 4 4"],
    points: Real[ArrayLike, "*#batch 3"],
    *,
    map_size: MapSize,
    normals: Real[ArrayLike, "*#batch 3"] | None = None,
) -> Float[Array, "*batch"]:
    r"""The world-space size of one shadow-map texel at receiver points.

    Without ``normals``: the texel's width **across the light ray**, the side of
    a square of the area the texel covers on the plane perpendicular to the ray
    through the point,

    .. math:: h_\perp = \frac{1}{\sqrt{W H \, |\nabla s \times \nabla t|}}

    (``grad s x grad t`` is parallel to the ray, and ``|grad s x grad t|`` the
    Jacobian of ``(s, t)`` on that plane). This is the quantity that normal offsets
    and slope-scaled biases are made of: for a point or spot light it grows
    linearly with the distance to the light, for a directional light it is the
    map's extent over its resolution everywhere. With ``normals``: the size on the
    receiver surface itself, ``1 / sqrt(W H |(grad s x grad t) . n|)``
    (:func:`receiver_texel_size`), which is ``h_perp / sqrt(cos theta)``, infinite
    where the surface is seen edge-on.

    Arguments:
        world_to_texture: ``(*batch, 4, 4)`` world to ``(s q, t q, r q, q)``
            (any :func:`api_convention`; perspective or affine).
        points: ``(*batch, 3)`` receiver points in front of the light (``q > 0``).
        map_size: ``size`` or ``(width, height)`` in texels.
        normals: optional ``(*batch, 3)`` surface normals (need not be unit).

    Returns:
        ``(*batch,)`` lengths in world units.

    Raises:
        ValueError: wrong shapes, non-finite values, a point at or behind the
            light, a singular ``world_to_texture``, a zero normal, a bad
            ``map_size`` (NaN under JAX transformations, except shapes and sizes).

    Example:
        >>> import numpy as np
        >>> # A directional light down -z, a 10 x 10 world-unit map of 100 texels
        >>> M = np.array([[0.1, 0, 0, 0.5], [0, 0.1, 0, 0.5], [0, 0, -0.1, 0], [0, 0, 0, 1]])
        >>> float(texel_world_size(M, [1.0, 2.0, -3.0], map_size=100))
        0.1
    """
    W, H = _map_size(map_size)
    checks, xp, M, p, n, _ = _prepare(world_to_texture, points, normals)
    size = (
        _bias.texel_size(xp, M, p, (W, H))
        if n is None
        else _bias.texel_size_on_surface(xp, M, p, n, (W, H))
    )
    return checks.poison(xp.asarray(size), 0)


@renamed_keywords(radius="pcf_radius", filter="pcf_filter")
def slope_scaled_bias(
    world_to_texture: Real[ArrayLike, "*#batch 4 4"],
    points: Real[ArrayLike, "*#batch 3"],
    normals: Real[ArrayLike, "*#batch 3"],
    *,
    map_size: MapSize,
    pcf_radius: IntLike = 0,
    pcf_filter: PcfFilter = "box",
    slope_factor: float | None = None,
    constant: float = DEFAULT_CONSTANT_BIAS,
    depth_bits: IntLike | None = 24,
) -> Float[Array, "*batch"]:
    r"""The polygon-offset depth bias: ``constant * r_min + slope_factor * m``, in depth units.

    ``m = max(|dr/dx|, |dr/dy|)`` is the receiver's depth slope per texel (``r``
    the stored depth of :func:`api_convention`, ``x, y`` in texels), as in
    ``glPolygonOffset(factor, units)`` / Direct3D's ``SlopeScaledDepthBias`` and
    ``DepthBias``. On the receiver's tangent plane

    .. math::

        \frac{\partial r}{\partial s} = \frac{\nabla r \cdot (\nabla t \times n)}
            {(\nabla s \times \nabla t) \cdot n}, \qquad
        \frac{\partial r}{\partial t} = \frac{\nabla r \cdot (n \times \nabla s)}
            {(\nabla s \times \nabla t) \cdot n}, \qquad
        m = \max\left(\frac{1}{W}\left|\frac{\partial r}{\partial s}\right|,
            \frac{1}{H}\left|\frac{\partial r}{\partial t}\right|\right).

    On a planar receiver the depth ``r`` is exactly affine in the texel coordinates
    (for perspective maps too: that is why depth interpolates linearly across a
    triangle in window space), so a point ``(a, b)`` texels away from a texel
    centre differs from the depth stored there by ``|a dr/dx + b dr/dy| <= (|a| + |b|) m``.
    A lookup that compares texel centres up to ``c`` texels away per axis (``c =
    1/2`` for one nearest sample, ``k + 1/2`` for a box kernel of radius ``k``,
    ``k + 1`` for a bilinear one) is free of acne on planes when
    ``slope_factor >= 2 c``: the default (``1`` without PCF, ``2 k + 1`` box,
    ``2 k + 2`` bilinear). In world units along the ray a directional light's slope
    is ``m (f - n) = h_perp tan(theta)`` (``theta`` between normal and ray), so the
    bias grows without bound at grazing angles: clamp it (Direct3D's
    ``DepthBiasClamp``) or prefer :func:`normal_offset` there.

    Too small: acne (stripes of self-shadow on lit surfaces). Too large:
    "peter-panning", shadows detached from their casters' contact points, and light
    leaking through thin casters. Use either the result as a per-point value
    (compare ``r - bias`` with the stored depth; ``r + bias`` with ``reversed_z``) or
    ``slope_factor`` and ``constant`` as the polygon offset's factor and units while
    drawing the map (negated with ``reversed_z``).

    Arguments:
        world_to_texture: ``(*batch, 4, 4)`` world to ``(s q, t q, r q, q)``.
        points: ``(*batch, 3)`` receiver points in front of the light.
        normals: ``(*batch, 3)`` their surface normals (need not be unit).
        map_size: ``size`` or ``(width, height)`` in texels.
        pcf_radius: the PCF kernel radius the lookup uses (sets the default
            ``slope_factor``; ``radius=``, deprecated).
        pcf_filter: ``"box"`` or ``"bilinear"``, the PCF filter (same; ``filter=``,
            deprecated).
        slope_factor: the factor of ``m``; ``None`` for the derived minimum above.
        constant: the factor of ``r_min`` (default 2).
        depth_bits: the bits of a fixed-point depth buffer, ``r_min = 1 / (2^bits - 1)``
            (16 or 24); ``None`` for a float32 depth buffer, where ``r_min`` is taken
            as ``2^-24`` (the resolution near depth ``1``; Direct3D uses the exponent
            of the primitive's largest depth).

    Returns:
        ``(*batch,)`` biases in depth units (``inf`` where the surface is edge-on).

    Raises:
        ValueError: as :func:`texel_world_size`, plus a zero normal and a bad
            ``pcf_radius``, ``pcf_filter``, ``slope_factor``, ``constant`` or ``depth_bits``.

    Example:
        >>> import numpy as np
        >>> M = np.array([[0.1, 0, 0, 0.5], [0, 0.1, 0, 0.5], [0, 0, -0.1, 0], [0, 0, 0, 1]])
        >>> # A floor tilted by 45 degrees under a directional light along -z:
        >>> # per texel (0.1 world units) the depth changes by 0.1 * tan 45 = 0.1 world
        >>> # units, 0.01 in depth units (depth range 10).
        >>> b = slope_scaled_bias(M, [0.0, 0.0, -3.0], [1.0, 0.0, 1.0], map_size=100, constant=0)
        >>> round(float(b), 12)
        0.01
    """
    W, H = _map_size(map_size)
    k, filt = check_kernel(pcf_radius, pcf_filter)
    factor = 2 * _bias.kernel_reach(k, filt) if slope_factor is None else slope_factor
    if not (isinstance(factor, int | float) and math.isfinite(factor) and factor >= 0):
        raise ValueError(f"slope_factor: expected a finite number >= 0, got {slope_factor!r}")
    if not (isinstance(constant, int | float) and math.isfinite(constant) and constant >= 0):
        raise ValueError(f"constant: expected a finite number >= 0, got {constant!r}")
    if depth_bits is None:
        r_min = 2.0**-24
    elif isinstance(depth_bits, int) and not isinstance(depth_bits, bool) and 1 <= depth_bits <= 32:
        r_min = 1.0 / (2.0**depth_bits - 1)
    else:
        raise ValueError(f"depth_bits: expected an integer 1..32 or None, got {depth_bits!r}")
    if normals is None:
        raise ValueError("normals: required (the slope is along the receiver's surface)")
    checks, xp, M, p, n, _ = _prepare(world_to_texture, points, normals)
    bias = _bias.slope_scaled_bias(
        xp, M, p, n, (W, H), constant=float(constant), slope_factor=float(factor),
        depth_resolution=r_min,
    )  # fmt: skip
    return checks.poison(xp.asarray(bias), 0)


@renamed_keywords(radius="pcf_radius", filter="pcf_filter")
def normal_offset(
    world_to_texture: Real[ArrayLike, "*#batch 4 4"],
    points: Real[ArrayLike, "*#batch 3"],
    normals: Real[ArrayLike, "*#batch 3"],
    *,
    map_size: MapSize,
    pcf_radius: IntLike = 0,
    pcf_filter: PcfFilter = "box",
    scale: float = 1.0,
) -> Float[Array, "*batch 3"]:
    r"""The world-space normal offset: look the map up at ``points + normal_offset(...)``.

    .. math::

        o = \hat n \; \mathrm{scale} \; c \;
            \frac{|\nabla r \cdot a_s| + |\nabla r \cdot a_t|}{|\nabla r \cdot \hat d|},
        \qquad
        a_s = \frac{\nabla t \times \hat n}{W\,|D|}, \quad
        a_t = \frac{\hat n \times \nabla s}{H\,|D|}, \quad D = \nabla s \times \nabla t,

    with ``d`` the light ray (along ``D``) and ``c`` the reach of the lookup in
    texels per axis (``1/2`` without PCF, ``k + 1/2`` for a box kernel of radius
    ``k``, ``k + 1`` bilinear). For a directional light (``grad r`` along the ray)
    this is ``c (|n . v_s| + |n . v_t|)`` with ``v_s``, ``v_t`` the texel's edges
    across the ray: for a square texel of size ``h`` (:func:`texel_world_size`)
    ``c h sin(theta) (|cos phi| + |sin phi|) <= sqrt(2) c h sin(theta)``, the
    engines' ``k * texel * sqrt(1 - (n . l)^2)`` with ``k = sqrt(2) c`` in its worst
    direction ``phi`` (texel diagonals), and exactly what each direction needs.

    Derivation, for a planar receiver: on the plane the stored depth ``r`` is
    affine in the texel coordinates, with per-texel slopes ``grad r . a_s`` and
    ``grad r . a_t`` (``a_s`` is the step along the plane with ``ds = 1/W, dt = 0``,
    divided by ``cos theta``), so a texel centre the lookup compares with, up to
    ``c`` texels away per axis, holds a depth up to ``c (|grad r . a_s| + |grad r .
    a_t|) / cos(theta)`` nearer to the light. Lifting the lookup point by ``o`` along
    the normal moves it ``o / cos(theta)`` along its ray in front of the plane, which
    is ``|grad r . d| o / cos(theta)`` in depth: the ``cos(theta)`` cancel, which is
    why the offset stays bounded at grazing angles where a depth bias
    (``tan theta``) does not. ``scale = 1`` is the exact minimum for a directional
    light; for point and spot lights it is exact to first order in the texel's
    angular size (their depth is planar distance, not distance along the ray,
    which the formula takes into account through ``grad r``): of 1500 random
    planes and maps the worst needed ``scale = 1.02`` (a 189 x 26 map), so use a
    few percent more there.

    Too small: acne. Too large: the lookup point leaves the surface, so shadows
    shift toward the light (peter-panning) and thin casters or contact corners leak
    light. ``normals`` should face the light's side of the surface: on faces turned
    away (``n . l < 0``, unlit anyway) the offset points into the surface.

    Arguments:
        world_to_texture: ``(*batch, 4, 4)`` world to ``(s q, t q, r q, q)``.
        points: ``(*batch, 3)`` receiver points in front of the light.
        normals: ``(*batch, 3)`` their surface normals (need not be unit).
        map_size: ``size`` or ``(width, height)`` in texels.
        pcf_radius: the PCF kernel radius of the lookup (``c`` above; ``radius=``,
            deprecated).
        pcf_filter: ``"box"`` or ``"bilinear"`` (``filter=``, deprecated).
        scale: a safety factor on the derived minimum (``>= 0``, default 1).

    Returns:
        ``(*batch, 3)`` world-space offset vectors along the unit normals.

    Raises:
        ValueError: as :func:`texel_world_size`, plus a zero normal and a bad
            ``pcf_radius``, ``pcf_filter`` or ``scale``.

    Example:
        >>> import numpy as np
        >>> M = np.array([[0.1, 0, 0, 0.5], [0, 0.1, 0, 0.5], [0, 0, -0.1, 0], [0, 0, 0, 1]])
        >>> # Tilted 45 degrees along s: 1/2 texel * 0.1 * sin 45 = 0.0354 along the normal
        >>> normal_offset(M, [0.0, 0.0, -3.0], [1.0, 0.0, 1.0], map_size=100).round(6)
        array([0.025, 0.   , 0.025])
    """
    W, H = _map_size(map_size)
    k, filt = check_kernel(pcf_radius, pcf_filter)
    if not (isinstance(scale, int | float) and math.isfinite(scale) and scale >= 0):
        raise ValueError(f"scale: expected a finite number >= 0, got {scale!r}")
    checks, xp, M, p, n, _ = _prepare(world_to_texture, points, normals)
    offset = _bias.normal_offset(
        xp, M, p, n, (W, H), reach=_bias.kernel_reach(k, filt), scale=float(scale)
    )
    return checks.poison(offset, 1)
