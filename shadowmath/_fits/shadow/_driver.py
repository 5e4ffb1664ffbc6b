"""The whole of Nagy's projective shadow texture set-up in one call: :func:`fit_shadow`.

A boundary: it reads the light's kind once (its type, or ``w`` of a homogeneous
``(x, y, z, w)``), makes the static :class:`shadowmath._fits._spec.FitKey`, converts and checks the
arrays' shapes once, then runs the one driver of the fit,
:func:`shadowmath._math._fit_entry.fit_entry`, on the trusted arrays in one of
three ways:

* NumPy input with Numba installed: compiled, per batch entry (:mod:`._compiled`);
  one small NumPy fit without Numba runs the same loop on Python floats;
* concrete JAX input: on whole arrays (:func:`._arrays.fit_arrays`) under a
  ``jax.jit`` cached per key, with the failed checks read back in one host sync;
* NumPy without Numba, or JAX inside a transformation: on whole arrays directly.
"""

from __future__ import annotations

import functools
from typing import Any, Literal

import numpy as np

from shadowmath._boundary import _messages as msg
from shadowmath._boundary._shapes import ArrayLike, BoolLike, Float, Real
from shadowmath._boundary._validate import (
    Array,
    Checks,
    Context,
    all_finite,
    convert,
    non_finite,
    raise_recorded,
    recorded_jit,
    require_matrix,
)
from shadowmath._fits._backend import form
from shadowmath._fits._spec import FitKey, ShadowMapSpec, map_spec
from shadowmath._geometry._light_frame import check_aim
from shadowmath._math._bias import PcfFilter
from shadowmath._math._conventions import GraphicsApi
from shadowmath._math._frame import LightFrame, stack_matrix
from shadowmath._math._frustum import volume
from shadowmath._math._specialize import formulas, scalar_formulas
from shadowmath._math._vector import matmul
from shadowmath.lights import Light
from shadowmath.receivers import Mesh, Triangles

from . import _compiled
from ._arrays import FitEntries, Inputs, driver, fit_arrays
from ._door import Operands, _check_shapes, door_for, refine, select_casters, warn_precision
from ._result import ShadowSetup

__all__ = ["ShadowSetup", "fit_shadow", "receiver_texture_matrix"]


def fit_shadow(
    light: Real[ArrayLike, "*#batch 3"] | Real[ArrayLike, "*#batch 4"] | Light,
    blocker_vertices: Real[ArrayLike, "*#batch N 3"] | Triangles | Mesh,
    map_size: int | tuple[int, int] | ShadowMapSpec,
    *,
    blocker_to_world: Real[ArrayLike, "*#batch 4 4"] | None = None,
    receivers: Real[ArrayLike, "*#batch M 3"] | Triangles | Mesh | None = None,
    up: Real[ArrayLike, "*#batch 3"] | None = None,
    near: Real[ArrayLike, "*#batch"] | None = None,
    far: Real[ArrayLike, "*#batch"] | None = None,
    aim: Literal["mean", "bbox"] = "mean",
    method: Literal["mdv", "optimized"] = "mdv",
    border_texels: int | None = None,
    pcf_radius: int | None = None,
    pcf_filter: PcfFilter = "box",
    margin: float | tuple[float, float] | None = None,
    api: GraphicsApi = "opengl",
    reversed_z: BoolLike = False,
    stable: BoolLike = False,
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
        light: a :class:`PointLight`, :class:`SpotLight` or :class:`DirectionalLight`
            (the kind is the type: only its fit runs, also under ``jit``); a ``(*batch, 3)`` point
            light position; or a ``(*batch, 4)`` homogeneous light ``(x, y, z, w)``,
            read once per call: all ``w != 0`` point lights at ``xyz / w``, all
            ``w == 0`` **directional** lights whose ``xyz`` points toward the light.
            A batch mixing both kinds is refused (split it by ``w == 0``), and so is
            a homogeneous light under a JAX transformation (pass a typed light).
        blocker_vertices: ``(*batch, N, 3)`` in the blocker's local coordinates
            (world coordinates when ``blocker_to_world`` is None), or the blocker's
            surfaces: :class:`Triangles` ``(*batch, M, 3, 3)`` or a :class:`Mesh` (their
            corners, for a point or directional light).
        map_size: ``size`` or ``(width, height)`` of the shadow map in texels, or a
            :class:`ShadowMapSpec` holding it with the options below (then give
            none of them as keywords).
        blocker_to_world: ``(*batch, 4, 4)`` the blocker's local-to-world placement.
        near, far: as in :func:`adaptive_frustum`, point lights only (a directional
            light's frame origin, and so its depth range, is placed by the fit).
        border_texels, pcf_radius, pcf_filter, margin, api, reversed_z, stable: the
            map's options, as in :class:`ShadowMapSpec` (one of ``border_texels``,
            ``pcf_radius`` and ``margin`` at most).
        aim: as in :func:`light_frame` (for ``method="mdv"``).
        method: ``"mdv"`` (default) the article's frame and symmetric frustum;
            ``"optimized"`` the frame and off-centre frustum of
            :func:`optimize_frustum` (needs JAX; point lights ``(x, y, z)`` without
            the scene options below).
        receivers: what the shadow falls on, in world coordinates:
            :class:`Triangles` ``(*batch, M, 3, 3)`` or a :class:`Mesh` (surfaces),
            or a ``(*batch, M, 3)`` array of points. The frustum's sides still fit
            the casters; ``far`` also holds every receiver point that the map
            covers (inside the side planes, ``|x_ndc|, |y_ndc| <= 1``, and in front
            of a point light): for triangles, their parts clipped exactly by the
            side planes, so a floor whose corners all lie outside the map still
            counts. Receivers only ever push ``far``: one nearer to the light than
            every caster can never be shadowed, so ``near`` stays the casters'
            (depth precision); such a receiver gets a depth before ``near``
            (below 0 in texture depth, above 1 with ``reversed_z``), which the
            recommended shader treats as lit, as it is. Receivers outside the
            side planes are lit by the map (clamp-to-border). Receivers never add
            batch dimensions: their batch shape broadcasts into the other
            arguments' (a raw ``(M, 3, 3)`` array is ``M`` sets of three points,
            refused beside one light and caster set: wrap triangles in
            :class:`Triangles`).
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
            extent comes from the blocker's minimal enclosing sphere (Welzl's
            algorithm: a property of the shape, the same however it is
            tessellated or turned), enlarged by half a texel, and
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
    max(R_x, R_y)``, behind every vertex, so every ``z > 0``.
    The projection is orthographic (``frustum`` is an :class:`OrthographicBox`):

    .. math::

        P = \begin{bmatrix} s_x & 0 & 0 & -s_x c_x \\ 0 & s_y & 0 & -s_y c_y \\
            0 & 0 & \frac{2}{f - n} & -\frac{f + n}{f - n} \\ 0 & 0 & 0 & 1 \end{bmatrix},
        \qquad s_x = \frac{m_x}{R_x}

    so every vertex lies within the margins, some vertex on each of the four
    (``blocker_to_clip`` is affine: last row ``(0, 0, 0, 1)``).

    Spot lights select their casters first (:mod:`shadowmath._math._spot_casters`): a
    receiver point inside the cone is shadowed only by geometry on its segment to the
    light, inside the cone, so what lies outside the cone's square pyramid
    ``|x|, |y| <= t z`` (``t = tan(angle)``, in the fit's frame) is dropped. Triangles
    (:class:`Triangles`, :class:`Mesh`) are clipped exactly to the pyramid (a triangle
    crossing the light's plane counts by its part in front; with a placement the
    planes act on local points as ``B^T pi``); a vertex set keeps its vertices in front
    of the light (their box clipped to the cone's square, as always) and drops those
    behind. ``casters_used`` counts what was kept. With nothing left (every caster
    behind the spot or outside its cone) the result is the **empty fit**: the square
    ``|x|, |y| <= min(t, 1) z`` at the casters' largest ``|z|`` (1 if zero), a finite
    frustum inside the pyramid that no caster enters, ``casters_used == 0``
    (receivers still push ``far``). Draw every caster with it: the GPU clips the rest
    (behind the light: ``w < 0``). Point lights keep every caster: their one frustum
    aims at the casters and has no fixed "behind" (use a spot light or a cube map).

    Every light and option runs the same fit steps (:mod:`shadowmath._math._fit_formulas`): in the
    compiled loop for NumPy input with the ``fast`` extra, on whole arrays otherwise.

    Raises:
        ValueError: everything :func:`light_frame` and :func:`adaptive_frustum`
            raise, a non-finite or wrongly shaped ``blocker_to_world``, one whose last row
            is not ``(0, 0, 0, 1)`` to rounding (``4 eps`` times its largest entry: a
            row-major, transposed, or a projective placement), a zero
            directional light, receivers of the wrong shape or non-finite or with batch
            dimensions that no other argument has, an
            unknown ``api`` (the message lists the valid ones), an ``up`` zero or
            parallel to the light's direction, a singular ``blocker_to_world``
            (its linear part's ``|det| <= 64 eps`` times its rows' norms), the nearest
            caster within rounding of a point or spot light (``z <= 32 eps`` times the
            coordinates' magnitude; for a point light also a caster behind it), a
            point-light frustum wider than 170 degrees (the light too
            close to the blocker: use a cube map or a spot cone), coordinates so far from
            the origin for their dtype that the casters' extent is within 32 rounding steps
            (``eps`` times the largest coordinate; the message names the precision where the
            fit's own rounding checks would have refused) (value errors are
            NaN outputs under JAX transformations); and, whatever the values:
            ``stable=True`` for a point light without ``up``, ``near``/``far`` for a
            directional light, a batch of homogeneous lights mixing ``w = 0`` and
            ``w != 0``, a homogeneous light under a JAX transformation, options given
            both in a :class:`ShadowMapSpec` and as keywords.

    Warns:
        ShadowFitWarning: NumPy input only (JAX gives no warnings): a point-light
            frustum wider than 120 degrees (a texel at the edge then sees a quarter
            of the angle of one at the centre or less), a map whose border
            leaves less than half of its texels per axis (from :class:`ShadowMapSpec`),
            and float32 coordinates whose rounding step (``eps`` times the largest
            coordinate of the light and casters) exceeds a quarter of a texel (the casters'
            extent over the map's larger side): far from the origin; pass float64, or
            recentre the coordinates about a nearby origin.

    Example:
        >>> import numpy as np
        >>> box = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (4, 6)])
        >>> s = fit_shadow([0, 0, 0], box, 100)
        >>> clip = (s.blocker_to_clip @ np.c_[box, np.ones(8)].T).T
        >>> float(np.abs(clip[:, 0] / clip[:, 3]).max().round(6))
        0.98
        >>> spec = ShadowMapSpec(100, api="vulkan")
        >>> sun = fit_shadow(DirectionalLight(np.array([0.3, 1.0, -0.2])), box, spec)
        >>> type(sun.frustum).__name__, sun.blocker_to_clip[3].tolist()
        ('OrthographicBox', [0.0, 0.0, 0.0, 1.0])
    """
    check_aim(aim)
    if method not in ("mdv", "optimized"):
        raise ValueError(f"method: expected 'mdv' or 'optimized', got {method!r}")
    spec = map_spec(map_size, border_texels=border_texels, pcf_radius=pcf_radius,
                    pcf_filter=pcf_filter, margin=margin, api=api, reversed_z=reversed_z,
                    stable=stable)  # fmt: skip
    operands = Operands(light, blocker_vertices, blocker_to_world, receivers, up, near, far)
    door = door_for(operands, spec, aim == "bbox", method)
    try:
        a, used = select_casters(door)
        setup = _fit(door.ctx, a, door.shape, door.key, method, used=used)
    except ValueError as err:
        refined = refine(door, err)
        if refined is err:
            raise
        raise refined from err
    if door.ctx.dtype == _SINGLE and not door.ctx.is_jax:  # (float64: see warn_precision)
        warn_precision(door)
    return setup


_SINGLE = np.dtype(np.float32)


def _fit(
    ctx: Context, a: Inputs, shape: tuple[int, ...], key: FitKey, method: str, *, used: Array
) -> ShadowSetup:
    """The fit of trusted, shape-checked inputs by the driver that suits them, with
    ``casters_used``."""
    if method == "optimized":
        return _optimized(ctx, a, key.margins)._replace(casters_used=used, map_size=key.texels)
    small = not shape and _points(a) <= _compiled.PYTHON_LOOP_POINTS
    chosen = form(not ctx.is_jax, small=small)
    if chosen != "arrays":
        return _compiled.fit(ctx, key, shape, a, used=used, python=chosen == "python")
    return _fit_on_arrays(ctx, a, shape, key)._replace(casters_used=used, map_size=key.texels)


def _fit_on_arrays(ctx: Context, a: Inputs, shape: tuple[int, ...], key: FitKey) -> ShadowSetup:
    """The fit on whole arrays: JAX (under one cached ``jax.jit`` when concrete), or NumPy
    without Numba."""
    if ctx.is_jax and not ctx.lazy:
        run, messages = _jitted_fit(key)
        setup: ShadowSetup
        setup, bad = run(*a)
        raise_recorded(messages, bad)
        return setup
    checks = Checks(ctx)
    if ctx.is_jax:
        entries = fit_arrays(ctx, checks, key, a, driver(ctx, scalar=False))
        return assemble(ctx, checks, key, shape, entries, B=a.B)
    scalar = not shape
    with np.errstate(all="ignore"):  # invalid entries are reported by the checks, in order
        entries = fit_arrays(ctx, checks, key, a, driver(ctx, scalar))
    if scalar:
        return assemble_one(ctx, key, a.B, entries)
    return assemble(ctx, checks, key, shape, entries, B=a.B)


def _points(a: Inputs) -> int:
    """Vertices plus receiver points (three per triangle)."""
    return int(a.verts.shape[-2]) + (0 if a.R is None else a.R.shape[-2] * a.R.shape[-1] // 3)


def _optimized(ctx: Context, a: Inputs, m: tuple[float, float]) -> ShadowSetup:
    from ._optimize_frustum import optimized_setup

    checks = Checks(ctx)
    xp = ctx.xp
    checks.require(all_finite(xp, a.light, 1), non_finite("light"))
    checks.require(all_finite(xp, a.verts, 2), non_finite("blocker_vertices"))
    world = a.verts
    if a.B is not None:
        checks.require(all_finite(xp, a.B, 2), non_finite("blocker_to_world"))
        F = formulas(xp)
        entries = tuple(a.B[..., i // 4, i % 4] for i in range(16))
        checks.require(F.placement_affine(entries, ctx.eps), msg.AFFINE_PLACEMENT)
        b = tuple(a.B[..., None, i // 4, i % 4] for i in range(16))
        *p, w = F.place(b, a.verts[..., 0], a.verts[..., 1], a.verts[..., 2])
        checks.require(xp.all(w > 0, axis=-1), msg.PROJECTIVE_PLACEMENT)
        world = xp.stack(p, axis=-1)
    return optimized_setup(ctx, checks, a.light, world, a.B, m=m, near=a.near, far=a.far)


def assemble(
    ctx: Context,
    checks: Checks,
    key: FitKey,
    shape: tuple[int, ...],
    e: FitEntries,
    *,
    B: Array | None,
) -> ShadowSetup:
    """The :class:`ShadowSetup` of a fit's per-entry results (invalid entries poisoned)."""
    xp = ctx.xp
    if checks.invalid is not None:
        checks.invalid = xp.broadcast_to(checks.invalid, shape)

    def vec(v: tuple[Array, ...]) -> Array:
        stacked = xp.stack([xp.broadcast_to(c, shape) for c in v], axis=-1)
        return checks.poison(stacked, 1)

    def matrix(entries: tuple[Array, ...]) -> Array:
        return checks.poison(xp.broadcast_to(stack_matrix(xp, entries), (*shape, 4, 4)), 2)

    def field(v: Array) -> Array:
        return checks.poison(xp.broadcast_to(xp.asarray(v, dtype=ctx.dtype), shape), 0)

    half_x, half_y, near, far, cx, cy = e.box
    mx, my = (xp.broadcast_to(ctx.constant(m), shape) for m in key.margins)
    frustum = volume(
        (field(half_x), field(half_y), field(near), field(far), mx, my, field(cx), field(cy)),
        key.directional,
    )
    clip = e.clip
    if B is not None:
        clip = formulas(xp).compose_rows(clip, tuple(B[..., i // 4, i % 4] for i in range(16)))
    placement = xp.eye(4, dtype=ctx.dtype) if B is None else B
    return ShadowSetup(
        frame=LightFrame(vec(e.origin), vec(e.axes[0:3]), vec(e.axes[3:6]), vec(e.axes[6:9])),
        frustum=frustum,
        world_to_light=matrix(e.W),
        blocker_to_world=xp.broadcast_to(placement, (*shape, 4, 4)),
        blocker_to_clip=matrix(clip),
        world_to_texture=matrix(e.tex),
    )


def assemble_one(ctx: Context, key: FitKey, B: Array | None, e: FitEntries) -> ShadowSetup:
    """:func:`assemble` for one NumPy entry computed on Python floats (valid: checks raised)."""
    dtype = ctx.dtype
    clip = e.clip
    if B is not None:
        clip = scalar_formulas().compose_rows(clip, tuple(B.reshape(16).tolist()))
    W = (*e.W, 0.0, 0.0, 0.0, 1.0)
    mats = np.array((W, clip, e.tex), dtype=dtype).reshape(3, 4, 4)
    half_x, half_y, near, far, cx, cy = e.box
    fields = np.array((half_x, half_y, near, far, *key.margins, cx, cy), dtype=dtype)
    frame = np.array((*e.origin, *e.axes), dtype=dtype).reshape(4, 3)
    return ShadowSetup(
        frame=LightFrame(*frame),
        frustum=volume(tuple(fields[..., i] for i in range(8)), key.directional),
        world_to_light=mats[0],
        blocker_to_world=np.eye(4, dtype=dtype) if B is None else B,
        blocker_to_clip=mats[1],
        world_to_texture=mats[2],
    )


@functools.cache
def _jitted_fit(key: FitKey) -> tuple[Any, list[str]]:
    """:func:`fit_arrays` and :func:`assemble` under ``jax.jit`` for concrete JAX input."""

    def core(ctx: Context, checks: Checks, *arrays: Array) -> ShadowSetup:
        a = Inputs(*arrays)
        shape = _check_shapes(a)
        entries = fit_arrays(ctx, checks, key, a, driver(ctx, scalar=False))
        return assemble(ctx, checks, key, shape, entries, B=a.B)

    return recorded_jit(core, _batch_of)


def _batch_of(setup: ShadowSetup) -> tuple[int, ...]:
    return tuple(setup.frustum.near.shape)


def receiver_texture_matrix(
    setup: ShadowSetup, receiver_to_world: Real[ArrayLike, "*#batch 4 4"]
) -> Float[Array, "*batch 4 4"]:
    """Receiver local coordinates straight to homogeneous shadow-map texture coordinates.

    ``setup.world_to_texture @ receiver_to_world``: the matrix a receiver's
    vertex shader applies to its local positions to get ``(s q, t q, r q, q)``.

    Arguments:
        setup: a :class:`ShadowSetup`.
        receiver_to_world: ``(*batch, 4, 4)`` the receiver's placement.

    Returns:
        ``(*batch, 4, 4)``.

    Raises:
        ValueError: wrong shape, non-finite values, or a last row other than
            ``(0, 0, 0, 1)`` to rounding (a row-major or projective matrix) (NaN under
            JAX transformations).

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
    entries = tuple(R[..., i // 4, i % 4] for i in range(16))
    affine = formulas(xp).placement_affine(entries, ctx.eps)
    checks.require(affine, msg.not_affine("receiver_to_world"))
    return checks.poison(matmul(xp, M, R), 2)
