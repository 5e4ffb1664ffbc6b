"""The light coordinate system of Nagy's projective shadow texture.

Origin at the light, ``Z`` toward the blocker (the normalized mean direction
vector), ``X = normalize(Z x V)`` with ``V`` the helper axis, ``Y = X x Z``.
Because ``X x Y = X x (X x Z) = -Z``, ``(X, Y, Z)`` is a *left-handed* frame:
it is an OpenGL right-handed look-at camera at the light with its ``z`` axis
flipped (the camera looks down its ``-z``, which is our ``+Z``).
"""

from __future__ import annotations

from typing import Any, Literal, NamedTuple

from ._backend import (
    Array,
    Checks,
    Context,
    all_finite,
    batch_shape,
    eps,
    non_finite,
    prepare,
    require_last,
)
from ._vector import cross, safe_normalize


class LightFrame(NamedTuple):
    """The light coordinate system, all fields in world coordinates.

    Attributes:
        origin: ``(*batch, 3)`` the light position.
        x_axis: ``(*batch, 3)`` unit ``X_light``.
        y_axis: ``(*batch, 3)`` unit ``Y_light``.
        z_axis: ``(*batch, 3)`` unit ``Z_light``, from the light toward the blocker.

    ``(x_axis, y_axis, z_axis)`` is orthonormal and left-handed
    (``x_axis x y_axis = -z_axis``).
    """

    origin: Array
    x_axis: Array
    y_axis: Array
    z_axis: Array


def _check_points(ctx: Context, checks: Checks, light: Array, vertices: Array) -> None:
    require_last("light_position", light, 3, hint="a light position is (x, y, z)")
    require_last("vertices", vertices, 3, min_ndim=2, hint="vertices are (*batch, N, 3)")
    if vertices.shape[-2] == 0:
        raise ValueError("vertices: the vertex set is empty (N = 0); a blocker needs vertices")
    xp = ctx.xp
    checks.require(all_finite(xp, light, 1), non_finite("light_position"))
    checks.require(all_finite(xp, vertices, 2), non_finite("vertices"))


def mean_direction_vector(light_position: Any, vertices: Any) -> Array:
    r"""The mean direction vector (MDV) from the light to the blocker's vertices.

    .. math:: \mathrm{MDV} = \frac{1}{N_v} \sum_{i=1}^{N_v} (V_i - P_\mathrm{light})

    Unnormalized; :func:`light_frame` normalizes it into ``Z_light``. The
    differences are taken before the sum, which keeps full precision when the
    scene sits far from the origin.

    Arguments:
        light_position: ``(*batch, 3)`` the point light's position.
        vertices: ``(*batch, N, 3)`` blocker vertices, in world coordinates.

    Returns:
        ``(*batch, 3)``.

    Raises:
        ValueError: wrong shapes, an empty vertex set, non-finite values (NaN
            outputs under JAX transformations).

    Example:
        >>> mean_direction_vector([0, 0, 0], [[1, 2, 3], [3, 2, 1]])
        array([2., 2., 2.])
    """
    ctx, a = prepare(light_position=light_position, vertices=vertices)
    xp = ctx.xp
    light, verts = a["light_position"], a["vertices"]
    checks = Checks(ctx)
    _check_points(ctx, checks, light, verts)
    batch_shape(light.shape[:-1], verts.shape[:-2], names=("light_position", "vertices"))
    mdv = xp.mean(verts - light[..., None, :], axis=-2)
    return checks.poison(mdv, 1)


def helper_axis(z_axis: Any) -> Array:
    r"""The world axis the light frame crosses with ``Z_light`` to get ``X_light``.

    The unit vector along the world axis at the component of ``z_axis`` with
    the *smallest* absolute value (ties go to the lowest index). For unit ``Z``
    that component is at most ``1/sqrt(3)`` in size, so
    ``|Z x V| = sqrt(1 - z_k^2) >= sqrt(2/3)``: the cross product is never
    short and its normalization never loses precision.

    Piecewise constant: the choice jumps where two components tie in size, so
    the frame's ``X`` and ``Y`` jump there too (its gradient is zero).

    Arguments:
        z_axis: ``(*batch, 3)`` direction (need not be normalized).

    Returns:
        ``(*batch, 3)`` one of ``(1, 0, 0)``, ``(0, 1, 0)``, ``(0, 0, 1)``.

    Raises:
        ValueError: wrong shape or non-finite values (NaN under JAX transformations).

    Example:
        >>> helper_axis([0.381, 0.889, 0.254])  # the article's first example
        array([0., 0., 1.])
        >>> helper_axis([-0.889, 0.254, 0.381])  # and its second
        array([0., 1., 0.])
    """
    ctx, a = prepare(z_axis=z_axis)
    z = a["z_axis"]
    require_last("z_axis", z, 3)
    checks = Checks(ctx)
    checks.require(all_finite(ctx.xp, z, 1), non_finite("z_axis"))
    return checks.poison(_helper_axis(ctx, z), 1)


def _helper_axis(ctx: Context, z: Array) -> Array:
    xp = ctx.xp
    ax, ay, az = xp.abs(z[..., 0]), xp.abs(z[..., 1]), xp.abs(z[..., 2])
    # Comparisons instead of argmin: ties resolve to the lowest index by the
    # order of the tests, and the result stays a traceable array.
    pick_x = (ax <= ay) & (ax <= az)
    pick_y = xp.logical_not(pick_x) & (ay <= az)
    pick_z = xp.logical_not(pick_x | pick_y)
    return xp.astype(xp.stack([pick_x, pick_y, pick_z], axis=-1), ctx.dtype)


def _frame_from_z(
    ctx: Context, checks: Checks, light: Array, direction: Array, noise: Array | float = 0.0
) -> LightFrame:
    """The frame with ``Z`` along ``direction``; ``noise`` bounds its rounding error."""
    xp = ctx.xp
    z, length = safe_normalize(xp, direction)
    checks.require(
        length > noise,
        "the light's viewing direction is zero: the light sits at the blocker's centre "
        "(zero mean direction vector, or one within rounding of zero); move the light or "
        "pass an explicit direction to light_frame_from_direction",
    )
    v = _helper_axis(ctx, z)
    x, _ = safe_normalize(xp, cross(xp, z, v))
    y = cross(xp, x, z)
    shape = batch_shape(light.shape[:-1], z.shape[:-1], names=("light_position", "direction"))
    frame = LightFrame(
        origin=xp.broadcast_to(light, (*shape, 3)),
        x_axis=xp.broadcast_to(x, (*shape, 3)),
        y_axis=xp.broadcast_to(y, (*shape, 3)),
        z_axis=xp.broadcast_to(z, (*shape, 3)),
    )
    return LightFrame(*(checks.poison(f, 1) for f in frame))


def light_frame(
    light_position: Any, vertices: Any, *, aim: Literal["mean", "bbox"] = "mean"
) -> LightFrame:
    r"""The article's light coordinate system for a point light and a blocker.

    .. math::

        Z = \frac{\mathrm{MDV}}{|\mathrm{MDV}|}, \quad
        X = \frac{Z \times V}{|Z \times V|}, \quad
        Y = X \times Z

    with ``V`` the :func:`helper_axis` of ``Z``. The frame is left-handed
    (``X x Y = -Z``); see :mod:`shadowmath` for how it relates to an OpenGL camera.
    Differentiable, but only piecewise smooth: where two components of ``Z``
    tie in size the helper axis switches, and ``X`` and ``Y`` jump (by a turn
    about ``Z``). :func:`rolled_light_frame` is a continuous alternative.

    Arguments:
        light_position: ``(*batch, 3)`` the point light's position.
        vertices: ``(*batch, N, 3)`` blocker vertices in world coordinates.
        aim: ``"mean"`` (default) aims ``Z`` along the mean direction vector;
            ``"bbox"`` aims it at the centre of the vertices' axis-aligned
            bounding box (the article's Optimization Tip #2).

    Returns:
        :class:`LightFrame` with ``(*batch, 3)`` fields.

    Raises:
        ValueError: wrong shapes, an empty vertex set, non-finite values, or a
            zero direction (the light at the blocker's centre). Under JAX
            transformations the frame's fields are NaN instead.

    Example:
        >>> f = light_frame([0, 0, 0], [[0, 0, 4], [1, 0, 4]])
        >>> f.z_axis.round(3)
        array([0.124, 0.   , 0.992])
    """
    if aim not in ("mean", "bbox"):
        raise ValueError(f"aim: expected 'mean' or 'bbox', got {aim!r}")
    ctx, a = prepare(light_position=light_position, vertices=vertices)
    xp = ctx.xp
    light, verts = a["light_position"], a["vertices"]
    checks = Checks(ctx)
    _check_points(ctx, checks, light, verts)
    offsets = verts - light[..., None, :]
    if aim == "mean":
        direction = xp.mean(offsets, axis=-2)
    else:
        direction = 0.5 * (xp.max(offsets, axis=-2) + xp.min(offsets, axis=-2))
    # A light at the blocker's centre computed in floating point (e.g. the mean
    # of the vertices) leaves an MDV of rounding noise, a few ulps of the
    # coordinates, pointing anywhere. Relative to the coordinates' size (the
    # precision the scene is stored with), anything that short is treated as
    # zero; any unit of length works.
    size = xp.maximum(
        xp.max(xp.max(xp.abs(verts), axis=-1), axis=-1), xp.max(xp.abs(light), axis=-1)
    )
    return _frame_from_z(ctx, checks, light, direction, 32 * eps(ctx) * size)


def light_frame_from_direction(light_position: Any, direction: Any) -> LightFrame:
    """The light frame for a given viewing direction instead of a vertex set.

    Same construction as :func:`light_frame` with ``Z = normalize(direction)``:
    use it when ``Z`` comes from elsewhere (a bounding volume's centre, a
    spotlight's axis, an optimizer).

    Arguments:
        light_position: ``(*batch, 3)`` the point light's position.
        direction: ``(*batch, 3)`` nonzero direction from the light toward the blocker.

    Returns:
        :class:`LightFrame` with ``(*batch, 3)`` fields.

    Raises:
        ValueError: wrong shapes, non-finite values, a zero direction (NaN under
            JAX transformations).

    Example:
        >>> light_frame_from_direction([0, 5, 0], [0, -2, 0]).x_axis + 0.0  # + 0.0: no -0.
        array([0., 0., 1.])
    """
    ctx, a = prepare(light_position=light_position, direction=direction)
    light, d = a["light_position"], a["direction"]
    require_last("light_position", light, 3)
    require_last("direction", d, 3)
    checks = Checks(ctx)
    checks.require(all_finite(ctx.xp, light, 1), non_finite("light_position"))
    checks.require(all_finite(ctx.xp, d, 1), non_finite("direction"))
    return _frame_from_z(ctx, checks, light, d)


def _frame_arrays(frame: LightFrame) -> tuple[Context, Checks, LightFrame]:
    if not isinstance(frame, tuple) or len(frame) != 4:
        raise ValueError("frame: expected a LightFrame (origin, x_axis, y_axis, z_axis)")
    ctx, a = prepare(origin=frame[0], x_axis=frame[1], y_axis=frame[2], z_axis=frame[3])
    checks = Checks(ctx)
    for name in ("origin", "x_axis", "y_axis", "z_axis"):
        require_last(f"frame.{name}", a[name], 3)
        checks.require(all_finite(ctx.xp, a[name], 1), non_finite(f"frame.{name}"))
    return ctx, checks, LightFrame(a["origin"], a["x_axis"], a["y_axis"], a["z_axis"])


def _rotation(ctx: Context, frame: LightFrame) -> Array:
    """``(*batch, 3, 3)`` with rows ``X, Y, Z``: world directions to light directions."""
    xp = ctx.xp
    shape = batch_shape(*(f.shape[:-1] for f in frame[1:]), names=("x_axis", "y_axis", "z_axis"))
    axes = [xp.broadcast_to(f, (*shape, 3)) for f in frame[1:]]
    return xp.stack(axes, axis=-2)


def _affine(ctx: Context, R: Array, t: Array) -> Array:
    """Stack ``[[R, t], [0, 0, 0, 1]]`` without writing into an array."""
    xp = ctx.xp
    shape = batch_shape(R.shape[:-2], t.shape[:-1], names=("rotation", "translation"))
    R = xp.broadcast_to(R, (*shape, 3, 3))
    t = xp.broadcast_to(t, (*shape, 3))
    top = xp.concat([R, t[..., None]], axis=-1)
    bottom = xp.broadcast_to(ctx.constant([0.0, 0.0, 0.0, 1.0]), (*shape, 1, 4))
    return xp.concat([top, bottom], axis=-2)


def world_to_light(frame: LightFrame) -> Array:
    r"""The rigid transform from world coordinates to light coordinates.

    .. math::

        M = \begin{bmatrix} R & -R\,P_\mathrm{light} \\ 0 & 1 \end{bmatrix},
        \qquad R = \begin{bmatrix} X^{\mathsf T} \\ Y^{\mathsf T} \\ Z^{\mathsf T} \end{bmatrix}

    so the light maps to the origin and the blocker to ``z > 0``.
    **Erratum:** the article prints the translation row as ``-P_light``, which
    is right only when the light sits at the world origin; the rotation must be
    applied to it, ``-R P_light``.

    Arguments:
        frame: a :class:`LightFrame` with ``(*batch, 3)`` fields.

    Returns:
        ``(*batch, 4, 4)`` column-vector matrix (``p_light = M @ p_world``).

    Raises:
        ValueError: wrong shapes or non-finite values (NaN under JAX transformations).

    Example:
        >>> import numpy as np
        >>> f = light_frame([0, 5, 0], [[0, 0, 0], [1, 0, 0]])
        >>> world_to_light(f) @ np.array([0, 5, 0, 1.0])  # the light -> origin
        array([0., 0., 0., 1.])
    """
    ctx, checks, f = _frame_arrays(frame)
    R = _rotation(ctx, f)
    t = -ctx.xp.sum(R * f.origin[..., None, :], axis=-1)
    return checks.poison(_affine(ctx, R, t), 2)


def light_to_world(frame: LightFrame) -> Array:
    """The inverse of :func:`world_to_light`: ``[[R^T, P_light], [0, 1]]``.

    Arguments:
        frame: a :class:`LightFrame` with ``(*batch, 3)`` fields.

    Returns:
        ``(*batch, 4, 4)``; its columns are ``X, Y, Z`` and the light position.

    Example:
        >>> f = light_frame_from_direction([1, 2, 3], [0, 0, 1])
        >>> light_to_world(f)[:3, 3]
        array([1., 2., 3.])
    """
    ctx, checks, f = _frame_arrays(frame)
    R = _rotation(ctx, f)
    return checks.poison(_affine(ctx, ctx.xp.matrix_transpose(R), f.origin), 2)
