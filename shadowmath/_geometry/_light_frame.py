"""The light coordinate system at the door: the frame's public functions and the
conversion and checks of a user-given frame (the formulas are :mod:`shadowmath._math._frame`'s
and :mod:`shadowmath._math._formulas`')."""

from __future__ import annotations

from typing import Any, Literal

from shadowmath._boundary import _messages as msg
from shadowmath._boundary._shapes import ArrayLike, Float, Real
from shadowmath._boundary._validate import (
    Array,
    Checks,
    Context,
    all_finite,
    batch_shape,
    convert,
    non_finite,
    require_last,
    require_vertices,
)
from shadowmath._math._frame import LightFrame, light_entries, stack_matrix, zero_direction_noise
from shadowmath._math._passes import spread
from shadowmath._math._specialize import formulas


def _check_points(checks: Checks, light: Array, vertices: Array) -> None:
    """Shapes and finiteness of a light position and a vertex set (the boundary's job)."""
    require_last("light_position", light, 3, hint="a light position is (x, y, z)")
    require_vertices("vertices", vertices)
    xp = checks.ctx.xp
    checks.require(all_finite(xp, light, 1), non_finite("light_position"))
    checks.require(all_finite(xp, vertices, 2), non_finite("vertices"))


def mean_direction_vector(
    light_position: Real[ArrayLike, "*#batch 3"], vertices: Real[ArrayLike, "*#batch N 3"]
) -> Float[Array, "*batch 3"]:
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
    ctx, (light, verts) = convert(light_position=light_position, vertices=vertices)
    checks = Checks(ctx)
    _check_points(checks, light, verts)
    batch_shape(light.shape[:-1], verts.shape[:-2], names=("light_position", "vertices"))
    mdv = ctx.xp.mean(verts - light[..., None, :], axis=-2)
    return checks.poison(mdv, 1)


def helper_axis(z_axis: Real[ArrayLike, "*batch 3"]) -> Float[Array, "*batch 3"]:
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
    ctx, (z,) = convert(z_axis=z_axis)
    require_last("z_axis", z, 3)
    checks = Checks(ctx)
    checks.require(all_finite(ctx.xp, z, 1), non_finite("z_axis"))
    v = formulas(ctx.xp).helper_axis3(z[..., 0], z[..., 1], z[..., 2])
    return checks.poison(ctx.xp.stack(v, axis=-1), 1)


def frame_along(
    ctx: Context, checks: Checks, light: Array, direction: Array, noise: Array | float = 0.0
) -> LightFrame:
    """The frame with ``Z`` along ``direction`` (trusted); ``noise`` bounds its rounding error."""
    xp = ctx.xp
    axes = formulas(xp).frame_axes(direction[..., 0], direction[..., 1], direction[..., 2])
    checks.require(axes[9] > noise, msg.ZERO_DIRECTION)
    shape = batch_shape(
        light.shape[:-1], direction.shape[:-1], names=("light_position", "direction")
    )
    return LightFrame(
        origin=checks.poison(xp.broadcast_to(light, (*shape, 3)), 1),
        x_axis=checks.poison(xp.broadcast_to(xp.stack(axes[0:3], axis=-1), (*shape, 3)), 1),
        y_axis=checks.poison(xp.broadcast_to(xp.stack(axes[3:6], axis=-1), (*shape, 3)), 1),
        z_axis=checks.poison(xp.broadcast_to(xp.stack(axes[6:9], axis=-1), (*shape, 3)), 1),
    )


def check_aim(aim: str) -> None:
    if aim not in ("mean", "bbox"):
        raise ValueError(f"aim: expected 'mean' or 'bbox', got {aim!r}")


def light_frame(
    light_position: Real[ArrayLike, "*#batch 3"],
    vertices: Real[ArrayLike, "*#batch N 3"],
    *,
    aim: Literal["mean", "bbox"] = "mean",
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
    check_aim(aim)
    ctx, (light, verts) = convert(light_position=light_position, vertices=vertices)
    checks = Checks(ctx)
    _check_points(checks, light, verts)
    s = spread(ctx.xp, light, verts, aim=aim)
    return frame_along(ctx, checks, light, s.direction, zero_direction_noise(ctx, s.coords))


def light_frame_from_direction(
    light_position: Real[ArrayLike, "*#batch 3"], direction: Real[ArrayLike, "*#batch 3"]
) -> LightFrame:
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
    ctx, (light, d) = convert(light_position=light_position, direction=direction)
    require_last("light_position", light, 3)
    require_last("direction", d, 3)
    checks = Checks(ctx)
    checks.require(all_finite(ctx.xp, light, 1), non_finite("light_position"))
    checks.require(all_finite(ctx.xp, d, 1), non_finite("direction"))
    return frame_along(ctx, checks, light, d)


def frame_arrays(
    frame: LightFrame, **extra: Any
) -> tuple[Context, Checks, LightFrame, tuple[Array, ...]]:
    """A user-given frame, and any ``extra`` arrays, converted together and checked.

    The boundary of every frame-taking function: one conversion for the frame's
    fields and the other arguments (one namespace, one dtype), and the frame's
    shape and finiteness checks. The extras are converted, not checked.
    """
    if not isinstance(frame, tuple) or len(frame) != 4:
        raise ValueError("frame: expected a LightFrame (origin, x_axis, y_axis, z_axis)")
    ctx, arrays = convert(
        origin=frame[0], x_axis=frame[1], y_axis=frame[2], z_axis=frame[3], **extra
    )
    fields = arrays[:4]
    checks = Checks(ctx)
    for name, value in zip(LightFrame._fields, fields, strict=True):
        require_last(f"frame.{name}", value, 3)
        checks.require(all_finite(ctx.xp, value, 1), non_finite(f"frame.{name}"))
    batch_shape(*(f.shape[:-1] for f in fields), names=LightFrame._fields)
    return ctx, checks, LightFrame(*fields), arrays[4:]


def world_to_light(frame: LightFrame) -> Float[Array, "*batch 4 4"]:
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
    ctx, checks, f, _ = frame_arrays(frame)
    return checks.poison(stack_matrix(ctx.xp, light_entries(ctx.xp, f)), 2)


def light_to_world(frame: LightFrame) -> Float[Array, "*batch 4 4"]:
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
    ctx, checks, (o, x, y, z), _ = frame_arrays(frame)
    entries = (
        x[..., 0], y[..., 0], z[..., 0], o[..., 0],
        x[..., 1], y[..., 1], z[..., 1], o[..., 1],
        x[..., 2], y[..., 2], z[..., 2], o[..., 2],
    )  # fmt: skip
    return checks.poison(stack_matrix(ctx.xp, entries), 2)
