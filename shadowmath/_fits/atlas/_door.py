"""Every tile of a shadow atlas fitted: the door of :func:`fit_atlas`.

Per frame a renderer calls :func:`allocate_atlas` (:mod:`._allocate`), then
:func:`fit_atlas` with the lights (read by :mod:`._lights`) and their casters: one
fit per tile, drawn with ``world_to_clip[t]`` inside ``viewports[t]`` and sampled with
``world_to_texture[t]`` (:mod:`._viewports`). The door reads and checks the options, the
lights and the arrays once; the driver (:mod:`._driver`) groups the 2D lights by (kind,
tile size, border) and runs each group through :func:`fit_shadow`'s compiled loop once
(NumPy with Numba) or its array driver (JAX, or NumPy alone) (:mod:`._fit_2d`); the cube
lights' faces are :func:`cube_face_views` and :func:`cube_face_projection` with the border
ring, on whole arrays (:mod:`._fit_cubes`); a light that cannot be fitted is reported
(:mod:`._report`). Then :func:`atlas_redraw` (:mod:`._redraw`) compares this frame's fit
with the last one: the tiles to draw (a tile's identity is its key ``(light id, face)``,
not its index).

The rule, the borders and the API conventions are written out in ``docs/atlas.md``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from shadowmath._boundary._shapes import ArrayLike, BoolLike, Real
from shadowmath._boundary._validate import RECEIVER_KINDS, Array, convert, non_finite, shape_error
from shadowmath._fits._light_kinds import POINT
from shadowmath._fits._spec import ShadowMapSpec, map_spec
from shadowmath._fits.shadow._door import _receiver_kind, _receiver_rows, caster_triangles
from shadowmath._geometry._api_convention import check_api as _check_api
from shadowmath._geometry._depth_bias import check_kernel as _check_kernel
from shadowmath._math._bias import PcfFilter
from shadowmath._math._conventions import GraphicsApi
from shadowmath._math._pcf import border_texels as _border_texels
from shadowmath.lights import Light
from shadowmath.receivers import Mesh, Triangles

from ._allocate import ShadowAtlas
from ._driver import fit_tiles
from ._lights import read_lights
from ._report import AtlasInputs, Report
from ._result import AtlasFit

__all__ = ["AtlasFit", "fit_atlas"]


def fit_atlas(
    lights: Sequence[Light] | Real[ArrayLike, "L 4"] | Real[ArrayLike, "L 3"],
    blocker_vertices: Real[ArrayLike, "*#l N 3"] | Triangles | Mesh,
    atlas: ShadowAtlas,
    *,
    receivers: Real[ArrayLike, "M 3"] | Triangles | Mesh | None = None,
    near: Real[ArrayLike, "*#l"] | None = None,
    far: Real[ArrayLike, "*#l"] | None = None,
    api: GraphicsApi = "opengl",
    reversed_z: BoolLike = False,
    pcf_radius: int | None = None,
    pcf_filter: PcfFilter = "box",
    spec: ShadowMapSpec | None = None,
) -> AtlasFit:
    r"""Fit every tile of an atlas: the matrices that draw and sample each light's map.

    * **2D light** (point, spot or directional): :func:`fit_shadow`'s fit with the
      tile's size and border (map ``n``, border ``b``: the casters stay within
      ``|x_ndc|, |y_ndc| <= (n - 2b) / n``), then moved into the tile:
      ``world_to_texture = T_tile @ T C P W`` (:func:`atlas_tile_transforms`).
    * **cube light**: face ``i``'s ``world_to_clip = P V_i`` with ``V_i`` of
      :func:`cube_face_views` and ``P`` of :func:`cube_face_projection` with the
      border ring ``b`` (scale ``k = (n - 2b) / n``); ``world_to_texture =
      T_tile @ T_api @ P V_i`` (``T_api`` the API's ``clip_to_texture``). ``near`` and
      ``far`` are :func:`cube_depth_range`'s: ``near = k D_min (1 - 1/64)`` and
      ``far = D_max (1 + 1/64)`` over the casters (and the receivers for ``far``), ``D``
      the largest absolute coordinate of ``p - light``: every caster drawn in a face,
      ring included, lies at a face depth ``>= k D``. ``D_min`` is over the casters'
      whole triangles when they are given as :class:`Triangles` or a :class:`Mesh` (a
      triangle can pass nearer the light than its corners), over the points otherwise.
      A renderer picks the face with :func:`cube_face`'s rule (the major axis of
      ``p - light``) and samples ``light_tiles[l, face]``.

    Arguments:
        lights: a sequence of ``L`` lights, each a :class:`PointLight`,
            :class:`SpotLight` or :class:`DirectionalLight` (each may hold a batch:
            its entries are consecutive lights); or an ``(L, 4)`` homogeneous array
            (``w = 0`` directional); or an ``(L, 3)`` array of point lights. Cube
            tiles need point lights.
        blocker_vertices: ``(N, 3)`` casters shared by every light, or ``(L, N, 3)``; or
            their surfaces, :class:`Triangles` ``([L,] M, 3, 3)`` or a :class:`Mesh`
            (the 2D fits use the corners; the cube faces' ``near`` the whole triangles).
        atlas: the :class:`ShadowAtlas` of these lights (``L`` entries).
        receivers: what the shadows fall on, shared by every light, as in
            :func:`fit_shadow`: ``(M, 3)`` points, :class:`Triangles` ``(M, 3, 3)`` or a
            :class:`Mesh` (each triangle clipped by a 2D map's sides, so a floor whose
            corners lie outside the map still counts). They only push ``far``.
        near, far: scalars or ``(L,)``: the depth range of the point and spot lights
            (ignored for directional ones, whose range is fitted), instead of the casters'.
        api, reversed_z: the graphics API's conventions (:func:`api_convention`).
        pcf_radius, pcf_filter: the kernel the atlas is sampled with: refused when a
            light's border is narrower than :func:`pcf_border_texels` of it.
        spec: instead of the four options above, the atlas texture's
            :class:`ShadowMapSpec` (size ``atlas.atlas_size``; its ``api``,
            ``reversed_z`` and PCF kernel used as above; its ``border_texels``, if
            given, at most every light's border; no ``margin``, no ``stable``). As in
            :func:`fit_shadow`, an option given both in it and as a keyword is refused.

    A spot light's tiles use the casters that reach into its cone's square pyramid
    (:func:`fit_shadow`'s selection): shared casters given as :class:`Triangles` or a
    :class:`Mesh` are clipped exactly to each spot's pyramid; a spot with nothing left
    gets the empty fit.

    Returns:
        :class:`AtlasFit`, one entry per tile of ``atlas`` (lights without a tile have
        none), with ``light_errors`` per light. NumPy input gives NumPy arrays;
        concrete JAX arrays (not under ``jit``: the atlas is host data) run the array
        driver and give JAX arrays.

    Raises:
        ValueError: what is wrong for the whole call: a light list of the wrong length
            or kind, a cube tile for a spot or directional light, non-finite casters or
            receivers, wrong shapes, an ``atlas`` that is not a :class:`ShadowAtlas`, an
            unknown ``api``, a kernel wider than a border, a ``spec`` that does not
            describe the atlas or beside conflicting keywords. What one light's geometry
            makes unfittable (what :func:`fit_shadow` would raise for it, a caster at a
            cube light's position) is not raised: it is reported in
            :attr:`AtlasFit.light_errors`, and every other light is fitted.

    Example:
        >>> import numpy as np, shadowmath as sm
        >>> box = np.array([[x, y, z] for x in (-1, 1) for y in (0, 2) for z in (-1, 1)], float)
        >>> lights = [sm.SpotLight(np.array([0.0, 6.0, 0.0]), np.array([0.0, -1.0, 0.0]),
        ...                        np.array(0.6)), sm.PointLight(np.array([3.0, 1.0, 0.0]))]
        >>> atlas = sm.allocate_atlas([0.5, 0.25], atlas_size=1024, cube=[False, True])
        >>> fit = fit_atlas(lights, box, atlas, api="vulkan")
        >>> fit.world_to_clip.shape, fit.viewports[0].tolist()
        ((7, 4, 4), [0, 0, 256, 256])
    """
    if not isinstance(atlas, ShadowAtlas):
        raise ValueError(f"atlas: expected a ShadowAtlas (from allocate_atlas), got {atlas!r}")
    if spec is not None:
        options = {"api": api, "reversed_z": reversed_z, "pcf_radius": pcf_radius,
                   "pcf_filter": pcf_filter}  # fmt: skip
        api, reversed_z, pcf_radius, pcf_filter = _atlas_spec(spec, atlas, options)
    _check_api(api, reversed_z)
    count = atlas.light_size.shape[0]
    if pcf_radius is not None:
        need = _border_texels(*_check_kernel(pcf_radius, pcf_filter, ("pcf_radius", "pcf_filter")))
        if count and int(atlas.light_border.min()) < need:
            raise ValueError(
                f"pcf_radius: a {pcf_filter} kernel of radius {pcf_radius} needs borders of "
                f"{need} texels; the atlas has {int(atlas.light_border.min())} (allocate it "
                f"with border_texels=sm.pcf_border_texels({pcf_radius}, {pcf_filter!r}))"
            )
    kinds, data = read_lights(lights, count)
    c_kind, c_name, c_array = _receiver_kind(blocker_vertices, "blocker_vertices")
    r_kind, r_name, r_array = _receiver_kind(receivers)
    ctx, (data, verts, R, n, f) = convert(
        lights=data, **{c_name: c_array}, **{r_name: r_array}, near=near, far=far
    )
    xp = ctx.xp
    tris = None  # surfaces: a cube face's near counts their insides; the 2D fits, corners
    if c_kind != "points":
        tris = caster_triangles(ctx, c_kind, verts, blocker_vertices, "blocker_vertices")
        verts = xp.reshape(tris, (*tris.shape[:-3], -1, 3))
    if R is not None:
        R = _receiver_rows(ctx, r_kind, R, receivers)
    _check_arrays(verts, R, n, f, count)
    for name, v in (("blocker_vertices", verts), ("receivers", R)):
        if v is not None and not ctx.lazy and not bool(xp.all(xp.isfinite(v))):
            raise ValueError(non_finite(name))
    if bool(np.any(atlas.light_cube & (kinds != POINT))):
        i = int(np.flatnonzero(atlas.light_cube & (kinds != POINT))[0])
        raise ValueError(f"lights[{i}]: a cube map needs a point light (atlas cube=True)")
    report = Report(ctx, api, reversed_z, count)
    inputs = AtlasInputs(data, verts, tris, R, n, f)
    return fit_tiles(ctx, atlas, kinds, inputs, report, api=api)


def _atlas_spec(
    spec: Any, atlas: ShadowAtlas, options: dict[str, Any]
) -> tuple[Any, bool, int | None, PcfFilter]:
    """The options of the atlas texture's spec, checked against the atlas and the keywords."""
    if not isinstance(spec, ShadowMapSpec):
        raise ValueError(f"spec: expected a ShadowMapSpec or None, got {type(spec).__name__}")
    map_spec(spec, **options)
    n = atlas.atlas_size
    if spec.size != (n, n):
        raise ValueError(f"spec: its size {spec.size} is not the atlas's ({n}, {n})")
    if spec.stable or spec.margin is not None:
        raise ValueError("spec: an atlas's tiles take no stable or margin option")
    borders = atlas.light_border
    if spec.border_texels is not None and borders.size and borders.min() < spec.border_texels:
        raise ValueError(
            f"spec: border_texels={spec.border_texels}, but the atlas leaves "
            f"{int(borders.min())} (allocate it with border_texels={spec.border_texels})"
        )
    return spec.api, spec.reversed_z, spec.pcf_radius, spec.pcf_filter


def _check_arrays(
    verts: Array, R: Array | None, n: Array | None, f: Array | None, count: int
) -> None:
    if verts.ndim not in (2, 3) or verts.shape[-1] != 3 or verts.shape[-2] == 0:
        raise shape_error("blocker_vertices", "(N, 3) or (L, N, 3), N >= 1", tuple(verts.shape))
    if verts.ndim == 3 and verts.shape[0] != count:
        raise shape_error("blocker_vertices", f"({count}, N, 3)", tuple(verts.shape),
                          "one caster set per light")  # fmt: skip
    if R is not None and R.ndim != 2:  # rows of 3 (points) or 9 (triangles), checked
        hint = f"one set of receivers shared by every light. {RECEIVER_KINDS}"
        raise shape_error("receivers", "(M, 3) points or M triangles", tuple(R.shape), hint)
    for name, v in (("near", n), ("far", f)):
        if v is not None and (v.ndim > 1 or (v.ndim == 1 and v.shape[0] != count)):
            raise shape_error(name, f"() or ({count},)", tuple(v.shape))
