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

from collections.abc import Sequence
from typing import Any, NamedTuple

import moderngl
import numpy as np
from numpy.typing import NDArray

import shadowmath as sm

from ._atlas_pass import NORMAL_OFFSET, AtlasLight, AtlasPass, describe_atlas
from ._context import image_size as _image_size
from ._context import program, resolve_context, set_matrix, set_uniform
from ._map_draws import DrawLists, MapDraw
from ._pass_depth import begin_depth_pass, cull_faces_toward_light
from ._pass_lit import draw_lit, finish
from ._resources import Body, GpuScene, read_texture
from ._scene_fit import SceneFit


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
    scene = describe_atlas(
        bodies, lights, view, projection, casters=casters, colors=colors, coverage=coverage,
        atlas_size=atlas_size, budget=budget, previous=previous, pcf_radius=pcf_radius,
        depth_bias=depth_bias, normal_offset=normal_offset, ambient=ambient,
        light_size=light_size, scene_fit=scene_fit,
    )  # fmt: skip
    size = _image_size("image_size", image_size)
    gl = resolve_context(ctx)
    clip = scene.projection @ scene.view
    texels = scene.fit.texture_size
    with GpuScene(gl, scene.bodies, (), [], clip, size=size, map_size=texels) as gpu:
        depths = draw_atlas(gpu, scene.maps, texels, scene.bias, back_faces=scene.pcss is not None)
        frame = _shade_all(gpu, scene, depths=depths, background=background)
    return frame._replace(draws=scene.draws)


def draw_atlas(
    scene: GpuScene,
    maps: Sequence[MapDraw],
    size: tuple[int, int],
    bias: tuple[float, float],
    *,
    back_faces: bool = False,
) -> moderngl.Texture:
    """Each :class:`MapDraw`'s bodies (a tile's draw list) into its viewport (scissored) of
    one depth texture of ``size``, cleared to 1, with the polygon offset ``bias``; returns
    the texture (released with the scene). ``back_faces``: only the faces turned from the
    light (:func:`cull_faces_toward_light`)."""
    gl = scene.ctx
    tex: moderngl.Texture = scene.keep(gl.depth_texture(size))
    fbo = scene.keep(gl.framebuffer(depth_attachment=tex))
    prog = program(gl, "depth_map.vert", "depth_map.frag")
    try:
        begin_depth_pass(gl, fbo, bias)
        for drawn in maps:
            fbo.viewport = fbo.scissor = drawn.viewport
            for b, body_to_clip in zip(drawn.bodies, drawn.body_to_clip, strict=True):
                if back_faces:
                    cull_faces_toward_light(gl, body_to_clip)
                set_matrix(prog, "body_to_clip", body_to_clip)
                scene.meshes[b].render(prog)
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
    described: AtlasPass,
    *,
    depths: moderngl.Texture,
    background: tuple[float, float, float],
) -> AtlasFrame:
    """The lit record, each light's mask, the picture; read back. The description's tiles
    and lights tables are data textures (a row a texel), the atlas on unit 0."""
    gl = scene.ctx
    data = [
        scene.keep(_data_texture(gl, described.tiles, 4)),
        scene.keep(_data_texture(gl, described.lights, 4)),
    ]
    draw_lit(scene, described.ambient, background)
    prog = program(gl, "surface.vert", "atlas.frag")
    for unit, (name, tex) in enumerate(zip(("tiles", "lights"), data, strict=True), 2):
        tex.use(location=unit)
        set_uniform(prog, name, unit)
    depths.use(location=0)
    set_uniform(prog, "atlas", 0)
    set_matrix(prog, "world_to_clip", scene.world_to_clip)
    set_uniform(prog, "light_count", len(described.lights))
    set_uniform(prog, "pcf_radius", described.pcf_radius)
    set_uniform(prog, "ambient", described.ambient)
    set_uniform(prog, "normal_offset", described.normal_offset)
    try:
        shadow = []
        for light in range(len(described.lights)):
            scene.clear_mask()
            scene.bind_mask()
            _draw_bodies(scene, prog, described.cast, mode=0, which=light)
            shadow.append(read_texture(scene.mask_tex, 1)[..., 0])
        scene.use(scene.color_fbo)
        scene.color_fbo.depth_mask = False
        scene.surface_tex.use(location=1)
        gl.disable(moderngl.BLEND)
        gl.enable(moderngl.DEPTH_TEST)
        gl.depth_func = "<="
        _draw_bodies(scene, prog, described.cast, mode=1, which=0)
        color = read_texture(scene.color_tex, 4)[..., :3]
    finally:
        finish(scene)
    return _frame(scene, color, np.stack(shadow), described.atlas, described.fit, depths=depths)


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
