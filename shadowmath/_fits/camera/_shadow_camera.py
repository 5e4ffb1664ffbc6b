r"""Engine-neutral shadow cameras: the eye, axes and window of every fit, for any engine.

Every engine describes a shadow camera with the same few numbers, under different
names (``docs/shadow-cameras.md`` has the table): where the eye is, where it looks,
which way is up, the window (an orthographic box's width and height, or a
perspective frustum's field of view, aspect and offset) and the depth range from
the eye. :func:`shadow_camera` reads them off a fit, so an engine's own camera,
built from them with its own look-at and projection, draws exactly the fitted map;
:func:`camera_to_world` places an engine's camera node (its local axes differ
between engines).

A fit's light frame has ``+Z`` toward the casters and ``X x Y = -Z``; a right-handed
camera looking down its ``-z`` with ``up = Y`` has right axis ``forward x up =
Z x Y = X``, so its view coordinates are light coordinates with ``z`` negated, and
the window's sides are the frustum's in light ``X`` and ``Y``.
"""

from __future__ import annotations

from collections.abc import Sequence
from types import ModuleType
from typing import Any, Literal, NamedTuple, TypeAlias

import numpy as np

from shadowmath._boundary._shapes import Float
from shadowmath._boundary._validate import (
    Array,
    Checks,
    Context,
    all_finite,
    batch_shape,
    convert,
    is_jax,
    non_finite,
    require_last,
    require_matrix,
)
from shadowmath._fits.cascades._result import Cascades
from shadowmath._fits.shadow._result import ShadowSetup
from shadowmath._math._frame import LightFrame
from shadowmath._math._frustum import Frustum, OrthographicBox
from shadowmath._math._vector import cross

__all__ = ["CameraLook", "ShadowCamera", "camera_to_world", "shadow_camera"]

#: How an engine's camera node looks along its local axes (see :func:`camera_to_world`).
CameraLook: TypeAlias = Literal["-z", "+z", "+y"]

_LOOKS: tuple[CameraLook, ...] = ("-z", "+z", "+y")


class ShadowCamera(NamedTuple):
    r"""A fit's shadow camera as an engine describes one: eye, axes, window, depth range.

    Rebuild the fit's clip matrix from it with any engine's look-at and projection:
    the right-handed look-at ``view = lookAt(eye, eye + forward, up)`` and OpenGL's
    ``frustum(left n, right n, bottom n, top n, n, f)`` (perspective) or
    ``ortho(left, right, bottom, top, n, f)`` (orthographic) give
    ``blocker_to_clip = C @ projection @ view @ blocker_to_world``, with ``C`` the
    API's :attr:`ApiConvention.gl_clip_to_clip`.

    Attributes:
        eye: ``(*batch, 3)`` the camera's position: a point or spot light's position;
            for an orthographic fit the centre of the map's box on its near-to-far axis,
            so that the box is symmetric about the eye (``left = -right``).
        forward: ``(*batch, 3)`` unit viewing direction (the light frame's ``Z``).
        up: ``(*batch, 3)`` unit up (the light frame's ``Y``), perpendicular to
            ``forward``: pass it as the engine camera's up, or the map rolls.
        left, right, bottom, top: ``(*batch,)`` the window's sides along the camera's
            right axis (``forward x up``, the light's ``X``) and ``up``, border
            included: tangents ``x / z`` and ``y / z`` for a perspective fit, world
            units from the eye for an orthographic one.
        near, far: ``(*batch,)`` the depth range, distances from the eye along
            ``forward`` (an orthographic box's ``near`` may be negative).
        orthographic: ``True`` for a directional light's fit (an
            :class:`OrthographicBox`), ``False`` for a perspective :class:`Frustum`.
    """

    eye: Float[Array, "*camera 3"]
    forward: Float[Array, "*camera 3"]
    up: Float[Array, "*camera 3"]
    left: Float[Array, "*camera"]
    right: Float[Array, "*camera"]
    bottom: Float[Array, "*camera"]
    top: Float[Array, "*camera"]
    near: Float[Array, "*camera"]
    far: Float[Array, "*camera"]
    orthographic: bool

    @property
    def width(self) -> Array:
        """``right - left``: world units (orthographic), or ``2 tan`` of the half-angle."""
        return self.right - self.left

    @property
    def height(self) -> Array:
        """``top - bottom``: world units (orthographic), or ``2 tan`` of the half-angle."""
        return self.top - self.bottom

    @property
    def aspect(self) -> Array:
        """``width / height``, the aspect ratio of the map's texels' window."""
        return self.width / self.height

    @property
    def fov_y(self) -> Array:
        r"""Vertical field of view in radians, :math:`2 \arctan(\mathrm{height} / 2)`.

        The angle of a frustum symmetric about its axis with this window's height;
        shift it by :attr:`offset` when the offset is not zero. NaN for an
        orthographic camera, which has no field of view.
        """
        xp = _namespace(self.height)
        angle = 2.0 * xp.arctan(0.5 * self.height)
        return xp.where(xp.asarray(self.orthographic), xp.nan, angle)

    @property
    def offset(self) -> Array:
        """``(*batch, 2)`` the window's centre ``((left + right) / 2, (bottom + top) / 2)``.

        Zero for an orthographic camera (its eye is centred) and for the default fits
        (``method="mdv"``); an off-centre perspective fit's offset in tangent units.
        """
        xp = _namespace(self.left)
        return xp.stack([0.5 * (self.left + self.right), 0.5 * (self.bottom + self.top)], axis=-1)


def _namespace(x: Array) -> ModuleType:
    """NumPy, or JAX's namespace for a JAX array (imported only then)."""
    if not is_jax(x):
        return np
    import jax.numpy as jnp

    return jnp


def shadow_camera(fit: ShadowSetup | Cascades) -> ShadowCamera:
    r"""The engine-neutral camera of a fit: eye, forward, up, window and depth range.

    With the frustum's half-extents :math:`R_x, R_y` at its margins :math:`m_x, m_y`
    and its centre :math:`(c_x, c_y)` (:class:`Frustum` or :class:`OrthographicBox`),
    the window is

    .. math::

        [\mathrm{left}, \mathrm{right}] = c_x \mp R_x / m_x,\qquad
        [\mathrm{bottom}, \mathrm{top}] = c_y \mp R_y / m_y

    in tangents for a perspective fit, whose eye is the light. An orthographic fit's
    eye moves to the box's centre line, ``eye = origin + c_x X + c_y Y``, and its
    window becomes ``[-R_x / m_x, R_x / m_x]``: the numbers an engine's
    orthographic camera takes (a width and a height about its position).

    Arguments:
        fit: a :class:`ShadowSetup` (:func:`fit_shadow`: point, spot or directional
            light; its ``blocker_to_world`` is not part of the camera) or
            :class:`Cascades` (:func:`fit_cascades`; one camera per cascade).

    Returns:
        A :class:`ShadowCamera`, batch ``(*batch,)`` of the fit (``(*batch, n)`` for
        ``n`` cascades), in the fit's namespace and dtype.

    Raises:
        ValueError: ``fit`` is neither a ``ShadowSetup`` nor ``Cascades``; cascades
            warped by LiSPSM (their clip matrices are a perspective warp that no
            orthographic camera draws); non-finite fields (NaN under JAX
            transformations).

    Example:
        >>> import numpy as np, shadowmath as sm
        >>> cube = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
        >>> setup = sm.fit_shadow(sm.PointLight([0.0, 0.0, 10.0]), cube, 100, up=[0, 1, 0])
        >>> cam = shadow_camera(setup)
        >>> cam.eye, cam.forward, cam.up
        (array([ 0.,  0., 10.]), array([ 0.,  0., -1.]), array([0., 1., 0.]))
        >>> # the nearest face, 9 away, spans tan = 1 / 9, inside the 0.98 margin
        >>> bool(np.isclose(cam.top, 1 / (9 * 0.98))), float(cam.aspect), float(cam.near) < 9
        (True, 1.0, True)
        >>> round(float(np.degrees(cam.fov_y)), 3)  # 2 atan(top)
        12.937
    """
    if isinstance(fit, ShadowSetup):
        _, checks, frame, frustum = _setup_arrays(fit)
    elif isinstance(fit, Cascades):
        _, checks, frame, frustum = _cascade_arrays(fit)
    else:
        raise ValueError(
            "fit: expected a ShadowSetup (from fit_shadow) or Cascades (from fit_cascades), "
            f"got {type(fit).__name__}"
        )
    camera = _camera_from_frustum(frame, frustum)
    poisoned = {
        name: checks.poison(getattr(camera, name), 1 if name in _VECTORS else 0)
        for name in ShadowCamera._fields[:-1]
    }
    return camera._replace(**poisoned)


_VECTORS = ("eye", "forward", "up")


Volume = Frustum | OrthographicBox


def _setup_arrays(fit: ShadowSetup) -> tuple[Context, Checks, LightFrame, Volume]:
    ctx, checks, arrays = _converted(tuple(fit.frame), fit.frustum)
    return ctx, checks, LightFrame(*arrays[:4]), _frustum(arrays[4:], fit.frustum)


def _cascade_arrays(fit: Cascades) -> tuple[Context, Checks, LightFrame, Volume]:
    """The frame of each cascade from its rigid ``world_to_light`` ``[[R, t], [0, 1]]``."""
    ctx, checks, (W, clip, *fields) = _converted(
        (fit.world_to_light, fit.world_to_clip), fit.frustum, names=_MATRICES, trailing=2
    )
    xp = ctx.xp
    # An orthographic clip matrix keeps w = 1; LiSPSM's perspective warp does not.
    w_row = clip[..., 3, :]
    orthographic = xp.all(w_row[..., :3] == 0, axis=-1) & (w_row[..., 3] == 1)
    checks.require(orthographic, _WARPED)
    R, t = W[..., :3, :3], W[..., :3, 3]
    origin = -xp.sum(R * t[..., :, None], axis=-2)  # -R^T t of a rigid [[R, t], [0, 1]]
    frame = LightFrame(origin, R[..., 0, :], R[..., 1, :], R[..., 2, :])
    return ctx, checks, frame, _frustum(fields, fit.frustum)


_MATRICES = ("world_to_light", "world_to_clip")
_WARPED = (
    "fit: these cascades are warped by LiSPSM (warp='lispsm'), a perspective warp that no "
    "orthographic camera draws; use their world_to_clip and world_to_texture"
)


def _converted(
    arrays: tuple[Any, ...],
    fr: Volume,
    *,
    names: tuple[str, ...] = LightFrame._fields,
    trailing: int = 1,
) -> tuple[Context, Checks, tuple[Array, ...]]:
    """One conversion and the shape and finite checks of a fit's arrays and frustum fields."""
    scalars = type(fr)._fields
    ctx, out = convert(**dict(zip(names, arrays, strict=True)), **fr._asdict())
    checks = Checks(ctx)
    xp = ctx.xp
    for name, value in zip(names, out[: len(names)], strict=True):
        if trailing == 1:
            require_last(f"fit.{name}", value, 3)
        else:
            require_matrix(f"fit.{name}", value)
        checks.require(all_finite(xp, value, trailing), non_finite(f"fit.{name}"))
    for name, value in zip(scalars, out[len(names) :], strict=True):
        checks.require(all_finite(xp, value, 0), non_finite(f"fit.frustum.{name}"))
    batch_shape(
        *(a.shape[: a.ndim - trailing] for a in out[: len(names)]),
        *(a.shape for a in out[len(names) :]),
        names=(*names, *scalars),
    )
    return ctx, checks, out


def _frustum(fields: Sequence[Float[Array, "*batch"]], fr: Volume) -> Volume:
    """The frustum or box of converted fields (the same type as ``fr``)."""
    return type(fr)._make(fields)


def _camera_from_frustum(frame: LightFrame, fr: Volume) -> ShadowCamera:
    """The camera of a trusted frame and frustum (the formula of :func:`shadow_camera`)."""
    o, X, Y, Z = frame
    half_x, half_y, near, far, margin_x, margin_y, center_x, center_y = fr
    hx, hy = half_x / margin_x, half_y / margin_y
    cx, cy = center_x + 0.0 * hx, center_y + 0.0 * hy  # broadcast to the batch
    ortho = isinstance(fr, OrthographicBox)
    shift_x, shift_y = (cx, cy) if ortho else (0.0 * cx, 0.0 * cy)
    eye = o + shift_x[..., None] * X + shift_y[..., None] * Y
    cx, cy = cx - shift_x, cy - shift_y
    return ShadowCamera(
        eye=eye,
        forward=Z + 0.0 * eye,
        up=Y + 0.0 * eye,
        left=cx - hx,
        right=cx + hx,
        bottom=cy - hy,
        top=cy + hy,
        near=near + 0.0 * hx,
        far=far + 0.0 * hx,
        orthographic=ortho,
    )


def camera_to_world(
    camera: ShadowCamera, *, look: CameraLook = "-z"
) -> Float[Array, "*camera 4 4"]:
    r"""The world matrix of an engine's camera node that shows ``camera``'s map.

    Engines differ in which local axis a camera looks along. The matrix's columns
    are the node's local axes in world coordinates and its position:

    ==========  ===============================  ============================  =======
    ``look``    engines                          columns ``x, y, z``           window
    ==========  ===============================  ============================  =======
    ``"-z"``    three.js, pygfx, Godot, Filament ``right, up, -forward``       as is
    ``"+y"``    Panda3D (``z`` up)               ``right, forward, up``        as is
    ``"+z"``    Babylon.js, Unity (left-handed)  ``-right, up, forward``       mirrored
    ==========  ===============================  ============================  =======

    with ``right = forward x up``. Each is a rotation (determinant ``+1``). A
    left-handed engine's look-at with the same ``up`` has ``right = up x forward``,
    the opposite of ours: its window along ``x`` is ``[-right, -left]`` (the same
    for the default symmetric fits) and its map is the mirror image of the fit's,
    which it samples with its own matrices consistently.

    Arguments:
        camera: a :class:`ShadowCamera` (from :func:`shadow_camera`).
        look: the engine's viewing axis, ``"-z"`` (default), ``"+y"`` or ``"+z"``.

    Returns:
        ``(*batch, 4, 4)`` rigid matrices, node-local to world.

    Raises:
        ValueError: an unknown ``look``, a ``camera`` that is not a ``ShadowCamera``.

    Example:
        >>> import numpy as np, shadowmath as sm
        >>> cube = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
        >>> cam = shadow_camera(sm.fit_shadow(sm.PointLight([0.0, 0.0, 10.0]), cube, 100,
        ...                                   up=[0, 1, 0]))
        >>> camera_to_world(cam)  # the light at z = 10 looking down world -z: no rotation
        array([[ 1.,  0.,  0.,  0.],
               [ 0.,  1.,  0.,  0.],
               [ 0.,  0.,  1., 10.],
               [ 0.,  0.,  0.,  1.]])
    """
    if not isinstance(camera, ShadowCamera):
        raise ValueError(f"camera: expected a ShadowCamera, got {type(camera).__name__}")
    if look not in _LOOKS:
        raise ValueError(f"look: expected one of {', '.join(map(repr, _LOOKS))}, got {look!r}")
    ctx, (eye, f, u) = convert(eye=camera.eye, forward=camera.forward, up=camera.up)
    return _node_matrix(ctx, eye, f, u, look)


def _node_matrix(ctx: Context, eye: Array, f: Array, u: Array, look: CameraLook) -> Array:
    xp = ctx.xp
    r = cross(xp, f, u)
    columns = {"-z": (r, u, -f), "+y": (r, f, u), "+z": (-r, u, f)}[look]
    top = xp.stack([*columns, eye], axis=-1)  # (*batch, 3, 4)
    last = xp.broadcast_to(ctx.constant([0.0, 0.0, 0.0, 1.0]), (*top.shape[:-2], 1, 4))
    return xp.concat([top, last], axis=-2) + 0.0
