"""Smooth frusta and frames at the door: soft maxima, the smooth and off-centre frusta
and the rolled light frame (checks; the soft bounds are :mod:`shadowmath._math._smooth`'s)."""

from __future__ import annotations

from typing import Any

from shadowmath._boundary._shapes import ArrayLike, BoolLike, Float, IntLike, MapSize, Real
from shadowmath._boundary._validate import (
    Array,
    Checks,
    Context,
    all_finite,
    batch_shape,
    convert,
    nan_unless,
    non_finite,
    require_last,
)
from shadowmath._math import _smooth
from shadowmath._math._frame import LightFrame
from shadowmath._math._frustum import Frustum, blocker_reach
from shadowmath._math._passes import extent
from shadowmath._math._smooth import soft_bounds
from shadowmath._math._specialize import formulas

from ._adaptive_frustum import bounded_frustum, check_blocker, margins
from ._light_frame import frame_arrays


def smooth_max(
    values: Real[ArrayLike, "*#batch N"], temperature: Real[ArrayLike, "*#batch"]
) -> Float[Array, "*batch"]:
    r"""A soft maximum over the last axis that never underestimates the maximum.

    .. math::

        \operatorname{smax}_T(x) = T \log \sum_{i=1}^{N} e^{x_i / T},
        \qquad \max_i x_i \le \operatorname{smax}_T(x) \le \max_i x_i + T \log N

    Smooth in every ``x_i`` (its gradient is the softmax of ``x / T``, spread
    over the near-maximal entries), and exact as ``T -> 0``.

    Arguments:
        values: ``(*batch, N)`` the values, ``N >= 1``.
        temperature: ``(*batch,)`` ``T > 0``, in the units of ``values``.

    Returns:
        ``(*batch,)``.

    Raises:
        ValueError: ``N = 0``, non-finite values, ``T <= 0`` or non-finite
            (NaN under JAX transformations).

    Example:
        >>> float(smooth_max([0.0, 1.0, 1.0], 0.01))  # two tied maxima: 1 + T log 2
        1.0069314718055995
    """
    ctx, (x, T) = convert(values=values, temperature=temperature)
    xp = ctx.xp
    if x.ndim < 1 or x.shape[-1] == 0:
        raise ValueError(f"values: expected shape (*batch, N) with N >= 1, got {tuple(x.shape)}")
    checks = Checks(ctx)
    checks.require(all_finite(xp, x, 1), non_finite("values"))
    checks.require(xp.isfinite(T) & (T > 0), "temperature: must be finite and > 0")
    shape = batch_shape(tuple(x.shape[:-1]), tuple(T.shape), names=("values", "temperature"))
    x = xp.broadcast_to(x, (*shape, x.shape[-1]))
    return checks.poison(
        xp.broadcast_to(_smooth.smooth_max(xp, x, nan_unless(xp, T > 0, T)), shape), 0
    )


def _ratio_frustum(
    frame: LightFrame,
    vertices: Any,
    map_size: int | tuple[int, int],
    *,
    temperature: Any,
    symmetric: bool,
    border_texels: int,
    margin: float | tuple[float, float] | None,
    near: Any,
    far: Any,
) -> Frustum:
    """The frustum from bounds of the ratios ``x / z`` and ``y / z`` (hard if T is None)."""
    m = margins(map_size, border_texels, margin)
    ctx, checks, f, (verts, T, n, fa) = frame_arrays(
        frame, vertices=vertices, temperature=temperature, near=near, far=far
    )
    check_blocker(checks, verts, n, fa)
    xp = ctx.xp
    ext = extent(xp, f.origin, verts, (f.x_axis, f.y_axis, f.z_axis))
    bounds = None
    if T is not None:
        checks.require(xp.isfinite(T) & (T > 0), "temperature: must be finite and > 0")
        T = nan_unless(xp, T > 0, T)
        bounds = soft_bounds(xp, ext.rx, ext.ry, T, symmetric=symmetric)
    reach = blocker_reach(xp, f.origin, verts)
    return bounded_frustum(
        ctx, checks, ext, reach, m, near=n, far=fa, symmetric=symmetric, bounds=bounds
    )


def smooth_frustum(
    frame: LightFrame,
    vertices: Real[ArrayLike, "*#batch N 3"],
    map_size: MapSize,
    *,
    temperature: Real[ArrayLike, "*#batch"],
    symmetric: BoolLike = True,
    border_texels: IntLike = 1,
    margin: float | tuple[float, float] | None = None,
    near: Real[ArrayLike, "*#batch"] | None = None,
    far: Real[ArrayLike, "*#batch"] | None = None,
) -> Frustum:
    r"""A frustum from soft maxima of the projection ratios: smooth and conservative.

    With ``r_i = x_i / z_i`` in light coordinates and :func:`smooth_max`
    ``smax_T``, the symmetric frustum has ``R_x = smax_T(r, -r) >= max |r_i|``
    and the off-centre one spans ``[-smax_T(-r), smax_T(r)]``, which contains
    ``[min r_i, max r_i]``, so (like :func:`adaptive_frustum`) every vertex
    maps inside the margins; only the touching is relaxed, by at most
    ``T log(2N)``. Smooth in the frame and the vertices (the default near and
    far planes are still the hard ``z`` extremes, which do not affect the
    silhouette's footprint in the map).

    Arguments:
        frame: the :class:`LightFrame` (``(*batch, 3)`` fields).
        vertices: ``(*batch, N, 3)`` blocker vertices in world coordinates.
        map_size: ``size`` or ``(width, height)`` in texels.
        temperature: ``(*batch,)`` ``T > 0`` in ratio units (``x / z``); a few
            percent of the ratios' spread keeps the bound tight.
        symmetric: True (default) for the article's centred frustum, False for
            the off-centre one (``x_offset``, ``y_offset`` at the mid-range).
        border_texels, margin, near, far: as in :func:`adaptive_frustum`.

    Returns:
        :class:`Frustum` with ``(*batch,)`` fields.

    Raises:
        ValueError: everything :func:`adaptive_frustum` raises, and a
            non-positive or non-finite temperature (NaN under JAX transformations).

    Example:
        >>> verts = [[-1, -1, 4], [1, 1, 4], [1, -1, 4], [-1, 1, 4]]
        >>> f = light_frame([0, 0, 0], verts)
        >>> exact = adaptive_frustum(f, verts, 100).rx_max
        >>> soft = smooth_frustum(f, verts, 100, temperature=1e-3).rx_max
        >>> bool(exact <= soft <= exact + 1e-3 * np.log(8))
        True
    """
    return _ratio_frustum(
        frame,
        vertices,
        map_size,
        temperature=temperature,
        symmetric=symmetric,
        border_texels=border_texels,
        margin=margin,
        near=near,
        far=far,
    )


def offcenter_frustum(
    frame: LightFrame,
    vertices: Real[ArrayLike, "*#batch N 3"],
    map_size: MapSize,
    *,
    border_texels: IntLike = 1,
    margin: float | tuple[float, float] | None = None,
    near: Real[ArrayLike, "*#batch"] | None = None,
    far: Real[ArrayLike, "*#batch"] | None = None,
) -> Frustum:
    r"""The off-centre adaptive frustum: the silhouette touches all four margins.

    .. math::

        c_x = \tfrac12 \big(\max_i r_i + \min_i r_i\big), \qquad
        R_x = \tfrac12 \big(\max_i r_i - \min_i r_i\big), \qquad r_i = x_i / z_i

    and likewise along ``Y``. :func:`blocker_projection` then maps
    ``x_ndc = m_x (x / z - c_x) / R_x``: the vertex with the smallest ratio
    lands on ``-m_x``, the largest on ``+m_x``. The article's symmetric
    frustum touches one side per axis only (``R_x = max |r_i|``), so this
    one's cross-section is never larger, usually smaller, at the same frame.

    Arguments:
        frame, vertices, map_size, border_texels, margin, near, far: as in
            :func:`adaptive_frustum`.

    Returns:
        :class:`Frustum` with ``(*batch,)`` fields, offsets set.

    Raises:
        ValueError: as :func:`adaptive_frustum` (NaN under JAX transformations).

    Example:
        >>> f = light_frame_from_direction([0, 0, 0], [0, 0, 1])
        >>> f.x_axis  # light X is world Y here
        array([0., 1., 0.])
        >>> verts = [[0, 0, 4], [1, 2, 4], [0, 2, 4], [1, 0, 4]]  # light x / z in [0, 0.5]
        >>> fr = offcenter_frustum(f, verts, 100)
        >>> float(fr.rx_max), float(fr.x_offset), float(adaptive_frustum(f, verts, 100).rx_max)
        (0.25, 0.25, 0.5)
    """
    return _ratio_frustum(
        frame,
        vertices,
        map_size,
        temperature=None,
        symmetric=False,
        border_texels=border_texels,
        margin=margin,
        near=near,
        far=far,
    )


def rolled_light_frame(
    light_position: Real[ArrayLike, "*#batch 3"],
    direction: Real[ArrayLike, "*#batch 3"],
    roll: Real[ArrayLike, "*#batch"],
    *,
    up: Real[ArrayLike, "*#batch 3"] | None = None,
) -> LightFrame:
    r"""A light frame from a direction and a roll angle, continuous in both.

    .. math::

        Z = \frac{d}{|d|}, \quad
        X_0 = \frac{Z \times U}{|Z \times U|}, \quad Y_0 = X_0 \times Z, \quad
        X = \cos\theta\, X_0 + \sin\theta\, Y_0, \quad
        Y = -\sin\theta\, X_0 + \cos\theta\, Y_0

    It is :func:`light_frame_from_direction`'s construction with a fixed
    reference axis ``U`` in place of the discretely chosen helper axis, then
    turned by ``theta`` about ``Z`` (positive turns ``X`` toward ``Y``). The
    frame stays left-handed (``X x Y = -Z``) and is smooth in ``d`` and
    ``theta`` everywhere except where ``d`` is parallel to ``U``. With
    ``U = helper_axis(d)`` and ``theta = 0`` it is the article's frame.

    Arguments:
        light_position: ``(*batch, 3)``.
        direction: ``(*batch, 3)`` nonzero, from the light toward the blocker.
        roll: ``(*batch,)`` the angle ``theta`` in radians.
        up: ``(*batch, 3)`` the reference axis ``U`` (default world ``+Y``),
            not parallel to ``direction``.

    Returns:
        :class:`LightFrame` with ``(*batch, 3)`` fields.

    Raises:
        ValueError: wrong shapes, non-finite values, a zero direction or ``up``
            parallel to it (NaN under JAX transformations).

    Example:
        >>> f = rolled_light_frame([0, 0, 0], [0, 0, 1], np.pi / 2)
        >>> f.x_axis.round(6) + 0.0, f.y_axis.round(6) + 0.0
        (array([0., 1., 0.]), array([1., 0., 0.]))
    """
    ctx, (light, d, theta, U) = convert(
        light_position=light_position, direction=direction, roll=roll, up=up
    )
    xp = ctx.xp
    U = U if U is not None else ctx.constant([0.0, 1.0, 0.0])
    require_last("light_position", light, 3)
    require_last("direction", d, 3)
    require_last("up", U, 3)
    checks = Checks(ctx)
    for name, v in (("light_position", light), ("direction", d), ("up", U)):
        checks.require(all_finite(xp, v, 1), non_finite(name))
    checks.require(xp.isfinite(theta), non_finite("roll"))
    return rolled_frame(ctx, checks, light, d, theta=theta, up=U)


def rolled_frame(
    ctx: Context, checks: Checks, light: Array, d: Array, *, theta: Array, up: Array
) -> LightFrame:
    """:func:`rolled_light_frame` on trusted arrays (checks the direction and ``up``)."""
    xp = ctx.xp
    U = up
    axes = formulas(xp).rolled_axes(
        (d[..., 0], d[..., 1], d[..., 2]), (U[..., 0], U[..., 1], U[..., 2]),
        xp.cos(theta), xp.sin(theta),
    )  # fmt: skip
    checks.require(axes[9] > 0, "direction: the light's viewing direction is zero")
    u_len = xp.max(xp.abs(U), axis=-1)
    # |Z x U| = sin(angle): below a few hundred ulps the cross product is rounding noise.
    checks.require(
        (u_len > 0) & (axes[10] > (256 * ctx.eps) ** 2),
        "up: the reference axis is zero or parallel to the direction; pick another up axis",
    )
    shape = batch_shape(
        tuple(light.shape[:-1]), tuple(axes[0].shape), names=("light_position", "direction/roll/up")
    )
    fields = (light, *(xp.stack(axes[3 * i : 3 * i + 3], axis=-1) for i in range(3)))
    if checks.invalid is not None:
        checks.invalid = xp.broadcast_to(checks.invalid, shape)
    return LightFrame(*(checks.poison(xp.broadcast_to(v, (*shape, 3)), 1) for v in fields))
