"""The whole of Nagy's projective shadow texture set-up in one call.

:func:`fit_shadow` is a boundary: it converts and checks its arguments once,
then runs one of three equivalent cores on the trusted arrays:

* NumPy input with Numba installed: the compiled loop of :mod:`._kernels`;
* concrete JAX input: :func:`fit_core` under a cached ``jax.jit``, with the
  failed checks read back in one host sync;
* NumPy without Numba, or JAX inside a transformation: :func:`fit_core`
  directly, on whole arrays.
"""

from __future__ import annotations

import functools
import math
from types import ModuleType
from typing import Any, Literal, NamedTuple

import numpy as np

from . import _kernels
from . import _messages as msg
from ._bias import PcfFilter, _check_kernel
from ._conventions import GraphicsApi, _check_api
from ._formulas import formulas
from ._frame import LightFrame, _frame, check_aim, light_entries, stack_matrix, zero_direction_noise
from ._frustum import (
    NEAR_FAR_SLACK,
    Frustum,
    _texels,
    bounded_frustum,
    margins,
    projection_terms,
)
from ._passes import extent, spread
from ._pcf import _border_texels
from ._scene import STABLE_NEEDS_UP, SceneOptions, scene_core
from ._validate import (
    Array,
    Checks,
    Context,
    all_finite,
    batch_shape,
    convert,
    flat_batch,
    non_finite,
    raise_recorded,
    raise_status,
    recorded_jit,
    require_last,
    require_matrix,
    require_vertices,
    shape_error,
)


class ShadowSetup(NamedTuple):
    """Everything a renderer needs to draw and apply one shadow map.

    Attributes:
        frame: the :class:`LightFrame`.
        frustum: the adaptive :class:`Frustum`.
        world_to_light: ``(*batch, 4, 4)`` world to light coordinates.
        blocker_to_world: ``(*batch, 4, 4)`` the blocker's placement (identity if none).
        blocker_to_clip: ``(*batch, 4, 4)`` the article's ``M_BlockerLocalToShadowMap``:
            draw the shadow map with it (``gl_Position = blocker_to_clip * p_local``).
        world_to_texture: ``(*batch, 4, 4)`` the article's ``M_WorldToShadowMapST``:
            world points to ``(s q, t q, r q, q)``.
    """

    frame: LightFrame
    frustum: Frustum
    world_to_light: Array
    blocker_to_world: Array
    blocker_to_clip: Array
    world_to_texture: Array


def _placed(xp: ModuleType, checks: Checks, B: Array, p: Array) -> Array:
    """``(*batch, N, 3)`` points through the placement ``B``, with the homogeneous divide."""
    w = xp.sum(p * B[..., None, 3, :3], axis=-1) + B[..., None, 3, 3]
    checks.require(xp.all(w > 0, axis=-1), msg.PROJECTIVE_PLACEMENT)
    h = xp.matmul(p, xp.matrix_transpose(B[..., :3, :3])) + B[..., None, :3, 3]
    return h / xp.where(w > 0, w, xp.ones_like(w))[..., None]


def fit_core(
    ctx: Context,
    checks: Checks,
    light: Array,
    verts: Array,
    B: Array | None,
    margins: tuple[float, float],
    near: Array | None,
    far: Array | None,
    aim: str,
) -> ShadowSetup:
    """The array path of :func:`fit_shadow` on shape-checked arrays; checks the values."""
    xp = ctx.xp
    checks.require(all_finite(xp, light, 1), non_finite("light_position"))
    checks.require(all_finite(xp, verts, 2), non_finite("blocker_vertices"))
    world = check_placement(checks, verts, B)
    s = spread(xp, light, world, aim=aim)
    frame = _frame(ctx, checks, light, s.direction, zero_direction_noise(ctx, s.coords))
    ext = extent(xp, light, world, frame.x_axis, frame.y_axis, frame.z_axis)
    if near is not None:
        checks.require(xp.isfinite(near), msg.NEAR_NOT_FINITE)
    if far is not None:
        checks.require(xp.isfinite(far), msg.FAR_NOT_FINITE)
    frustum = bounded_frustum(ctx, checks, ext, s.reach, margins, near, far)
    return setup_from(ctx, checks, frame, frustum, B)


def check_placement(checks: Checks, verts: Array, B: Array | None) -> Array:
    """The vertices in world coordinates, with the placement's checks."""
    xp = checks.ctx.xp
    if B is None:
        return verts
    checks.require(all_finite(xp, B, 2), non_finite("blocker_to_world"))
    return _placed(xp, checks, B, verts)


def setup_from(
    ctx: Context, checks: Checks, frame: LightFrame, frustum: Frustum, B: Array | None
) -> ShadowSetup:
    """The matrices of a trusted frame and frustum, in closed form."""
    xp = ctx.xp
    F = formulas(xp)
    W = light_entries(xp, frame)
    clip = F.clip_rows(W, projection_terms(xp, frustum))
    tex = F.texture_rows(clip)
    if B is not None:
        b = tuple(B[..., i // 4, i % 4] for i in range(16))
        clip = F.compose_rows(clip, b)
    shape = tuple(frustum.near.shape)
    placement = xp.eye(4, dtype=ctx.dtype) if B is None else B
    return ShadowSetup(
        frame=frame,
        frustum=frustum,
        world_to_light=checks.poison(stack_matrix(xp, W), 2),
        blocker_to_world=xp.broadcast_to(placement, (*shape, 4, 4)),
        blocker_to_clip=checks.poison(stack_matrix(xp, clip), 2),
        world_to_texture=checks.poison(stack_matrix(xp, tex), 2),
    )


def fit_shadow(
    light_position: Any,
    blocker_vertices: Any,
    map_size: int | tuple[int, int],
    *,
    border_texels: int | None = None,
    blocker_to_world: Any = None,
    margin: float | tuple[float, float] | None = None,
    near: Any = None,
    far: Any = None,
    aim: Literal["mean", "bbox"] = "mean",
    method: Literal["mdv", "optimized"] = "mdv",
    receivers: Any = None,
    api: GraphicsApi = "opengl",
    reversed_z: bool = False,
    up: Any = None,
    stable: bool = False,
    pcf_radius: int | None = None,
    pcf_filter: PcfFilter = "box",
) -> ShadowSetup:
    r"""Nagy's projective shadow texture for one point or directional light and one blocker.

    .. math::

        M_\mathrm{blocker \to clip} = P \, W \, B, \qquad
        M_\mathrm{world \to texture} = T \, W

    with ``B`` the blocker's placement, ``W`` :func:`world_to_light` of the
    :func:`light_frame`, ``P`` :func:`blocker_projection` and ``T``
    :func:`receiver_projection` of the :func:`adaptive_frustum`. (The article
    writes the same products in row-vector order, ``B * W * P``.)

    Arguments:
        light_position: ``(*batch, 3)`` a point light, or ``(*batch, 4)`` a
            homogeneous light ``(x, y, z, w)``: ``w != 0`` the point ``xyz / w``,
            ``w == 0`` a **directional** light whose ``xyz`` points toward the light.
            ``w`` is a value (not static under ``jax.jit``): both fits are computed
            for every entry and selected per entry with ``where``.
        blocker_vertices: ``(*batch, N, 3)`` in the blocker's local coordinates
            (world coordinates when ``blocker_to_world`` is None).
        map_size: ``size`` or ``(width, height)`` of the shadow map in texels.
        border_texels: texels left empty on each side of the map (default 1, or
            :func:`pcf_border_texels` ``(pcf_radius, pcf_filter)`` when a radius is given).
        blocker_to_world: ``(*batch, 4, 4)`` the blocker's local-to-world placement.
        margin, near, far: as in :func:`adaptive_frustum` (for a directional light,
            ``near`` and ``far`` are ``z`` in the returned frame, whose origin is
            placed by the fit: leave them None).
        aim: as in :func:`light_frame` (for ``method="mdv"``).
        method: ``"mdv"`` (default) the article's frame and symmetric frustum;
            ``"optimized"`` the frame and off-centre frustum of
            :func:`optimize_frustum` (needs JAX; point lights ``(x, y, z)`` without
            the scene options below).
        receivers: ``(*batch, M, 3)`` receiver points in world coordinates. The
            frustum's sides still fit the casters; its depth range (``near``,
            ``far``) also encloses every receiver point inside the side planes
            (``|x_ndc|, |y_ndc| <= 1``), so no depth comparison falls outside the
            map's range. Receivers outside the side planes are not in the map and
            are lit by it (clamp-to-border); receivers behind a point light
            (``z <= 0``) are ignored for the range; casters behind it are refused.
        api: ``"opengl"`` (default), ``"vulkan"``, ``"direct3d"``, ``"metal"`` or
            ``"webgpu"``: ``blocker_to_clip = C P W B`` and
            ``world_to_texture = T C P W`` with :func:`api_convention`'s ``C`` and
            ``T``, so a receiver point samples the texel the caster was drawn
            into and ``r`` is the depth that API stores.
        reversed_z: store ``1`` at near and ``0`` at far (see :func:`api_convention`).
        up: ``(*batch, 3)`` an up hint: light ``Y`` is the part of ``up``
            perpendicular to ``Z`` (as in a look-at camera) and ``X = Z x Y``, so
            the frame turns smoothly with the light instead of jumping where
            Nagy's helper axis switches.
        stable: for directional lights a shadow that does not shimmer: the
            extent comes from the blocker's bounding sphere about its vertices'
            mean (the same as the blocker turns), enlarged by half a texel, and
            the centre is snapped to whole texels of a grid anchored in world
            space, so the texels move by whole texels as the blocker or light
            moves and their size stays fixed. For point lights it means a frame
            that does not jump: ``up`` is required there.
        pcf_radius, pcf_filter: the PCF kernel the map will be filtered with:
            ``border_texels`` defaults to :func:`pcf_border_texels` of them.

    Directional fit: ``Z = -normalize(xyz)``, ``X, Y`` from the helper axis (or
    ``up``); in light coordinates about the blocker's bounding-box centre ``c``
    the frustum is the box ``[lo_x, hi_x] x [lo_y, hi_y]`` of the vertices
    (centre ``c_x = (hi_x + lo_x) / 2``, half-width ``R_x = (hi_x - lo_x) / 2``),
    and the frame's origin is ``c + Z (z_lo - pad)``, ``pad = (z_hi - z_lo) +
    max(R_x, R_y)``, behind every vertex (and counted receiver), so every ``z > 0``.
    The projection is orthographic (``frustum.orthographic``):

    .. math::

        P = \begin{bmatrix} s_x & 0 & 0 & -s_x c_x \\ 0 & s_y & 0 & -s_y c_y \\
            0 & 0 & \frac{2}{f - n} & -\frac{f + n}{f - n} \\ 0 & 0 & 0 & 1 \end{bmatrix},
        \qquad s_x = \frac{m_x}{R_x}

    so every vertex lies within the margins, some vertex on each of the four
    (``blocker_to_clip`` is affine: last row ``(0, 0, 0, 1)``).

    The options other than ``pcf_radius`` run on the array path (NumPy or JAX,
    whole arrays); the compiled loop serves point lights with the default options.

    Raises:
        ValueError: everything :func:`light_frame` and :func:`adaptive_frustum`
            raise, a non-finite or wrongly shaped ``blocker_to_world``, a zero
            directional light, receivers of the wrong shape or non-finite, an
            unknown ``api`` (the message lists the valid ones), an ``up`` zero or
            parallel to the light's direction, ``stable=True`` for a point light
            without ``up`` (value errors are NaN outputs under JAX transformations).

    Example:
        >>> import numpy as np
        >>> box = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (4, 6)])
        >>> s = fit_shadow([0, 0, 0], box, 100)
        >>> clip = (s.blocker_to_clip @ np.c_[box, np.ones(8)].T).T
        >>> float(np.abs(clip[:, 0] / clip[:, 3]).max().round(6))
        0.98
        >>> sun = fit_shadow([0.3, 1.0, -0.2, 0.0], box, 100, api="vulkan")  # directional
        >>> bool(sun.frustum.orthographic), sun.blocker_to_clip[3].tolist()
        (True, [0.0, 0.0, 0.0, 1.0])
    """
    check_aim(aim)
    if method not in ("mdv", "optimized"):
        raise ValueError(f"method: expected 'mdv' or 'optimized', got {method!r}")
    if border_texels is None:
        border_texels = 1 if pcf_radius is None else _pcf_border(pcf_radius, pcf_filter)
    m = margins(map_size, border_texels, margin)
    _check_api(api, reversed_z)
    if not isinstance(stable, bool | np.bool_):
        raise ValueError(f"stable: expected True or False, got {stable!r}")
    ctx, (light, verts, B, n, f, R, U) = convert(
        light_position=light_position,
        blocker_vertices=blocker_vertices,
        blocker_to_world=blocker_to_world,
        near=near,
        far=far,
        receivers=receivers,
        up=up,
    )
    homogeneous = light.ndim >= 1 and light.shape[-1] == 4
    if homogeneous or R is not None or U is not None or api != "opengl" or reversed_z or stable:
        if method != "mdv":
            raise ValueError(
                "method: 'optimized' fits point lights (x, y, z) without receivers, api, "
                "reversed_z, up or stable; use method='mdv' with them"
            )
        opts = SceneOptions(
            api, bool(reversed_z), bool(stable), homogeneous, _texels("map_size", map_size)
        )
        return _fit_scene(ctx, light, verts, B, n, f, R, U, m, aim, opts)
    require_last("light_position", light, 3, hint="a light position is (x, y, z)")
    require_vertices("blocker_vertices", verts)
    shape = light.shape[:-1]
    if B is not None or n is not None or f is not None or shape != verts.shape[:-2]:
        shape = _batch_shape(light, verts, B, n, f)
    if method == "optimized":
        from ._fitting import optimized_setup

        checks = Checks(ctx)
        world = check_placement(checks, verts, B)
        return optimized_setup(ctx, checks, light, world, B, m, n, f)
    if ctx.is_jax and not ctx.lazy:
        run, messages = _jitted_fit(m, aim, B is None, n is None, f is None)
        setup: ShadowSetup
        setup, bad = run(light, verts, B, n, f)
        raise_recorded(messages, bad)
        return setup
    if not ctx.is_jax and _kernels.available():
        return _fit_compiled(ctx, shape, light, verts, B, m, n, f, aim)
    return fit_core(ctx, Checks(ctx), light, verts, B, m, n, f, aim)


def _pcf_border(radius: int, filter: PcfFilter) -> int:
    k, filt = _check_kernel(radius, filter)
    return _border_texels(k, filt)


def _fit_scene(
    ctx: Context,
    light: Array,
    verts: Array,
    B: Array | None,
    n: Array | None,
    f: Array | None,
    R: Array | None,
    U: Array | None,
    m: tuple[float, float],
    aim: str,
    opts: SceneOptions,
) -> ShadowSetup:
    """The scene options' boundary: shapes, then the array path (a cached jit for JAX)."""
    if light.ndim < 1 or light.shape[-1] not in (3, 4):
        raise shape_error(
            "light_position",
            "(*batch, 3) or (*batch, 4)",
            tuple(light.shape),
            "a point light is (x, y, z); a homogeneous light (x, y, z, w), w = 0 directional",
        )
    require_vertices("blocker_vertices", verts)
    if R is not None:
        require_vertices("receivers", R)
    if U is not None:
        require_last("up", U, 3, hint="an up hint is (x, y, z)")
    if opts.stable:
        for name, mm, size in (("x", m[0], opts.texels[0]), ("y", m[1], opts.texels[1])):
            if mm * size <= 1:
                raise ValueError(
                    f"map_size: stable=True needs more than one texel inside the border "
                    f"along {name} (got {mm * size:g})"
                )
    _batch_shape(light, verts, B, n, f, R, U)
    if opts.stable and U is None and not opts.homogeneous:
        raise ValueError(STABLE_NEEDS_UP)
    if ctx.is_jax and not ctx.lazy:
        absent = tuple(v is None for v in (B, n, f, R, U))
        run, messages = _jitted_scene(m, aim, opts, absent)
        setup: ShadowSetup
        setup, bad = run(light, verts, B, n, f, R, U)
        raise_recorded(messages, bad)
        return setup
    return scene_fit(ctx, Checks(ctx), light, verts, B, n, f, R, U, m, aim, opts)


def scene_fit(
    ctx: Context,
    checks: Checks,
    light: Array,
    verts: Array,
    B: Array | None,
    n: Array | None,
    f: Array | None,
    R: Array | None,
    U: Array | None,
    m: tuple[float, float],
    aim: str,
    opts: SceneOptions,
) -> ShadowSetup:
    """:func:`scene_core` and its matrices, on shape-checked arrays."""
    xp = ctx.xp
    checks.require(all_finite(xp, light, 1), non_finite("light_position"))
    checks.require(all_finite(xp, verts, 2), non_finite("blocker_vertices"))
    world = check_placement(checks, verts, B)
    frame, frustum, W, clip, tex = scene_core(
        ctx, checks, light, world, B, R, U, m, n, f, aim, opts
    )
    shape = tuple(frustum.near.shape)
    placement = xp.eye(4, dtype=ctx.dtype) if B is None else B
    return ShadowSetup(
        frame=frame,
        frustum=frustum,
        world_to_light=checks.poison(xp.broadcast_to(stack_matrix(xp, W), (*shape, 4, 4)), 2),
        blocker_to_world=xp.broadcast_to(placement, (*shape, 4, 4)),
        blocker_to_clip=checks.poison(xp.broadcast_to(stack_matrix(xp, clip), (*shape, 4, 4)), 2),
        world_to_texture=checks.poison(xp.broadcast_to(stack_matrix(xp, tex), (*shape, 4, 4)), 2),
    )


def _batch_shape(
    light: Array,
    verts: Array,
    B: Array | None,
    near: Array | None,
    far: Array | None,
    R: Array | None = None,
    U: Array | None = None,
) -> tuple[int, ...]:
    """The broadcast batch shape of ``fit_shadow``'s arguments (checks ``B``'s shape)."""
    if B is not None:
        require_matrix("blocker_to_world", B)
    named = [("light_position", light.shape[:-1]), ("blocker_vertices", verts.shape[:-2])]
    named += [("blocker_to_world", B.shape[:-2])] if B is not None else []
    named += [(name, v.shape) for name, v in (("near", near), ("far", far)) if v is not None]
    named += [("receivers", R.shape[:-2])] if R is not None else []
    named += [("up", U.shape[:-1])] if U is not None else []
    return batch_shape(*(s for _, s in named), names=[name for name, _ in named])


@functools.cache
def _jitted_scene(
    m: tuple[float, float], aim: str, opts: SceneOptions, absent: tuple[bool, ...]
) -> tuple[Any, list[str]]:
    """:func:`scene_fit` under ``jax.jit`` for concrete JAX input (``absent``: cache key)."""

    def core(ctx: Context, checks: Checks, *a: Array) -> ShadowSetup:
        light, verts, B, near, far, R, U = a
        return scene_fit(ctx, checks, light, verts, B, near, far, R, U, m, aim, opts)

    return recorded_jit(core, _batch_of)


@functools.cache
def _jitted_fit(m: tuple[float, float], aim: str, *absent: bool) -> tuple[Any, list[str]]:
    """:func:`fit_core` under ``jax.jit`` for concrete JAX input (``absent``: cache key)."""

    def core(ctx: Context, checks: Checks, *a: Array) -> ShadowSetup:
        light, verts, B, near, far = a
        return fit_core(ctx, checks, light, verts, B, m, near, far, aim)

    return recorded_jit(core, _batch_of)


def _batch_of(setup: ShadowSetup) -> tuple[int, ...]:
    return tuple(setup.frustum.near.shape)


# The compiled loop's status bits and the array path's messages, in check order.
_STATUS_MESSAGES = (
    (_kernels.NONFINITE_LIGHT, non_finite("light_position")),
    (_kernels.NONFINITE_VERTICES, non_finite("blocker_vertices")),
    (_kernels.NONFINITE_PLACEMENT, non_finite("blocker_to_world")),
    (_kernels.PROJECTIVE_PLACEMENT, msg.PROJECTIVE_PLACEMENT),
    (_kernels.ZERO_DIRECTION, msg.ZERO_DIRECTION),
    (_kernels.BEHIND_LIGHT, msg.BEHIND_LIGHT),
    (_kernels.ZERO_SILHOUETTE, msg.ZERO_SILHOUETTE),
    (_kernels.NEAR_NOT_FINITE, msg.NEAR_NOT_FINITE),
    (_kernels.FAR_NOT_FINITE, msg.FAR_NOT_FINITE),
    (_kernels.NEAR_POSITIVE, msg.NEAR_POSITIVE),
    (_kernels.NEAR_FAR, msg.NEAR_FAR),
    (_kernels.NEAR_CLIPS, msg.NEAR_CLIPS),
    (_kernels.FAR_CLIPS, msg.FAR_CLIPS),
    (_kernels.OVERFLOW, msg.OVERFLOW),
)


_IDENTITY = np.eye(4).reshape(1, 4, 4)
_NONE = np.zeros(1)


def _fit_compiled(
    ctx: Context,
    shape: tuple[int, ...],
    light: Array,
    verts: Array,
    B: Array | None,
    m: tuple[float, float],
    near: Array | None,
    far: Array | None,
    aim: str,
) -> ShadowSetup:
    """:func:`fit_core`'s results from the compiled loop (NumPy input, Numba installed)."""
    count = math.prod(shape)
    out = np.empty((count, _kernels.ROW), dtype=ctx.dtype)
    mats = np.empty((count, 4, 4, 4), dtype=ctx.dtype)
    status = np.empty(count, dtype=np.int32)
    options = _options(aim, B is not None, near is not None, far is not None, m, ctx.dtype)
    _kernels.fit_kernel()(
        flat_batch(light, shape, (3,)) if shape else light[None],
        flat_batch(verts, shape, verts.shape[-2:]) if shape else verts[None],
        _IDENTITY if B is None else flat_batch(B, shape, (4, 4)),
        _NONE if near is None else flat_batch(near, shape, ()),
        _NONE if far is None else flat_batch(far, shape, ()),
        options,
        out,
        mats,
        status,
    )
    if status[0] if count == 1 else status.any():
        raise_status(status.reshape(shape), _status_messages(verts))
    # Views of the two output blocks (first-axis indexing: the cheapest views NumPy makes).
    if shape:
        v = np.moveaxis(out.reshape(*shape, _kernels.ROW), -1, 0)
        M = np.moveaxis(mats.reshape(*shape, 4, 4, 4), -3, 0)
        frame = LightFrame(*(np.moveaxis(v[i : i + 3], 0, -1) for i in (0, 3, 6, 9)))
        frustum = Frustum(*v[12:20])
    else:
        v, M = out[0], mats[0]
        frame = LightFrame(v[0:3], v[3:6], v[6:9], v[9:12])
        frustum = Frustum(*(v[..., i] for i in range(12, 20)))  # 0-d arrays, not scalars
    return ShadowSetup(frame, frustum, M[0], M[3], M[1], M[2])


@functools.lru_cache(maxsize=64)
def _options(
    aim: str, has_b: bool, has_near: bool, has_far: bool, m: tuple[float, float], dtype: Any
) -> Array:
    """The compiled loop's options (cached: the same few sets recur every frame)."""
    eps = float(np.finfo(dtype).eps)
    flags = [aim == "bbox", has_b, has_near, has_far, *m, eps, NEAR_FAR_SLACK, dtype == np.float32]
    options = np.array(flags, dtype=np.float64)
    options.flags.writeable = False
    return options


def _status_messages(verts: Array) -> tuple[tuple[int, str], ...]:
    """The loop's messages; a non-finite sum of finite vertices is an overflow."""
    if bool(np.isfinite(verts).all()):
        return tuple(
            (bit, msg.OVERFLOW if bit == _kernels.NONFINITE_VERTICES else message)
            for bit, message in _STATUS_MESSAGES
        )
    return _STATUS_MESSAGES


def receiver_texture_matrix(setup: ShadowSetup, receiver_to_world: Any) -> Array:
    """Receiver local coordinates straight to homogeneous shadow-map texture coordinates.

    ``setup.world_to_texture @ receiver_to_world``: the matrix a receiver's
    vertex shader applies to its local positions to get ``(s q, t q, r q, q)``.

    Arguments:
        setup: a :class:`ShadowSetup`.
        receiver_to_world: ``(*batch, 4, 4)`` the receiver's placement.

    Returns:
        ``(*batch, 4, 4)``.

    Raises:
        ValueError: wrong shape or non-finite values (NaN under JAX transformations).

    Example:
        >>> import numpy as np
        >>> s = fit_shadow([0, 0, 0], [[-1, -1, 4], [1, 1, 4], [1, -1, 5]], 64)
        >>> bool(np.allclose(receiver_texture_matrix(s, np.eye(4)), s.world_to_texture))
        True
    """
    ctx, (M, R) = convert(
        world_to_texture=setup.world_to_texture, receiver_to_world=receiver_to_world
    )
    xp = ctx.xp
    require_matrix("receiver_to_world", R)
    checks = Checks(ctx)
    checks.require(all_finite(xp, R, 2), non_finite("receiver_to_world"))
    return checks.poison(xp.matmul(M, R), 2)
