"""Many shadowed lights through one shadow atlas: :func:`render_atlas`.

A client of the public API like any user's renderer: :func:`shadowmath.allocate_atlas`
gives each light its tile(s) (a point light's cube map six face tiles) and
:func:`shadowmath.fit_atlas` their matrices (OpenGL conventions); every caster's depth is
drawn into each tile's viewport (scissored to it) with a polygon offset; the camera-view
pass (``shaders/atlas.frag``) picks each light's tile (a cube light's face by
:func:`shadowmath.cube_face`'s rule) and compares with PCF, every tap clamped into the tile.
With ``scene_fit="draw_lists"`` the bodies become a :class:`shadowmath.ShadowScene`, fitted
by :meth:`shadowmath.ShadowScene.fit_atlas`, and each tile is drawn only its draw list.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, Literal, NamedTuple

import moderngl
import numpy as np
from numpy.typing import NDArray

import shadowmath as sm

from ._context import (
    check_camera_projection,
    check_matrix,
    program,
    resolve_context,
    set_matrix,
    set_uniform,
)
from ._context import image_size as _image_size
from ._pass_depth import (
    begin_depth_pass,
    cull_faces_toward_light,
    depth_bias_option,
    pcf_radius_option,
)
from ._pass_lit import draw_lit, finish
from ._pass_pcss import PCSS_POLYGON_OFFSET, light_size_option
from ._resources import Body, GpuScene, Prepared, prepare_body, read_texture

#: The default normal-offset bias of :func:`render_atlas`, in texels of each light's map.
NORMAL_OFFSET = 0.5

#: The atlas lights' kinds, as :func:`render_atlas` takes them.
AtlasLight = sm.PointLight | sm.SpotLight | sm.DirectionalLight

#: Where the atlas's fit and each tile's draws come from (``scene_fit``): None, every
#: caster's triangles and every caster in every tile; ``"draw_lists"``, a
#: :class:`shadowmath.ShadowScene` of the bodies and each tile's draw list;
#: ``"every_caster"``, that scene's fit with every caster in every tile.
SceneFit = Literal["draw_lists", "every_caster"] | None

#: Body indices, one integer array per map (a tile, a cascade).
DrawLists = tuple[NDArray[np.int64], ...]


class AtlasFrame(NamedTuple):
    """What :func:`render_atlas` returns; images have row 0 at the *top* (as saved).

    Attributes:
        color: ``(H, W, 3)`` float32 in ``[0, 1]``, the picture lit by every light.
        shadow: ``(L, H, W)`` float32, each light's shadow mask on the visible bodies (1
            shadowed, 0 lit or not reached by the light; PCF gives fractions).
        position: ``(H, W, 3)`` float32 world position of the visible surface (NaN on
            the background).
        normal: ``(H, W, 3)`` float32 unit face normal (NaN on the background).
        body: ``(H, W)`` int32, which body is visible (``-1`` the background).
        atlas: the :class:`shadowmath.ShadowAtlas` (pass it as ``previous`` next frame).
        fit: the :class:`shadowmath.AtlasFit` the tiles were drawn and sampled with.
        shadow_map: ``(A, A)`` float32 window depths of the whole atlas, row 0 its first
            row in memory (``t = 0``); 1 where nothing was drawn.
        draws: the bodies drawn into each tile (one integer array of body indices per
            tile, in the atlas's tile order): each tile's draw list with
            ``scene_fit="draw_lists"``, else every caster.
    """

    color: NDArray[np.float32]
    shadow: NDArray[np.float32]
    position: NDArray[np.float32]
    normal: NDArray[np.float32]
    body: NDArray[np.int32]
    atlas: sm.ShadowAtlas
    fit: sm.AtlasFit
    shadow_map: NDArray[np.float32]
    draws: DrawLists = ()


class _Options(NamedTuple):
    """The checked shading options of one :func:`render_atlas` call."""

    cast: list[bool]
    pcf_radius: int
    normal_offset: float
    ambient: float
    background: tuple[float, float, float]


class LightTable(NamedTuple):
    """The lights as the shader reads them: ``(L, 4, 4)`` rows of light, colour, spot
    ``(axis, cos angle)`` (``w = -2`` not a spot), ``(cube, 0, 0, 0)``."""

    rows: NDArray[np.float32]
    cube: NDArray[np.bool_]


def render_atlas(
    bodies: Sequence[Body],
    lights: Sequence[AtlasLight],
    view: Any,
    projection: Any,
    *,
    casters: Sequence[bool] | None = None,
    colors: Any = None,
    coverage: Any = None,
    atlas_size: int = 2048,
    budget: float = 1.0,
    previous: sm.ShadowAtlas | None = None,
    pcf_radius: int = 1,
    depth_bias: tuple[float, float] | None = None,
    normal_offset: float = NORMAL_OFFSET,
    light_size: Any = None,
    image_size: int | tuple[int, int] = (512, 384),
    ambient: float = 0.15,
    background: tuple[float, float, float] = (0.06, 0.07, 0.09),
    scene_fit: SceneFit = None,
    ctx: moderngl.Context | None = None,
) -> AtlasFrame:
    r"""Render bodies under many shadowed lights whose maps share one atlas.

    1. :func:`shadowmath.allocate_atlas` (``coverage``, ``atlas_size``, ``budget``,
       ``previous``; point lights are cube maps of six face tiles, the border
       :func:`shadowmath.pcf_border_texels` of the kernel), then
       :func:`shadowmath.fit_atlas` of the casters' world triangles
       (:class:`shadowmath.Triangles`: a cube face's near counts their whole surfaces),
       every body's triangles as receivers (they push ``far``), OpenGL conventions; or,
       with ``scene_fit``, :meth:`shadowmath.ShadowScene.fit_atlas` of a scene of the
       bodies (each body one object: its mesh, its ``to_world``; casting per
       ``casters``; every body receives).
    2. One depth texture of ``atlas_size``\ ² texels, cleared to 1: per tile ``t``, the
       viewport and scissor ``viewports[t]``, every caster (with
       ``scene_fit="draw_lists"``, the bodies of the tile's draw list) through
       ``world_to_clip[t]`` with ``glPolygonOffset(*depth_bias)``.
    3. The lit record, then per light its shadow mask (the point moved off a caster's
       face by the normal offset), and the picture: ``albedo
       (ambient + sum_l colour_l max(n . l, 0) (1 - shadow_l))``, a spot lighting only
       inside its cone.

    Arguments:
        bodies: the scene; all receive.
        lights: ``L`` lights, each one :class:`shadowmath.PointLight` (a cube map),
            :class:`shadowmath.SpotLight` or :class:`shadowmath.DirectionalLight`.
        view: ``(4, 4)`` the camera's world-to-view matrix (OpenGL: it looks down ``-z``).
        projection: ``(4, 4)`` its OpenGL projection (refused, like
            :func:`shadowmath.fit_cascades`'s, unless its last row is perspective or
            orthographic: a transposed matrix is).
        casters: ``(len(bodies),)`` which bodies cast (default all). A body that only
            receives (a ground) costs no texels.
        colors: ``(L, 3)`` each light's diffuse RGB; default white shared out, ``1.6 / L``.
        coverage: ``(L,)`` each light's screen coverage for :func:`shadowmath.allocate_atlas`
            (default 1: every light asks for the largest tile, the budget decides).
        atlas_size, budget, previous: as in :func:`shadowmath.allocate_atlas`.
        pcf_radius: the PCF box kernel's radius ``k`` (its tiles' border).
        depth_bias: ``(factor, units)`` polygon offset; default ``(2.5 + 2 k, 4.0)``.
        normal_offset: the normal-offset bias on the casters, in texels: a caster's point
            is looked up moved along its face normal by ``normal_offset`` texels' world
            size there, times the sine of the angle to the light
            (:data:`NORMAL_OFFSET` by default, 0 for none; receivers that cast nothing
            need none).
        light_size: ``(L,)`` each light's radius (point and spot lights only): PCSS
            instead of the PCF box. Each tile's ``K`` and ``d_near`` are
            :func:`shadowmath.pcss_parameters` of the fit (atlas texels); the atlas is
            allocated again with the border :func:`shadowmath.pcss_border_texels` of
            them all (one border for every tile) when that exceeds the kernel's; the
            tiles hold the faces turned from the light (default ``depth_bias``
            :data:`PCSS_POLYGON_OFFSET`); the search and filter of ``pcss.glsl`` clamp
            their taps to the tile.
        image_size: the picture's size in pixels.
        ambient, background: shading as in :func:`render_scene`.
        scene_fit: None (default): the fit of every caster's triangles, every caster
            drawn into every tile. ``"draw_lists"``: the renderer as a client of
            :class:`shadowmath.ShadowScene`: the bodies added as one object each, fitted
            by :meth:`~shadowmath.ShadowScene.fit_atlas` (from the geometries'
            summaries: the matrices may differ slightly from None's), each tile drawn
            only the bodies of its draw list. ``"every_caster"``: the same scene fit,
            every caster drawn into every tile (what the draw lists are compared with).
        ctx: a moderngl context; default the shared EGL :func:`standalone_context`.

    Returns:
        :class:`AtlasFrame`.

    Raises:
        ValueError: bad bodies, lights, matrices, sizes or options, no caster; a
            ``light_size`` that is not one radius ``>= 0`` per light, or beside a
            directional light; and
            whatever :func:`shadowmath.allocate_atlas` and :func:`shadowmath.fit_atlas`
            raise (casters behind a spot light or outside its cone are not refused:
            each spot's fit clips the casters' triangles to its cone's square pyramid).
        GLUnavailableError: no OpenGL context could be created.

    Example:
        >>> import shadowmath as sm
        >>> from shadowmath.meshes import box, grid
        >>> from shadowmath.render import Body, look_at, perspective
        >>> ground = Body(*grid((20.0, 20.0), segments=(1, 1)))
        >>> cube = Body(*box((2.0, 2.0, 2.0)), to_world=np.array(
        ...     [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 1], [0, 0, 0, 1.0]]))
        >>> lights = [sm.PointLight(np.array([3.0, 0.0, 4.0])),
        ...           sm.DirectionalLight(np.array([1.0, 1.0, 2.0]))]
        >>> frame = render_atlas([ground, cube], lights, look_at([0, -12, 8], [0, 0, 0], [0, 0, 1]),
        ...                      perspective(50.0, 1.0, 0.5, 50.0), casters=[False, True],
        ...                      image_size=64, atlas_size=512)
        >>> frame.shadow.shape, frame.atlas.tile_light.tolist()
        ((2, 64, 64), [0, 0, 0, 0, 0, 0, 1])
    """
    scene = prepare_atlas(
        bodies, lights, view, projection, casters=casters, colors=colors, coverage=coverage,
        atlas_size=atlas_size, budget=budget, previous=previous, pcf_radius=pcf_radius,
        depth_bias=depth_bias, normal_offset=normal_offset, ambient=ambient,
        light_size=light_size, scene_fit=scene_fit,
    )  # fmt: skip
    size = _image_size("image_size", image_size)
    atlas, fit, cast = scene.atlas, scene.fit, scene.cast
    gl = resolve_context(ctx)
    clip = scene.projection @ scene.view
    with GpuScene(gl, scene.bodies, (), [], clip, size=size, map_size=fit.texture_size) as gpu:
        depths = draw_atlas(gpu, fit, scene.draws, scene.bias, back_faces=scene.pcss is not None)
        options = _Options(cast, scene.pcf_radius, scene.normal_offset, scene.ambient, background)
        frame = _shade_all(
            gpu, scene.lights, atlas, fit, depths=depths, options=options, pcss=scene.pcss
        )
    return frame._replace(draws=scene.draws)


class AtlasScene(NamedTuple):
    """An atlas pass's checked scene and options, its atlas and fit (:func:`prepare_atlas`)."""

    bodies: list[Prepared]
    cast: list[bool]
    lights: LightTable
    view: NDArray[np.float64]
    projection: NDArray[np.float64]
    pcf_radius: int
    bias: tuple[float, float]
    normal_offset: float
    ambient: float
    atlas: sm.ShadowAtlas
    fit: sm.AtlasFit
    #: Each tile's PCSS ``K`` and ``d_near`` (atlas texels), None without ``light_size``.
    pcss: sm.PcssParameters | None = None
    #: The bodies to draw into each tile (:attr:`AtlasFrame.draws`).
    draws: DrawLists = ()


def prepare_atlas(
    bodies: Sequence[Body],
    lights: Sequence[AtlasLight],
    view: Any,
    projection: Any,
    *,
    casters: Sequence[bool] | None,
    colors: Any,
    coverage: Any,
    atlas_size: int,
    budget: float,
    previous: sm.ShadowAtlas | None,
    pcf_radius: int,
    depth_bias: tuple[float, float] | None,
    normal_offset: float,
    ambient: float = 0.15,
    api: Literal["opengl", "webgpu"] = "opengl",
    light_size: Any = None,
    scene_fit: SceneFit = None,
) -> AtlasScene:
    """Check the bodies, lights, camera (OpenGL conventions) and options of an atlas pass;
    allocate the atlas and fit it in ``api``'s conventions, from every caster's triangles
    or, with ``scene_fit``, from a :class:`shadowmath.ShadowScene` of the bodies (step 1 of
    :func:`render_atlas`); each tile's bodies to draw."""
    prepared = [prepare_body(f"bodies[{i}]", b) for i, b in enumerate(bodies)]
    if not prepared:
        raise ValueError("bodies: expected at least one body")
    cast = _casters(casters, len(prepared))
    table = _light_table(lights, colors)
    k = pcf_radius_option(pcf_radius)
    sizes = None if light_size is None else _light_sizes(light_size, table)
    bias = depth_bias_option(depth_bias, k)
    if sizes is not None and depth_bias is None:
        bias = PCSS_POLYGON_OFFSET
    if not (np.isfinite(normal_offset) and normal_offset >= 0):
        raise ValueError(f"normal_offset: must be finite and >= 0, got {normal_offset!r}")
    if not (np.isfinite(ambient) and ambient >= 0):
        raise ValueError(f"ambient: must be finite and >= 0, got {ambient!r}")
    if scene_fit not in (None, "draw_lists", "every_caster"):
        raise ValueError(
            f"scene_fit: expected None, 'draw_lists' or 'every_caster', got {scene_fit!r}"
        )
    v, p = check_matrix("view", view), check_camera_projection(projection)
    fit_tiles = _triangle_fit(prepared, cast, lights, k, api)
    if scene_fit is not None:
        fit_tiles = _scene_fit(prepared, cast, lights, (k, api), scene_fit)

    def allocate_and_fit(border: int) -> tuple[sm.ShadowAtlas, sm.AtlasFit, DrawLists]:
        atlas = sm.allocate_atlas(
            np.ones(len(table.cube)) if coverage is None else coverage, atlas_size=atlas_size,
            cube=table.cube, border_texels=border, previous=previous, budget=budget,
        )  # fmt: skip
        return (atlas, *fit_tiles(atlas))

    border = sm.pcf_border_texels(k)
    atlas, fit, draws = allocate_and_fit(border)
    pcss = None
    if sizes is not None:  # the border holds the widest search (K only shrinks with it)
        pcss = sm.pcss_parameters(fit, light_radius=sizes[np.asarray(atlas.tile_light)])
        if sm.pcss_border_texels(pcss) > border:
            atlas, fit, draws = allocate_and_fit(sm.pcss_border_texels(pcss))
            pcss = sm.pcss_parameters(fit, light_radius=sizes[np.asarray(atlas.tile_light)])
    return AtlasScene(prepared, cast, table, v, p, k, bias, float(normal_offset), float(ambient),
                      atlas, fit, pcss, draws)  # fmt: skip


#: An allocated atlas's fit and each tile's bodies to draw.
_FitTiles = Callable[[sm.ShadowAtlas], tuple[sm.AtlasFit, DrawLists]]


def _triangle_fit(
    prepared: Sequence[Prepared],
    cast: Sequence[bool],
    lights: Sequence[AtlasLight],
    k: int,
    api: Literal["opengl", "webgpu"],
) -> _FitTiles:
    """:func:`shadowmath.fit_atlas` of every caster's world triangles; every caster in
    every tile."""
    world = [b.world_vertices()[b.triangles] for b in prepared]  # (T, 3, 3) each
    # The casters as surfaces: a cube light's near counts a triangle passing nearer the
    # light than its corners. Every body's triangles hold what the shadows fall on: a
    # ground's corners may lie outside a light's map while its middle is under the casters.
    casting = sm.Triangles(np.concatenate([t for t, c in zip(world, cast, strict=True) if c]))
    surfaces = sm.Triangles(np.concatenate(world))
    every = np.flatnonzero(cast)

    def fit_tiles(atlas: sm.ShadowAtlas) -> tuple[sm.AtlasFit, DrawLists]:
        fit = sm.fit_atlas(list(lights), casting, atlas, receivers=surfaces, pcf_radius=k, api=api)
        return fit, tuple(every for _ in range(len(atlas.tile_light)))

    return fit_tiles


def _scene_fit(
    prepared: Sequence[Prepared],
    cast: Sequence[bool],
    lights: Sequence[AtlasLight],
    options: tuple[int, Literal["opengl", "webgpu"]],
    scene_fit: Literal["draw_lists", "every_caster"],
) -> _FitTiles:
    """:meth:`shadowmath.ShadowScene.fit_atlas` of :func:`body_scene` with ``options = (k,
    api)`` (the PCF radius, the API); each tile's draw list (``"draw_lists"``) or every
    caster (``"every_caster"``)."""
    k, api = options
    scene = body_scene(prepared, cast)
    every = np.flatnonzero(cast)

    def fit_tiles(atlas: sm.ShadowAtlas) -> tuple[sm.AtlasFit, DrawLists]:
        fitted = scene.fit_atlas(list(lights), atlas, pcf_radius=k, api=api)
        if scene_fit == "every_caster":
            return fitted.fit, tuple(every for _ in fitted.draws)
        return fitted.fit, tuple(np.asarray(d, dtype=np.int64) for d in fitted.draws)

    return fit_tiles


def body_scene(prepared: Sequence[Prepared], cast: Sequence[bool]) -> sm.ShadowScene:
    """A :class:`shadowmath.ShadowScene` of the bodies, object ``i`` body ``i``: its mesh in
    local coordinates placed by its ``to_world``, casting per ``cast``, every body
    receiving."""
    scene = sm.ShadowScene()
    for body, casts in zip(prepared, cast, strict=True):
        geometry = scene.add_geometry(sm.Mesh(body.vertices, body.triangles))
        scene.add_objects(geometry, body.to_world, casts=bool(casts))
    return scene


def _light_sizes(light_size: Any, table: LightTable) -> NDArray[np.float64]:
    """``light_size`` checked: one radius ``>= 0`` per light, point and spot lights only."""
    sizes = np.asarray([light_size_option(r) for r in np.atleast_1d(light_size)])
    if sizes.shape != table.cube.shape:
        raise ValueError(f"light_size: expected one radius per light ({len(table.cube)})")
    if np.any(table.rows[:, 0, 3] == 0):
        raise ValueError("light_size: PCSS in the atlas takes point and spot lights only")
    return sizes


def _casters(casters: Sequence[bool] | None, count: int) -> list[bool]:
    if casters is None:
        return [True] * count
    flags = [bool(c) for c in casters]
    if len(flags) != count:
        raise ValueError(f"casters: expected one flag per body ({count}), got {len(flags)}")
    if not any(flags):
        raise ValueError("casters: at least one body must cast")
    return flags


def _light_table(lights: Sequence[AtlasLight], colors: Any) -> LightTable:
    """The shader's per-light rows; point lights are cube maps."""
    count = len(lights)
    if count == 0:
        raise ValueError("lights: expected at least one light")
    rgb = np.full((count, 3), 1.6 / count) if colors is None else np.asarray(colors, float)
    if rgb.shape != (count, 3) or not np.all(np.isfinite(rgb)) or rgb.min() < 0:
        raise ValueError(f"colors: expected ({count}, 3) finite values >= 0, got {rgb.shape}")
    rows = np.zeros((count, 4, 4))
    rows[:, 2, 3] = -2.0
    with np.errstate(all="ignore"):  # a zero direction's NaNs are refused below
        for i, light in enumerate(lights):
            rows[i] = _light_rows(i, light, rows[i])
    rows[:, 1, :3] = rgb
    bad = np.flatnonzero(~np.isfinite(rows).all(axis=(1, 2)))
    if bad.size:
        raise ValueError(
            f"lights[{bad[0]}]: its position, direction and angle must be finite, the "
            "direction nonzero"
        )
    return LightTable(rows.astype(np.float32), rows[:, 3, 0] > 0.5)


def _light_rows(i: int, light: Any, rows: NDArray[np.float64]) -> NDArray[np.float64]:
    """Light ``i``'s shader rows (``rows`` as initialised: the spot row's ``w = -2``)."""
    if isinstance(light, AtlasLight) and np.shape(light[0]) != (3,):
        raise ValueError(
            f"lights[{i}]: expected one light (a (3,) vector), got a batch of shape "
            f"{np.shape(light[0])}; list its lights one by one"
        )
    if isinstance(light, sm.DirectionalLight):
        d = np.asarray(light.direction, dtype=np.float64)
        rows[0] = [*(d / np.linalg.norm(d)), 0.0]
    elif isinstance(light, sm.PointLight | sm.SpotLight):
        rows[0] = [*np.asarray(light.position, dtype=np.float64), 1.0]
    else:
        raise ValueError(
            f"lights[{i}]: expected an sm.PointLight, sm.SpotLight or sm.DirectionalLight, "
            f"got {type(light).__name__}"
        )
    if isinstance(light, sm.SpotLight):
        axis = np.asarray(light.direction, dtype=np.float64)
        rows[2] = [*(axis / np.linalg.norm(axis)), np.cos(float(light.angle))]
    rows[3, 0] = float(isinstance(light, sm.PointLight))
    return rows


def draw_atlas(
    scene: GpuScene,
    fit: sm.AtlasFit,
    draws: DrawLists,
    bias: tuple[float, float],
    *,
    back_faces: bool = False,
) -> moderngl.Texture:
    """The depth of the bodies ``draws[t]`` (in body order) into each tile ``t``'s viewport
    (scissored) of one depth texture of ``fit.texture_size``, cleared to 1; returns the
    texture (released with the scene). ``back_faces``: only the faces turned from the
    light (:func:`cull_faces_toward_light`)."""
    gl = scene.ctx
    tex: moderngl.Texture = scene.keep(gl.depth_texture(fit.texture_size))
    fbo = scene.keep(gl.framebuffer(depth_attachment=tex))
    prog = program(gl, "depth_map.vert", "depth_map.frag")
    clip = np.asarray(fit.world_to_clip, dtype=np.float64)
    try:
        begin_depth_pass(gl, fbo, bias)
        for t, port in enumerate(np.asarray(fit.viewports)):
            fbo.viewport = fbo.scissor = tuple(int(c) for c in port)
            for i in draws[t].tolist():
                body, mesh = scene.bodies[i], scene.meshes[i]
                if back_faces:
                    cull_faces_toward_light(gl, clip[t] @ body.to_world)
                set_matrix(prog, "body_to_clip", clip[t] @ body.to_world)
                mesh.render(prog)
    finally:
        gl.polygon_offset = (0.0, 0.0)
        gl.disable(moderngl.CULL_FACE)
        gl.cull_face = "back"
        fbo.scissor = None
    tex.compare_func = ""  # read the stored depth itself (texelFetch)
    tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
    return tex


def _data_texture(gl: moderngl.Context, rows: NDArray[Any], components: int) -> moderngl.Texture:
    """``(height, width, components)`` float32 data as a nearest-filtered float texture."""
    h, w = rows.shape[:2]
    tex = gl.texture(
        (w, h), components, np.ascontiguousarray(rows, np.float32).tobytes(), dtype="f4"
    )
    tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
    return tex


def _shade_all(
    scene: GpuScene,
    table: LightTable,
    atlas: sm.ShadowAtlas,
    fit: sm.AtlasFit,
    *,
    depths: moderngl.Texture,
    options: _Options,
    pcss: sm.PcssParameters | None = None,
) -> AtlasFrame:
    """The lit record, each light's mask, the picture; read back."""
    gl = scene.ctx
    texture = np.asarray(fit.world_to_texture, dtype=np.float64)
    rect = np.concatenate([atlas.tile_rect, np.zeros((len(atlas.tile_rect), 1))], axis=1)
    pcss_row = np.zeros_like(rect)  # (K_s, K_t, d_near, 1) with PCSS, 0 without
    if pcss is not None:
        k_near = np.column_stack([pcss.texels_per_depth, pcss.near_depth])
        pcss_row = np.nan_to_num(np.column_stack([k_near, np.ones(len(rect))]))
    tile_rows = np.concatenate([texture, rect[:, None, :], pcss_row[:, None, :]], axis=1)
    faces = atlas.light_tiles.astype(np.float32)[..., None]  # (L, 6, 1)
    data = [
        scene.keep(_data_texture(gl, tile_rows, 4)),
        scene.keep(_data_texture(gl, table.rows, 4)),
        scene.keep(_data_texture(gl, faces, 1)),
    ]
    draw_lit(scene, options.ambient, options.background)
    prog = program(gl, "surface.vert", "atlas.frag")
    for unit, (name, tex) in enumerate(zip(("tiles", "lights", "faces"), data, strict=True), 2):
        tex.use(location=unit)
        set_uniform(prog, name, unit)
    depths.use(location=0)
    set_uniform(prog, "atlas", 0)
    set_matrix(prog, "world_to_clip", scene.world_to_clip)
    set_uniform(prog, "light_count", len(table.cube))
    set_uniform(prog, "pcf_radius", options.pcf_radius)
    set_uniform(prog, "ambient", options.ambient)
    set_uniform(prog, "normal_offset", options.normal_offset)
    try:
        shadow = []
        for light in range(len(table.cube)):
            scene.clear_mask()
            scene.bind_mask()
            _draw_bodies(scene, prog, options.cast, mode=0, which=light)
            shadow.append(read_texture(scene.mask_tex, 1)[..., 0])
        scene.use(scene.color_fbo)
        scene.color_fbo.depth_mask = False
        scene.surface_tex.use(location=1)
        gl.disable(moderngl.BLEND)
        gl.enable(moderngl.DEPTH_TEST)
        gl.depth_func = "<="
        _draw_bodies(scene, prog, options.cast, mode=1, which=0)
        color = read_texture(scene.color_tex, 4)[..., :3]
    finally:
        finish(scene)
    return _frame(scene, color, np.stack(shadow), atlas, fit, depths=depths)


def _draw_bodies(
    scene: GpuScene, prog: moderngl.Program, cast: Sequence[bool], mode: int, which: int
) -> None:
    set_uniform(prog, "mode", mode)
    set_uniform(prog, "which", which)
    for i, (body, mesh) in enumerate(zip(scene.bodies, scene.meshes, strict=True)):
        set_uniform(prog, "casts", float(cast[i]))
        set_matrix(prog, "body_to_world", body.to_world)
        set_uniform(prog, "albedo", tuple(body.color))
        scene.bind_record(prog, i)
        mesh.render(prog)


def _frame(
    scene: GpuScene,
    color: NDArray[np.float32],
    shadow: NDArray[np.float32],
    atlas: sm.ShadowAtlas,
    fit: sm.AtlasFit,
    *,
    depths: moderngl.Texture,
) -> AtlasFrame:
    position, normal, body = scene.read_record()
    width, height = fit.texture_size
    stored = np.frombuffer(depths.read(alignment=1), dtype=np.float32).reshape(height, width)
    return AtlasFrame(
        color=np.clip(color, 0.0, 1.0).astype(np.float32),
        shadow=shadow.astype(np.float32),
        position=position,
        normal=normal,
        body=body,
        atlas=atlas,
        fit=fit,
        shadow_map=stored.copy(),
    )
