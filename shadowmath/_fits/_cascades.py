r"""Cascaded shadow maps fitted to a camera: :func:`fit_cascades`.

A boundary and two drivers of the same formulas (:mod:`shadowmath._math._cascade_formulas`):

* NumPy input: the loop of :mod:`shadowmath._math._cascade_loop` over cameras and
  cascades, compiled by Numba (the ``fast`` extra), or run by Python on lists for one
  to :data:`PYTHON_LOOP_CAMERAS` cameras without Numba;
* JAX input (and NumPy batches without Numba): the array driver below, vectorized over
  the batch, the cascades and the 24 clipped edges; values and gradients follow the
  same expressions. ``warp="lispsm"`` runs here only.

The boundary converts and checks the arguments once; each driver reports its failed
checks with the same messages.
"""

from __future__ import annotations

import functools
import math
from typing import Any, Literal, NamedTuple

import numpy as np

from shadowmath._backends import _kernels
from shadowmath._boundary import _messages as msg
from shadowmath._boundary._projection import check_projection
from shadowmath._boundary._shapes import ArrayLike, Float, Int, Real
from shadowmath._boundary._validate import (
    Array,
    Checks,
    Context,
    all_finite,
    batch_shape,
    convert,
    flat_batch,
    non_finite,
    raise_status,
    require_last,
    require_matrix,
)
from shadowmath._math._bias import PcfFilter
from shadowmath._math._cascade_formulas import EDGES
from shadowmath._math._cascade_loop import CHECKS, ROW
from shadowmath._math._conventions import GraphicsApi, _check_api, _clip_from_gl
from shadowmath._math._frustum import NEAR_FAR_SLACK, Frustum
from shadowmath._math._specialize import formulas, scalar_formulas
from shadowmath.lights import DirectionalLight

from ._cascade_splits import (
    LOG_NEAR,
    SplitScheme,
    check_count,
    check_range,
    check_scheme,
    split_depths,
)
from ._lispsm import check_warp, warp_cascades
from ._spec import ShadowMapSpec, api_rows, map_spec

__all__ = ["Cascades", "fit_cascades"]

CascadeLayout = Literal["layers", "atlas"]


class Cascades(NamedTuple):
    """Everything a renderer needs to draw and sample a directional light's cascades.

    ``n`` is the number of cascades; every matrix is in the ``api``'s conventions.

    Attributes:
        world_to_light: ``(*batch, n, 4, 4)`` world to each cascade's light
            coordinates (one rotation for all; origins differ along ``Z`` only).
        frustum: the orthographic :class:`Frustum` of each cascade, fields ``(*batch, n)``.
        world_to_clip: ``(*batch, n, 4, 4)`` world to the cascade's clip coordinates:
            draw the casters into cascade ``i`` with ``world_to_clip[i] @ model``.
        world_to_texture: ``(*batch, n, 4, 4)`` world to ``(s, t, r, 1)``: texture
            coordinates in the cascade's layer, or in the atlas (``layout="atlas"``),
            and the stored depth ``r`` to compare with.
        splits: ``(*batch, n + 1)`` the view depths that bound the cascades: cascade
            ``i`` serves view depths ``[splits[i], splits[i + 1])``.
        band_end: ``(*batch, n)`` cascade ``i`` is fitted out to ``band_end[i] >=
            splits[i + 1]``; in ``[splits[i + 1], band_end[i]]`` the shader blends
            cascades ``i`` and ``i + 1`` (weight of ``i + 1``: the fraction of the band
            passed). The last cascade has no band (``band_end = splits[n]``).
        texel_size: ``(*batch, n, 2)`` the world size of one texel along light ``X``
            and ``Y`` (for normal-offset and slope bias).
        viewports: ``(n, 4)`` integers ``(x, y, width, height)`` of each cascade's
            tile in the atlas, in the API's own viewport convention (``(0, 0, W, H)``
            for every cascade with ``layout="layers"``).
        texture_size: ``(width, height)`` in texels of the depth texture to allocate
            (the same for every batch entry): each layer's, ``(W, H)``, with
            ``layout="layers"``; the atlas's, ``(cols W, rows H)`` (``cols =
            ceil(sqrt(n))``, ``rows = ceil(n / cols)``), with ``layout="atlas"``.
            Every viewport lies inside it.
        texture_layers: the texture's layer count: ``n`` with ``layout="layers"``
            (a texture array), 1 with ``layout="atlas"``.
    """

    world_to_light: Float[Array, "*batch n 4 4"]
    frustum: Frustum
    world_to_clip: Float[Array, "*batch n 4 4"]
    world_to_texture: Float[Array, "*batch n 4 4"]
    splits: Float[Array, "*batch n+1"]
    band_end: Float[Array, "*batch n"]
    texel_size: Float[Array, "*batch n 2"]
    viewports: Int[Array, "n 4"]
    texture_size: tuple[int, int]
    texture_layers: int


def fit_cascades(
    light: Real[ArrayLike, "*#batch 3"] | Real[ArrayLike, "*#batch 4"] | DirectionalLight,
    view: Real[ArrayLike, "*#batch 4 4"],
    projection: Real[ArrayLike, "*#batch 4 4"],
    scene_bounds: Real[ArrayLike, "*#batch 2 3"],
    map_size: int | tuple[int, int] | ShadowMapSpec,
    *,
    count: int = 4,
    splits: Real[ArrayLike, "*#batch _"] | None = None,
    scheme: SplitScheme = "practical",
    lam: Real[ArrayLike, "*#batch"] = 0.75,
    max_distance: Real[ArrayLike, "*#batch"] | None = None,
    overlap: Real[ArrayLike, "*#batch"] = 0.1,
    up: Real[ArrayLike, "*#batch 3"] | None = None,
    stable: bool = False,
    border_texels: int | None = None,
    pcf_radius: int | None = None,
    pcf_filter: PcfFilter = "box",
    api: GraphicsApi = "opengl",
    reversed_z: bool = False,
    camera_api: GraphicsApi | None = None,
    camera_reversed_z: bool = False,
    layout: CascadeLayout = "layers",
    warp: Literal[None, "lispsm"] = None,
) -> Cascades:
    r"""Fit a directional light's cascaded shadow maps to what a camera sees.

    The camera's view depth range ``[near, far]`` (or ``[near, max_distance]``) is
    cut at :func:`cascade_splits`; cascade ``i`` covers the frustum slice between
    ``splits[i]`` and ``band_end[i]`` (its split plus ``overlap`` of its length,
    for blending). Each cascade's orthographic map is fitted in one light frame
    (``Z`` along the light's travel, the helper axis or ``up`` for ``Y``):

    * **lateral box**: the light-space bounds of the slice intersected exactly
      with ``scene_bounds`` (the convex polyhedron's vertices are the clipped
      ends of both solids' edges), so no texel covers empty space beside the
      scene; with ``stable=True`` instead a square of fixed size, the slice's
      bounding sphere (which depends on the projection and the splits only) plus
      half a texel, its centre snapped to whole texels of a grid anchored at the
      world origin: as the camera moves and turns, every cascade keeps its size
      and its texel grid moves by whole texels;
    * **depth**: from the scene box's corner nearest the light (every caster that
      can shadow the slice lies behind it, seen or not) to the slice's deepest
      point in the scene, widened by ``NEAR_FAR_SLACK``;
    * **border**: each map leaves ``border_texels`` (or the PCF kernel's border)
      on every side, so a PCF kernel never reads past its cascade (nor, in an
      atlas, into a neighbour's tile).

    Arguments:
        light: :class:`DirectionalLight`, or ``(*batch, 3)`` a direction toward the
            light, or ``(*batch, 4)`` with ``w = 0``.
        view: ``(*batch, 4, 4)`` the camera's world-to-view matrix (rigid, affine).
        projection: ``(*batch, 4, 4)`` its projection, in ``camera_api``'s clip
            conventions (perspective or orthographic; an infinite far plane needs
            ``max_distance``), a column-vector matrix (``clip = projection @ p_view``)
            with its last row as every API writes it: ``(0, 0, -1, 0)`` or
            ``(0, 0, 1, 0)`` (perspective, looking down ``-z`` or ``+z``) or
            ``(0, 0, 0, 1)`` (orthographic), to rounding; any depth row (reversed Z,
            ``[0, 1]`` or ``[-1, 1]`` depth, an infinite far plane).
        scene_bounds: ``(*batch, 2, 3)`` the scene's box, ``[min_corner, max_corner]``:
            every caster and receiver inside it.
        map_size: each cascade's map, ``size``, ``(width, height)`` or a
            :class:`ShadowMapSpec` holding it with the map's options (then give none of
            ``border_texels``, ``pcf_radius``, ``pcf_filter``, ``api``, ``reversed_z``
            and ``stable`` as keywords: as in :func:`fit_shadow`, an option given in
            both is refused; its ``margin`` is not used).
        count: the number of cascades (ignored when ``splits`` is given).
        splits: ``(*batch, n + 1)`` custom increasing view depths within the
            camera's range, instead of a scheme.
        scheme, lam: :func:`cascade_splits`'s scheme and blend.
        max_distance: ``(*batch,)`` the shadow distance: the last split (at most
            the camera's far plane).
        overlap: the blend band, a fraction of each cascade's length in ``[0, 1)``.
        up: ``(*batch, 3)`` optional up hint of the light frame.
        stable: fixed sizes and texel-snapped centres (see above).
        border_texels, pcf_radius, pcf_filter: the map's border, as in
            :class:`ShadowMapSpec`.
        api, reversed_z: the shadow maps' graphics API conventions.
        camera_api, camera_reversed_z: the conventions of ``projection``
            (default: ``api`` and not reversed).
        layout: ``"layers"`` (one texture layer per cascade) or ``"atlas"`` (tiles
            in a grid of ``ceil(sqrt(n))`` columns, each ``map_size``); the texture
            to allocate is ``texture_size`` (with ``texture_layers``) of the result.
        warp: ``"lispsm"``: light-space perspective warping of each cascade (Wimmer
            et al. 2004, ``docs/lispsm.md``): more texels near the eye; the matrices
            then have ``q = w != 1`` (divide by it) and ``texel_size`` is the largest
            texel, along the map's axes; ``frustum`` stays the unwarped box. Falls
            back to the orthographic cascade where the view is within ~1.15 degrees
            of the light (``sin < 0.02``) or the camera is orthographic. Not with
            ``stable=True`` (``ValueError``).

    Returns:
        :class:`Cascades`.

    Raises:
        ValueError: wrong shapes, non-finite values, a non-invertible view or
            projection, a projective view, a ``projection`` whose last row is
            neither perspective nor orthographic (a transposed or scaled matrix), a
            zero light direction, ``up`` parallel to the light, an inverted
            ``scene_bounds``, splits outside the camera's range or not increasing, bad
            scheme options (these are NaN under JAX transformations); and whatever the
            values: map options given both in a :class:`ShadowMapSpec` and as keywords.

    Example:
        >>> import numpy as np, shadowmath as sm
        >>> view = np.eye(4); view[2, 3] = -1.0                 # camera at z = 1, looking down -z
        >>> f, n, far = 1.0, 0.1, 50.0                          # 90 degree OpenGL perspective
        >>> proj = np.array([[f, 0, 0, 0], [0, f, 0, 0],
        ...                  [0, 0, (far + n) / (n - far), 2 * far * n / (n - far)], [0, 0, -1, 0]])
        >>> box = np.array([[-20.0, -20.0, -60.0], [20.0, 20.0, 2.0]])
        >>> c = sm.fit_cascades(np.array([0.3, 0.2, 1.0]), view, proj, box, 1024)
        >>> c.world_to_clip.shape, c.splits.shape
        ((4, 4, 4), (5,))
    """
    spec = map_spec(map_size, border_texels=border_texels, pcf_radius=pcf_radius,
                    pcf_filter=pcf_filter, api=api, reversed_z=reversed_z,
                    stable=stable)  # fmt: skip
    check_warp(warp, spec.stable)
    cam_api = spec.api if camera_api is None else camera_api
    _check_api(cam_api, camera_reversed_z)
    if layout not in ("layers", "atlas"):
        raise ValueError(f"layout: expected 'layers' or 'atlas', got {layout!r}")
    direction = light.direction if isinstance(light, DirectionalLight) else light
    fixed = check_scheme(scheme)
    n_given = None if splits is not None else check_count(count)
    lam_v = lam if fixed is None else fixed
    # Python numbers stay Python numbers (the common case): no array conversion per frame.
    plain = all(type(v) in (float, int) for v in (lam_v, overlap)) and (
        max_distance is None or type(max_distance) in (float, int)
    )
    ctx, (L, V, P, box, S, U, dmax, lm, ov) = convert(
        light=direction, view=view, projection=projection, scene_bounds=scene_bounds,
        splits=splits, up=up, max_distance=None if plain else max_distance,
        lam=None if plain else lam_v, overlap=None if plain else overlap,
    )  # fmt: skip
    if plain:
        lm, ov = float(lam_v), float(overlap)
        dmax = None if max_distance is None else float(max_distance)
    checks = Checks(ctx)
    L = _light_vector(checks, L)
    require_matrix("view", V)
    check_projection(checks, P)
    require_last("scene_bounds", box, 3, min_ndim=2, hint="[min_corner, max_corner]")
    if box.shape[-2] != 2:
        raise ValueError(
            f"scene_bounds: expected shape (*batch, 2, 3) ([min_corner, max_corner]), "
            f"got {tuple(box.shape)}"
        )
    if U is not None:
        require_last("up", U, 3)
    if S is not None:
        require_last("splits", S, S.shape[-1] if S.ndim else 2)
        if S.shape[-1] < 2:
            raise ValueError(
                f"splits: expected (*batch, n + 1) depths, n >= 1, got {tuple(S.shape)}"
            )
    shapes = [L.shape[:-1], V.shape[:-2], P.shape[:-2], box.shape[:-2]]
    names = ["light", "view", "projection", "scene_bounds"]
    for name, v, drop in (("up", U, 1), ("splits", S, 1), ("max_distance", dmax, 0)):
        if v is not None and not isinstance(v, float):
            shapes.append(v.shape[: v.ndim - drop])
            names.append(name)
    shape = batch_shape(*shapes, names=names)
    C = _clip_from_gl(cam_api, camera_reversed_z)
    if ctx.xp is np and warp is None:
        python = not _kernels.available()
        if not python or (_kernels.python_loop() and math.prod(shape) <= PYTHON_LOOP_CAMERAS):
            arrays = (L, V, P, box, U, S, dmax, lm, ov)
            try:
                return _compiled(ctx, spec, layout, shape, arrays, C, n_given, python)
            except (ZeroDivisionError, OverflowError):
                pass  # Python floats raise where Numba's give inf: invalid input, which the
                # array driver below reports with its message
    if plain:
        lm, ov = ctx.constant(lm), ctx.constant(ov)
        dmax = None if dmax is None else ctx.constant(dmax)
    cam = _camera(ctx, checks, V, P, C)
    depths = _splits(ctx, checks, cam, S, dmax, lm, ov, fixed, n_given)
    _value_checks(checks, L, box, U)
    return _fit(ctx, checks, spec, layout, shape, (L, V, box, U), cam, depths, warp)


def _light_vector(checks: Checks, L: Array) -> Array:
    """A direction toward the light: ``(*batch, 3)``, or the ``xyz`` of a ``w = 0`` 4-vector."""
    if L.ndim == 0 or L.shape[-1] not in (3, 4):
        raise ValueError(
            f"light: expected a direction (*batch, 3) or (x, y, z, 0), got {tuple(L.shape)}"
        )
    if L.shape[-1] == 4:
        checks.require(
            L[..., 3] == 0, "light: cascades need a directional light (w = 0 in (x, y, z, w))"
        )
        L = L[..., :3]
    return L


def _value_checks(checks: Checks, L: Array, box: Array, U: Array | None) -> None:
    xp = checks.ctx.xp
    checks.require(all_finite(xp, L, 1), non_finite("light"))
    checks.require(all_finite(xp, box, 2), non_finite("scene_bounds"))
    checks.require(xp.all(box[..., 1, :] >= box[..., 0, :], axis=-1), MESSAGES["bounds_order"])
    if U is not None:
        checks.require(all_finite(xp, U, 1), non_finite("up"))


class Camera(NamedTuple):
    """A camera's frustum edges in view space and its depth conventions (per batch entry)."""

    near_corners: Array  # (*b, 4, 3): the near plane's corners, i + 2 j
    far_corners: Array  # (*b, 4, 4): the far plane's, homogeneous (w >= 0)
    sign: Array  # (*b,): view depth = sign * z_view
    near: Array  # (*b,) view depth of the near plane
    far: Array  # (*b,) view depth of the far plane (inf for an infinite far plane)
    view_to_world: Array  # (*b, 4, 4)
    clip_rows: Array  # (*b, 4, 4): projection @ view (its rows x, y and w are used)


def _camera(ctx: Context, checks: Checks, V: Array, P: Array, C: Any) -> Camera:
    """The camera's frustum from ``view`` and ``projection`` (``C``: OpenGL clip to theirs)."""
    xp = ctx.xp
    checks.require(all_finite(xp, V, 2), non_finite("view"))
    checks.require(all_finite(xp, P, 2), non_finite("projection"))
    last = xp.asarray([0.0, 0.0, 0.0, 1.0], dtype=ctx.dtype)
    checks.require(xp.all(V[..., 3, :] == last, axis=-1), MESSAGES["view_affine"])
    eps = ctx.eps
    # The linear part's Hadamard test, as a blocker's placement's (free of scale).
    ok_v = formulas(xp).placement_ok(tuple(V[..., i // 4, i % 4] for i in range(16)), eps)
    checks.require(ok_v, MESSAGES["view_singular"])
    pscale = xp.prod(xp.sqrt(xp.sum(P**2, axis=-1)), axis=-1)
    ok_p = xp.abs(xp.linalg.det(P)) > 64 * eps * pscale
    checks.require(ok_p, MESSAGES["projection_singular"])
    safe = ~(ok_p & ok_v)
    eye = xp.eye(4, dtype=ctx.dtype)
    Vs = xp.where(safe[..., None, None], eye, V)
    Ps = xp.where(safe[..., None, None], eye, P)
    inv_v, inv_p = xp.linalg.inv(Vs), xp.linalg.inv(Ps)
    # The eight NDC corners of OpenGL's cube, in the camera API's clip space.
    corners = (
        np.array([[x, y, z, 1.0] for z in (-1.0, 1.0) for y in (-1.0, 1.0) for x in (-1.0, 1.0)])
        @ np.asarray(C, dtype=float).T
    )
    hom = xp.matmul(xp.asarray(corners, dtype=ctx.dtype), xp.swapaxes(inv_p, -1, -2))
    near_h, far_h = hom[..., :4, :], hom[..., 4:, :]
    near = near_h[..., :3] / near_h[..., 3:]
    far = xp.where(far_h[..., 3:] < 0, -far_h, far_h)
    far = far / xp.max(xp.abs(far), axis=-1, keepdims=True)
    nz = xp.mean(near[..., 2], axis=-1)
    fw = xp.mean(far[..., 3], axis=-1)
    fz = xp.mean(far[..., 2], axis=-1)
    finite_far = fw > 32 * eps
    safe_fw = xp.where(finite_far, fw, xp.ones_like(fw))
    sign = xp.where(finite_far, xp.sign(fz / safe_fw - nz), xp.sign(nz))
    sign = xp.where(sign == 0, xp.ones_like(sign), sign)
    far_depth = xp.where(finite_far, sign * fz / safe_fw, xp.asarray(np.inf, dtype=ctx.dtype))
    checks.require(finite_far | (sign * nz > 0), MESSAGES["infinite_far"])
    return Camera(near, far, sign, sign * nz, far_depth, inv_v, xp.matmul(P, V))


class Depths(NamedTuple):
    splits: Array  # (*b, n + 1)
    start: Array  # (*b, n) each cascade's first view depth
    end: Array  # (*b, n) its last (band_end)


def _splits(
    ctx: Context,
    checks: Checks,
    cam: Camera,
    S: Array | None,
    dmax: Array | None,
    lm: Array,
    ov: Array,
    fixed: float | None,
    count: int | None,
) -> Depths:
    xp = ctx.xp
    checks.require(all_finite(xp, ov, 0), non_finite("overlap"))
    checks.require((ov >= 0) & (ov < 1), _OVERLAP_RANGE)
    tol = float(np.sqrt(ctx.eps))
    if S is not None:
        checks.require(all_finite(xp, S, 1), non_finite("splits"))
        checks.require(xp.all(S[..., 1:] > S[..., :-1], axis=-1), MESSAGES["splits_increase"])
        checks.require(
            # Within sqrt(eps) relative: the camera's own near/far, rounded by its inverse.
            (S[..., 0] >= cam.near - tol * xp.abs(cam.near)) & (S[..., -1] <= cam.far * (1 + tol)),
            MESSAGES["splits_range"],
        )
        s = S
    else:
        far = cam.far
        if dmax is not None:
            checks.require(all_finite(xp, dmax, 0), non_finite("max_distance"))
            checks.require((dmax > cam.near) & (dmax <= cam.far), MESSAGES["max_distance"])
            far = xp.where(dmax > cam.near, xp.minimum(dmax, cam.far), cam.near + 1)
        else:
            checks.require(xp.isfinite(cam.far), MESSAGES["far_infinite"])
        check_range(checks, cam.near, far, lm, fixed)
        assert count is not None
        safe_far = xp.where(far > cam.near, far, cam.near + 1)
        safe_far = xp.where(xp.isfinite(safe_far), safe_far, cam.near + 1)
        s = split_depths(xp, cam.near, safe_far, lm, count)
    a, b = s[..., :-1], s[..., 1:]
    ov = xp.asarray(ov)[..., None]
    end = xp.minimum(b + ov * (b - a), s[..., -1:])
    return Depths(s, a, end)


_E0 = np.array([e[0] for e in EDGES])
_E1 = np.array([e[1] for e in EDGES])


def _fit(
    ctx: Context,
    checks: Checks,
    spec: ShadowMapSpec,
    layout: str,
    shape: tuple[int, ...],
    arrays: tuple[Array, Array, Array, Array | None],
    cam: Camera,
    depths: Depths,
    warp: str | None = None,
) -> Cascades:
    """Every cascade of every batch entry on whole arrays (trusted inputs)."""
    xp, F = ctx.xp, formulas(ctx.xp)
    L, V, box, U = arrays
    coords = xp.max(xp.abs(box), axis=(-2, -1))
    up = (0.0, 0.0, 0.0) if U is None else (U[..., 0], U[..., 1], U[..., 2])
    a, ok_light, _, ok_up = F.fit_axes((-L[..., 0], -L[..., 1], -L[..., 2]), up, U is not None,
                                       coords, ctx.eps)  # fmt: skip
    checks.require(ok_light, MESSAGES["light_zero"])
    checks.require(ok_up, MESSAGES["up_parallel"])
    a_n = tuple(v[..., None] for v in a)  # per cascade
    view, world = _slice_corners(xp, F, cam, depths)
    bounds, zb = _clipped_bounds(
        xp, F, cam, V, box, depths, world, tuple(v[..., None] for v in a_n)
    )
    mx, my = spec.margins
    if spec.stable:
        hx, hy, cx, cy, z_lo, z_hi = _stable_box(xp, F, cam, view, a_n, (mx, my), spec, zb, ctx)
        pad = (z_hi - z_lo) + xp.maximum(hx, hy)
        near, far = pad, pad + (z_hi - z_lo)
    else:
        hx, hy, cx, cy, near, far = F.cascade_box(bounds)
        z_lo = bounds[4]
    shift = z_lo - near  # the origin, on Z through the world origin: x, y stay anchored
    origin = (shift * a_n[6], shift * a_n[7], shift * a_n[8])
    near, far = near * (1 - NEAR_FAR_SLACK), far * (1 + NEAR_FAR_SLACK)
    w, clip, tex = F.fit_rows(origin, a_n, F.safe_box(hx, hy, cx, cy, near, far), (mx, my),
                              True, api_rows(spec.api, spec.reversed_z))  # fmt: skip
    n = depths.start.shape[-1]
    ports, tile = _tiles(n, spec.size, layout)
    tex = _in_tile(xp, tex, tile)
    full = (*shape, n)

    def out(entries: tuple[Array, ...]) -> Array:
        if len(entries) == 12:
            zero = xp.zeros_like(entries[0])
            entries = (*entries, zero, zero, zero, zero + 1)
        same = [e if getattr(e, "shape", None) == full else xp.broadcast_to(e, full)
                for e in entries]  # fmt: skip
        flat = xp.stack(same, axis=-1)
        m = xp.reshape(xp.broadcast_to(flat, (*full, 16)), (*full, 4, 4))
        return checks.poison(m, 3)

    size = xp.stack([2 * hx / (mx * spec.size[0]), 2 * hy / (my * spec.size[1])], axis=-1)
    # >>> LiSPSM hook (shadowmath/_fits/_lispsm.py): the warp replaces clip, tex and size.
    if warp is not None:
        a_l = tuple(v[..., None] for v in a_n)
        body = _body(xp, F, cam, V, box, depths, world, a_l)
        tiled = lambda rows: _in_tile(xp, rows, tile)  # noqa: E731
        clip, tex, size = warp_cascades(xp, F, body, cam, V, a_n, spec, (clip, tex, size), tiled)
    # <<< end of the LiSPSM hook
    mxs, mys = (xp.full(full, m, dtype=ctx.dtype) for m in (mx, my))
    fields = [checks.poison(xp.broadcast_to(v, full), 1)
              for v in (hx, hy, near, far, mxs, mys, cx, cy)]  # fmt: skip
    rx, ry, nr, fa, m_x, m_y, ox, oy = fields
    fr = Frustum(rx, ry, nr, fa, m_x, m_y, ox, oy, orthographic=True)
    texture = _texture(n, spec.size, layout)
    return Cascades(
        world_to_light=out(w),
        frustum=fr,
        world_to_clip=out(clip),
        world_to_texture=out(tex),
        splits=checks.poison(xp.broadcast_to(depths.splits, (*shape, n + 1)), 1),
        band_end=checks.poison(xp.broadcast_to(depths.end, full), 1),
        texel_size=checks.poison(xp.broadcast_to(size, (*full, 2)), 2),
        viewports=ports,
        texture_size=texture[0],
        texture_layers=texture[1],
    )


def _slice_corners(xp: Any, F: Any, cam: Camera, depths: Depths) -> tuple[Array, Array]:
    """The slices' corners ``i + 2 j + 4 l``: view and world, each ``(3, *b, n, 8)``."""
    nc = cam.near_corners[..., None, :, :]  # (*b, 1, 4, 3)
    fc = cam.far_corners[..., None, :, :]  # (*b, 1, 4, 4)
    s = cam.sign[..., None, None]
    n = tuple(nc[..., c] for c in range(3))
    f = tuple(fc[..., c] for c in range(4))
    near = F.edge_point(n, f, s, depths.start[..., None])
    far = F.edge_point(n, f, s, depths.end[..., None])
    view = xp.stack([xp.concat([p, q], axis=-1) for p, q in zip(near, far, strict=True)])
    m = tuple(cam.view_to_world[..., i // 4, i % 4][..., None, None] for i in range(12))
    world = xp.stack(F.affine(m, view[0], view[1], view[2]))
    return view, world


def _box_corners(xp: Any, box: Array) -> tuple[Array, Array, Array]:
    """The scene box's corners ``i + 2 j + 4 l``, three ``(*b, 1, 8)`` arrays."""
    lo, hi = box[..., 0, :], box[..., 1, :]
    bits = np.array([[(k >> c) & 1 for k in range(8)] for c in range(3)], dtype=bool)
    return tuple(
        xp.where(xp.asarray(bits[c]), hi[..., c, None], lo[..., c, None])[..., None, :]
        for c in range(3)
    )


def _body(
    xp: Any, F: Any, cam: Camera, V: Array, box: Array, depths: Depths, world: Array, a: Any
) -> tuple[list[Array], Array, tuple[Array, ...], tuple[Array, ...]]:
    """The vertices of each slice intersected with the scene box, in the frame ``a``.

    Returns ``(ends, ok, slice_corners, box_corners)``: ``ends`` three ``(*b, n, 48)``
    arrays (both clipped ends of the 24 edges; a vertex of the intersection is one of
    them), ``ok`` ``(*b, n, 48)`` True where the edge kept a part; the slices' corners
    ``(*b, n, 8)`` and the box's ``(*b, 1, 8)`` in the same frame. With identity axes
    ``a`` the coordinates are world coordinates.
    """
    bx, by, bz = _box_corners(xp, box)
    lo = tuple(box[..., 0, c][..., None, None] for c in range(3))
    hi = tuple(box[..., 1, c][..., None, None] for c in range(3))
    # The slice's corners in the box's half-spaces, the box's corners in the slice's.
    g_slice = F.box_values(world[0], world[1], world[2], lo, hi)
    pv = tuple(cam.clip_rows[..., i // 4, i % 4][..., None, None] for i in range(16))
    sides = F.camera_values(pv, bx, by, bz)
    vz = tuple(V[..., 2, i][..., None, None] for i in range(4))
    depth = cam.sign[..., None, None] * (vz[0] * bx + vz[1] * by + vz[2] * bz + vz[3])
    g_box = F.slice_values(sides, depth, depths.start[..., None], depths.end[..., None])
    g0 = [xp.concat([gs[..., _E0], xp.broadcast_to(gb, gs.shape)[..., _E0]], axis=-1)
          for gs, gb in zip(g_slice, g_box, strict=True)]  # fmt: skip
    g1 = [xp.concat([gs[..., _E1], xp.broadcast_to(gb, gs.shape)[..., _E1]], axis=-1)
          for gs, gb in zip(g_slice, g_box, strict=True)]  # fmt: skip
    t0, t1, ok = F.clip_segment(tuple(g0), tuple(g1))
    sl = F.to_light(world[0], world[1], world[2], a)  # (*b, n, 8) each
    bl = F.to_light(bx, by, bz, a)
    ends = []
    for p_s, p_b in zip(sl, bl, strict=True):
        p_b = xp.broadcast_to(p_b, p_s.shape)
        p0 = xp.concat([p_s[..., _E0], p_b[..., _E0]], axis=-1)
        p1 = xp.concat([p_s[..., _E1], p_b[..., _E1]], axis=-1)
        ends.append(xp.concat([p0 + t0 * (p1 - p0), p0 + t1 * (p1 - p0)], axis=-1))
    return ends, xp.concat([ok, ok], axis=-1), sl, bl


def _clipped_bounds(
    xp: Any, F: Any, cam: Camera, V: Array, box: Array, depths: Depths, world: Array, a: Any
) -> tuple[tuple[Array, ...], tuple[Array, Array]]:
    """Light-space bounds of slice intersected with box; the box's own ``z`` range."""
    ends, ok2, sl, bl = _body(xp, F, cam, V, box, depths, world, a)
    seen = xp.any(ok2, axis=-1)
    inf = xp.asarray(np.inf, dtype=world.dtype)

    def low(v: Array, fallback: Array) -> Array:
        return xp.where(seen, xp.min(xp.where(ok2, v, inf), axis=-1), xp.min(fallback, axis=-1))

    def high(v: Array, fallback: Array) -> Array:
        return xp.where(seen, xp.max(xp.where(ok2, v, -inf), axis=-1), xp.max(fallback, axis=-1))

    zb_lo, zb_hi = xp.min(bl[2], axis=-1), xp.max(bl[2], axis=-1)  # (*b, 1)
    z_hi = high(ends[2], sl[2])
    z_lo = xp.minimum(xp.minimum(zb_lo, low(ends[2], sl[2])), z_hi)
    bounds = (low(ends[0], sl[0]), high(ends[0], sl[0]), low(ends[1], sl[1]),
              high(ends[1], sl[1]), z_lo, z_hi)  # fmt: skip
    return bounds, (zb_lo, zb_hi)


def _stable_box(
    xp: Any,
    F: Any,
    cam: Camera,
    view: Array,
    a: Any,
    margins: tuple[float, float],
    spec: ShadowMapSpec,
    zb: tuple[Array, Array],
    ctx: Context,
) -> tuple[Array, ...]:
    """The stable box: the slice's sphere plus half a texel, centre snapped; its depth range."""
    corners = tuple(view[c][..., k] for k in range(8) for c in range(3))
    vx, vy, vz, r2 = F.slice_sphere(corners)
    m = tuple(cam.view_to_world[..., i // 4, i % 4][..., None] for i in range(12))
    c = F.affine(m, vx, vy, vz)
    texels = (margins[0], margins[1], float(spec.size[0]), float(spec.size[1]))
    r = xp.sqrt(r2)
    hx, hy, ox, oy, _ = F.stable_sides(r2, c, a, texels, r, ctx.eps)
    cx = c[0] * a[0] + c[1] * a[1] + c[2] * a[2] + ox
    cy = c[0] * a[3] + c[1] * a[4] + c[2] * a[5] + oy
    cz = c[0] * a[6] + c[1] * a[7] + c[2] * a[8]
    z_hi = xp.minimum(cz + r, zb[1])
    z_lo = xp.minimum(zb[0], z_hi - r)
    return hx, hy, cx, cy, z_lo, z_hi


@functools.lru_cache(maxsize=64)
def _tiles(n: int, size: tuple[int, int], layout: str) -> tuple[Array, tuple[int, int, Array]]:
    """Each cascade's viewport ``(x, y, w, h)`` and its tile: columns, rows, ``(n, 2)`` cells."""
    w, h = size
    if layout == "layers":
        ports = np.tile(np.array([0, 0, w, h]), (n, 1))
        ports.setflags(write=False)  # cached: shared by every call
        return ports, (1, 1, np.zeros((n, 2), dtype=int))
    cols, rows = _grid(n, layout)
    cells = np.array([(i % cols, i // cols) for i in range(n)])
    ports = np.column_stack([cells[:, 0] * w, cells[:, 1] * h, np.full(n, w), np.full(n, h)])
    ports.setflags(write=False)  # cached: shared by every call
    return ports, (cols, rows, cells)


def _texture(n: int, size: tuple[int, int], layout: str) -> tuple[tuple[int, int], int]:
    """The texture holding ``n`` cascades of ``size``: ``texture_size``, ``texture_layers``."""
    w, h = int(size[0]), int(size[1])
    if layout == "layers":
        return (w, h), n
    cols, rows = _grid(n, layout)
    return (cols * w, rows * h), 1


def _in_tile(xp: Any, tex: tuple[Array, ...], tile: tuple[int, int, Array]) -> tuple[Array, ...]:
    """Texture rows moved into the tile: ``s' = (s + col) / cols``, ``t' = (t + row) / rows``.

    Rows count from the texture's first row in memory, where ``t = 0`` lies and where
    every API's viewport ``y = 0`` lies (OpenGL's bottom row is both).
    """
    cols, rows, cells = tile
    if cols == 1 and rows == 1:
        return tex
    dtype = tex[0].dtype
    col = xp.asarray(cells[:, 0], dtype=dtype)
    row = xp.asarray(cells[:, 1], dtype=dtype)
    q = tex[12:16]
    s = tuple((tex[i] + col * q[i]) / cols for i in range(4))
    t = tuple((tex[4 + i] + row * q[i]) / rows for i in range(4))
    return (*s, *t, *tex[8:16])


#: The messages of the value checks, by the names of :data:`._cascade_loop.CHECKS`: the
#: compiled loop reports its status bits with them, the array driver its ``require``\ s.
MESSAGES = {
    "light_finite": non_finite("light"),
    "view_finite": non_finite("view"),
    "projection_finite": non_finite("projection"),
    "bounds_finite": non_finite("scene_bounds"),
    "up_finite": non_finite("up"),
    "view_affine": "view: expected an affine world-to-view matrix (last row 0, 0, 0, 1)",
    "view_singular": "view: singular (its 3x3 part has no inverse)",
    "projection_singular": "projection: singular (no inverse)",
    "infinite_far": "projection: an infinite far plane needs a perspective camera (near > 0)",
    "bounds_order": "scene_bounds: the max corner must be >= the min corner on every axis",
    "light_zero": "light: zero direction (x = y = z = 0): a directional light points toward "
    "the light",
    "up_parallel": msg.UP_PARALLEL,
    "far_infinite": "max_distance: the projection's far plane is at infinity; give the "
    "shadow distance as max_distance",
    "max_distance": "max_distance: the shadow distance must lie beyond the camera's near "
    "plane and no farther than its far plane",
    "log_near": LOG_NEAR,
    "splits_increase": "splits: the depths must increase",
    "splits_range": "splits: the depths must lie within the camera's [near, far] view depths",
}
LOOP_MESSAGES = tuple(MESSAGES[name] for name in CHECKS)


def _compiled(
    ctx: Context,
    spec: ShadowMapSpec,
    layout: str,
    shape: tuple[int, ...],
    arrays: tuple[Any, ...],
    C: Any,
    count: int | None,
    python: bool = False,
) -> Cascades:
    """:func:`fit_cascades` for NumPy input through the compiled loop (``fast`` extra), or,
    ``python``, the same loop run by Python (a few cameras without Numba)."""
    L, V, P, box, U, S, dmax, lm, ov = arrays
    _scalar_checks(lm, ov)
    n = S.shape[-1] - 1 if S is not None else count
    assert n is not None
    total = math.prod(shape)
    if type(lm) is float and type(ov) is float and (dmax is None or type(dmax) is float):
        scal = np.array([[lm, np.nan if dmax is None else dmax, ov]])
    else:
        scal = np.stack(np.broadcast_arrays(lm, np.nan if dmax is None else dmax, ov), axis=-1)
    given = (U is not None, S is not None, dmax is not None)
    opts = _options(spec, layout, n, given, ctx.eps, tuple(v for row in C for v in row))
    operands = (
        flat_batch(L, shape, (3,)), flat_batch(V, shape, (4, 4)).reshape(-1, 16),
        flat_batch(P, shape, (4, 4)).reshape(-1, 16), flat_batch(box, shape, (2, 3)).reshape(-1, 6),
        _NO_UP if U is None else flat_batch(U, shape, (3,)), flat_batch(scal, shape, (3,)),
        _NO_SPLITS if S is None else flat_batch(S, shape, (n + 1,)),
    )  # fmt: skip
    if python:  # one camera without Numba: the same loop on Python lists and floats
        rows = [[[0.0] * ROW for _ in range(n)] for _ in range(total)]
        cuts, flags = [[0.0] * (n + 1) for _ in range(total)], [0] * total
        scalar_formulas().cascade_loop(*(v.tolist() for v in operands), opts.tolist(), rows,
                                       cuts, flags)  # fmt: skip
        out = np.asarray(rows, dtype=ctx.dtype)
        splits = np.asarray(cuts, dtype=ctx.dtype)
        status = np.asarray(flags, dtype=np.int64)
    else:
        out = np.empty((total, n, ROW), dtype=ctx.dtype)
        splits = np.empty((total, n + 1), dtype=ctx.dtype)
        status = np.zeros(total, dtype=np.int32)
        _kernels.loops().cascade_loop(*operands, opts, out, splits, status)
    if status[0] if total == 1 else status.any():
        raise_status(status.reshape(shape), [(1 << i, m) for i, m in enumerate(LOOP_MESSAGES)])
    o = out.reshape(*shape, n, ROW)
    m = o[..., :48].reshape(*shape, n, 3, 4, 4)
    rx, ry, near, far, m_x, m_y, cx, cy = (o[..., 48 + k] for k in range(8))
    texture = _texture(n, spec.size, layout)
    return Cascades(
        world_to_light=m[..., 0, :, :],
        frustum=Frustum(rx, ry, near, far, m_x, m_y, cx, cy, orthographic=True),
        world_to_clip=m[..., 1, :, :],
        world_to_texture=m[..., 2, :, :],
        splits=splits.reshape(*shape, n + 1),
        band_end=o[..., 56],
        texel_size=o[..., 57:59],
        viewports=_tiles(n, spec.size, layout)[0],
        texture_size=texture[0],
        texture_layers=texture[1],
    )


#: The most cameras that NumPy without Numba fits with the loop run by Python (beyond,
#: the array driver, vectorized over the cameras, is faster).
PYTHON_LOOP_CAMERAS = 4

_NO_UP = np.zeros((1, 3))
_NO_SPLITS = np.zeros((1, 2))


def _scalar_checks(lm: Any, ov: Any) -> None:
    """lam and overlap, checked on NumPy values or Python floats (the loop trusts them)."""
    if type(lm) is float and type(ov) is float:
        if not 0 <= lm <= 1:  # NaN fails both
            raise ValueError(non_finite("lam") if lm != lm else _LAM_RANGE)
        if not 0 <= ov < 1:
            raise ValueError(non_finite("overlap") if ov != ov else _OVERLAP_RANGE)
        return
    if not np.all(np.isfinite(lm)):
        raise ValueError(non_finite("lam"))
    if not np.all((lm >= 0) & (lm <= 1)):
        raise ValueError(_LAM_RANGE)
    if not np.all(np.isfinite(ov)):
        raise ValueError(non_finite("overlap"))
    if not np.all((ov >= 0) & (ov < 1)):
        raise ValueError(_OVERLAP_RANGE)


@functools.lru_cache(maxsize=256)
def _options(
    spec: ShadowMapSpec,
    layout: str,
    n: int,
    given: tuple[bool, bool, bool],
    eps: float,
    C: tuple[float, ...],
) -> Array:
    """The loop's options as one float64 array (cached: the same few recur every frame)."""
    cols, rows = _grid(n, layout)
    mx, my = spec.margins
    C_api, TC_api = api_rows(spec.api, spec.reversed_z)
    has_up, has_splits, has_dmax = given
    opts = np.array([
        has_up, spec.stable, has_splits, has_dmax, mx, my, *spec.size, eps, NEAR_FAR_SLACK,
        cols, rows, *C, *C_api, *TC_api,
    ], dtype=np.float64)  # fmt: skip
    opts.setflags(write=False)
    return opts


_LAM_RANGE = "lam: the practical scheme's blend must lie in [0, 1]"
_OVERLAP_RANGE = "overlap: the blend band must be a fraction in [0, 1)"


def _grid(n: int, layout: str) -> tuple[int, int]:
    if layout == "layers":
        return 0, 0  # the loop's mark: no tiles
    cols = math.ceil(math.sqrt(n))
    return cols, math.ceil(n / cols)
