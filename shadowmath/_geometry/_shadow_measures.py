"""What a shadow-map user wants from a frustum, measured.

* :func:`silhouette_coverage`: the fraction of the usable map (inside the
  border) the rendered silhouette covers, from a rendered mask;
* :func:`cross_section_area`: its differentiable proxy, the area of the
  frustum's usable cross-section at unit distance (coverage is the
  silhouette's area in that plane divided by this);
* :func:`receiver_texel_size`: the world-space size of one shadow-map texel
  where it lands on a receiver.
"""

from __future__ import annotations

from typing import Any

from shadowmath._boundary._shapes import ArrayLike, Bool, Float, IntLike, MapSize, Real
from shadowmath._boundary._validate import (
    Array,
    Checks,
    all_finite,
    batch_shape,
    convert,
    flags,
    integer,
    non_finite,
    require_last,
    require_matrix,
)
from shadowmath._math import _bias
from shadowmath._math._frustum import Frustum, OrthographicBox
from shadowmath._math._vector import dot

from ._adaptive_frustum import frustum_arrays, texel_counts


def cross_section_area(
    frustum: Frustum | OrthographicBox | tuple[Any, ...],
) -> Float[Array, "*batch"]:
    r"""The usable cross-section of the frustum at unit distance from the light.

    .. math:: A = (2 R_x)(2 R_y)

    in ratio units (``x / z``, ``y / z``): the part of the plane ``z = 1`` that
    maps inside the margins. A silhouette of area ``S`` in that plane covers
    ``S / A`` of the usable map, so at a fixed frame a smaller ``A`` means a
    proportionally larger coverage: the differentiable proxy the fitter minimises.

    Arguments:
        frustum: a :class:`Frustum` with ``(*batch,)`` fields, or an
            :class:`OrthographicBox` (its cross-section ``(2 R_x)(2 R_y)`` in world
            units squared, the same at every depth).

    Returns:
        ``(*batch,)``.

    Example:
        >>> float(cross_section_area(Frustum(0.5, 0.25, 1.0, 2.0, 0.98, 0.98)))
        0.5
    """
    _, checks, fr = frustum_arrays(frustum)
    half_x, half_y = fr[0], fr[1]  # rx_max, ry_max or half_width, half_height
    return checks.poison(4 * half_x * half_y, 0)


def silhouette_coverage(
    mask: Real[ArrayLike, "*batch H W"] | Bool[ArrayLike, "*batch H W"],
    *,
    border_texels: IntLike = 1,
) -> Float[Array, "*batch"]:
    """The fraction of the usable shadow map that the silhouette covers.

    The mean of ``mask`` over the texels inside the border (the border itself
    must stay empty; it is not counted). Pass a mask rendered by
    :func:`shadowmath.render.render_shadow_map` (1 under the silhouette).

    Arguments:
        mask: ``(*batch, height, width)`` values in ``[0, 1]``.
        border_texels: the border width on each side.

    Returns:
        ``(*batch,)`` coverage in ``[0, 1]``.

    Raises:
        ValueError: fewer than 2 dimensions, or a map no larger than its borders.

    Example:
        >>> m = np.zeros((6, 6)); m[1:3, 1:5] = 1  # half of the 4x4 interior
        >>> float(silhouette_coverage(m))
        0.5
    """
    ctx, (m,) = convert(mask=flags(mask))
    if m.ndim < 2:
        raise ValueError(f"mask: expected shape (*batch, height, width), got {tuple(m.shape)}")
    b = integer("border_texels", border_texels)
    h, w = int(m.shape[-2]), int(m.shape[-1])
    if b < 0 or min(h, w) <= 2 * b:
        raise ValueError(f"border_texels: {b} leaves no interior in a {w}x{h} mask")
    inner = m[..., b : h - b, b : w - b]
    return ctx.xp.mean(ctx.xp.mean(inner, axis=-1), axis=-1)


def receiver_texel_size(
    world_to_texture: Real[ArrayLike, "*#batch 4 4"],
    points: Real[ArrayLike, "*#batch 3"],
    normals: Real[ArrayLike, "*#batch 3"],
    map_size: MapSize,
) -> Float[Array, "*batch"]:
    r"""The world-space edge length of one shadow-map texel on a receiver surface.

    With ``(s q, t q, r q, q) = M p``, the texture coordinates ``s``, ``t``
    have world gradients ``grad s = (m_0 - s m_3) / q`` and
    ``grad t = (m_1 - t m_3) / q`` (``m_i`` the first three entries of row ``i``).
    On a surface with unit normal ``n`` the map from the tangent plane to
    ``(s, t)`` has Jacobian determinant ``(grad s x grad t) . n``, so one texel
    (``1/W`` by ``1/H`` in ``(s, t)``) covers

    .. math:: a = \frac{1}{W H \, |(\nabla s \times \nabla t) \cdot n|}

    of the surface; the result is ``sqrt(a)``, the side of a square of that
    area. Smaller is sharper. Infinite where the surface is seen edge-on from
    the light.

    Arguments:
        world_to_texture: ``(*batch, 4, 4)`` e.g. :attr:`ShadowSetup.world_to_texture`.
        points: ``(*batch, 3)`` receiver points in world coordinates (in front
            of the light, ``q > 0``).
        normals: ``(*batch, 3)`` the surface normals there (need not be unit).
        map_size: ``size`` or ``(width, height)`` in texels.

    Returns:
        ``(*batch,)`` lengths in world units.

    Raises:
        ValueError: wrong shapes, non-finite values, a zero normal, a point
            behind the light (NaN under JAX transformations).

    Example:
        >>> s = fit_shadow([0, 0, 0], [[-1, -1, 4], [1, 1, 4], [1, -1, 4], [-1, 1, 4]], 100)
        >>> # The wall z = 8 is twice as far as the blocker: 2 R z / (m W) = 2 * 0.25 * 8 / 98
        >>> float(receiver_texel_size(s.world_to_texture, [0, 0, 8], [0, 0, 1], 100).round(6))
        0.040816
    """
    W, H = texel_counts("map_size", map_size)
    ctx, (M, p, n) = convert(world_to_texture=world_to_texture, points=points, normals=normals)
    xp = ctx.xp
    require_matrix("world_to_texture", M)
    require_last("points", p, 3)
    require_last("normals", n, 3)
    checks = Checks(ctx)
    checks.require(all_finite(xp, M, 2), non_finite("world_to_texture"))
    checks.require(all_finite(xp, p, 1), non_finite("points"))
    checks.require(all_finite(xp, n, 1), non_finite("normals"))
    n_sq = dot(xp, n, n)
    checks.require(n_sq > 0, "normals: a normal is zero")
    shape = batch_shape(
        tuple(M.shape[:-2]),
        tuple(p.shape[:-1]),
        tuple(n.shape[:-1]),
        names=("world_to_texture", "points", "normals"),
    )
    q = xp.sum(M[..., 3, :3] * p, axis=-1) + M[..., 3, 3]
    checks.require(q > 0, "points: a receiver point is behind the light (q <= 0)")
    unit_n = n / xp.sqrt(n_sq)[..., None]
    size = _bias.texel_size_on_surface(xp, M, p, unit_n, (W, H))
    return checks.poison(xp.broadcast_to(size, shape), 0)
