"""Cascaded shadow maps of a sun, seen from a camera: :func:`render_cascades`.

A client of the public API like any user's renderer: :func:`shadowmath.fit_cascades`
fits the cascades to the camera's ``view`` and ``projection`` and the scene's box;
every body's depth is drawn into each cascade's map (a layer of a texture array, or a
tile of an atlas) with ``world_to_clip[i]``; the camera-view pass picks the cascade by
the fragment's view depth, blends across the band, biases with shadowmath's normal
offset and slope-scaled bias and compares with PCF (``shaders/cascades.frag``). Every
body casts and receives, as with ``render_scene(..., method="depth")``, whose lit and
subtractive passes it shares. With ``scene_fit="draw_lists"`` the bodies become a
:class:`shadowmath.ShadowScene`, fitted by :meth:`shadowmath.ShadowScene.fit_cascades`,
and each cascade's map is drawn only its draw list.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Literal, NamedTuple

import moderngl
import numpy as np
from numpy.typing import NDArray

import shadowmath as sm

from ._cascade_pass import (
    NORMAL_OFFSET,
    CascadePass,
    cascade_index,
    cascade_options,
    describe_cascades,
    fit_keywords,
)
from ._context import bind_block, program, resolve_context, set_matrix, set_uniform, uniform
from ._context import image_size as _image_size
from ._map_draws import DrawLists, MapDraw
from ._pass_depth import begin_depth_pass, cull_faces_toward_light
from ._pass_lit import draw_lit, finish, subtract_light
from ._resources import Body, GpuScene, Light, read_texture
from ._scene_fit import SceneFit
from ._shader_constants import MAX_CASCADES as MAX_CASCADES

#: The debug view's cascade colours, multiplied into the picture (cascade ``i`` takes
#: ``CASCADE_COLORS[i % len]``): red, green, blue, yellow, magenta, cyan, orange, violet.
CASCADE_COLORS = (
    (1.0, 0.45, 0.45),
    (0.45, 1.0, 0.45),
    (0.5, 0.6, 1.0),
    (1.0, 1.0, 0.4),
    (1.0, 0.45, 1.0),
    (0.4, 1.0, 1.0),
    (1.0, 0.7, 0.35),
    (0.7, 0.5, 1.0),
)


class CascadeFrame(NamedTuple):
    """What :func:`render_cascades` returns; images have row 0 at the *top* (as saved).

    Attributes:
        color: ``(H, W, 3)`` float32 in ``[0, 1]``, the shadowed picture.
        cascade_color: ``(H, W, 3)`` float32, the same picture tinted by cascade
            (:data:`CASCADE_COLORS`, blended across the bands); None unless asked.
        shadow: ``(H, W)`` float32 shadow mask on every visible body (1 shadowed, 0 lit;
            PCF and the blend bands give fractions).
        cascade: ``(H, W)`` int32, the cascade serving each pixel's view depth (``-1``
            on the background and beyond the last split).
        position: ``(H, W, 3)`` float32 world position of the visible surface (NaN on
            the background).
        normal: ``(H, W, 3)`` float32 unit face normal (NaN on the background).
        body: ``(H, W)`` int32, which body is visible (``-1`` the background).
        cascades: the :class:`shadowmath.Cascades` the maps were drawn and sampled with.
        shadow_maps: ``(layers, h, w)`` float32 window depths, row 0 is ``t = 0`` (1 where
            nothing was drawn): one layer per cascade, or the whole atlas as one layer.
        draws: the bodies drawn into each cascade's map (one integer array of body
            indices per cascade): its draw list with ``scene_fit="draw_lists"``, else
            every body.
    """

    color: NDArray[np.float32]
    cascade_color: NDArray[np.float32] | None
    shadow: NDArray[np.float32]
    cascade: NDArray[np.int32]
    position: NDArray[np.float32]
    normal: NDArray[np.float32]
    body: NDArray[np.int32]
    cascades: sm.Cascades
    shadow_maps: NDArray[np.float32]
    draws: DrawLists = ()


def render_cascades(
    bodies: Sequence[Body],
    light: Light,
    view: Any,
    projection: Any,
    *,
    scene_bounds: Any = None,
    image_size: int | tuple[int, int] = (512, 384),
    map_size: int | tuple[int, int] = 1024,
    count: int = 4,
    splits: Any = None,
    scheme: Literal["auto", "uniform", "log", "practical"] = "practical",
    lam: float | None = 0.5,
    max_distance: float | None = None,
    overlap: float = 0.1,
    stable: bool = False,
    warp: Literal[None, "lispsm"] = None,
    orientation: Literal["light", "fitted"] = "light",
    layout: Literal["layers", "atlas"] = "layers",
    pcf_radius: int = 0,
    depth_bias: tuple[float, float] | None = None,
    normal_offset: float = NORMAL_OFFSET,
    cascade_colors: bool = False,
    ambient: float = 0.15,
    background: tuple[float, float, float] = (0.06, 0.07, 0.09),
    light_size: float = 0.0,
    scene_fit: SceneFit = None,
    ctx: moderngl.Context | None = None,
) -> CascadeFrame:
    r"""Render bodies under a sun with cascaded shadow maps fitted to the camera.

    1. :func:`shadowmath.fit_cascades` (``light.direction``, ``view``, ``projection``,
       ``scene_bounds``, ``map_size`` and the split, band, stability, layout and
       ``pcf_radius`` options, OpenGL conventions); or, with ``scene_fit``,
       :meth:`shadowmath.ShadowScene.fit_cascades` of a scene of the bodies (each body
       one object: its mesh, its ``to_world``) with the same options over the scene's
       bounds.
    2. Per cascade ``i``: every body's depth (with ``scene_fit="draw_lists"``, the
       bodies of the cascade's draw list) through ``world_to_clip[i]`` (no polygon
       offset), into layer ``i`` of an ``(n, h, w)`` float texture array
       (``layout="layers"``), or into tile ``viewports[i]`` of one atlas.
    3. The lit pass, then the mask: each visible point's view depth
       ``d = -(view @ p)_z`` picks cascade ``i`` with ``splits[i] <= d < splits[i+1]``;
       ``world_to_texture[i] @ p = (s q, t q, r q, q)`` (``q = 1`` unless ``warp``: the
       shader divides, and its bias follows the warped depth's gradients; ``p`` moved off
       its face by :func:`shadowmath.normal_offset`'s offset) is compared with the map over a
       ``(2k + 1)^2`` box of texels clamped to the tile (``r - b <= stored``: lit, ``b``
       :func:`shadowmath.slope_scaled_bias`'s bias), and for ``d <=
       band_end[i - 1]`` the comparison in cascade ``i - 1`` is mixed in with weight
       ``(band_end[i-1] - d) / (band_end[i-1] - splits[i])``; then the subtractive pass.
       With ``cascade_colors`` a second picture multiplies each pixel by its
       cascade's colour (mixed the same way across the bands).
       With ``light_size > 0`` (the sun's angular radius) the shadow is
       percentage-closer soft shadows instead: the maps hold the faces turned from the
       sun, and in cascade ``i`` each point searches for blockers over
       ``K_i |r - d_near_i|`` texels and filters over ``K_i (r - d_B)``
       (:func:`shadowmath.pcss_parameters` of the cascades: the same world penumbra in
       every cascade, so none jumps at a split), Vogel disks rotated per pixel, taps
       clamped to the tile, the constant bias only; unless ``stable``, the boxes are
       widened first (:func:`shadowmath.widen_cascades`) so that they hold every
       blocker of their receivers' search.

    Arguments:
        bodies: every body casts and receives.
        light: a directional :class:`Light` (``Light(direction=...)``, toward the sun).
        view: ``(4, 4)`` the camera's world-to-view matrix (OpenGL: it looks down ``-z``),
            e.g. :func:`look_at`.
        projection: ``(4, 4)`` its OpenGL projection, e.g. :func:`perspective` (refused, like
            :func:`shadowmath.fit_cascades`'s, unless its last row is perspective or
            orthographic: a transposed matrix is).
        scene_bounds: ``(2, 3)`` ``[min_corner, max_corner]`` holding every caster and
            receiver; default the bodies' bounding box. A caster outside it may lose
            its shadow (the maps reach toward the sun only to the box).
        image_size, map_size: the picture's and each cascade's map size in pixels/texels.
        count, splits, scheme, lam, max_distance, overlap, stable, warp, orientation,
            layout: as in :func:`shadowmath.fit_cascades` (at most :data:`MAX_CASCADES`
            cascades), but the splits default to the practical scheme with ``lam = 0.5``
            (three.js's); ``scheme="auto", lam=None`` is ``fit_cascades``'s default.
        pcf_radius: the PCF kernel's radius ``k`` (also the maps' border).
        depth_bias: ``(factor, units)`` of the slope-scaled bias ``b = units r_min +
            factor m`` (:func:`shadowmath.slope_scaled_bias`'s formula, computed per
            fragment in the shader; ``m`` the receiver's depth slope per texel, ``r_min``
            ``1 / (2^24 - 1)``); default ``(2 k + 1, 2)``, the derived minimum.
        normal_offset: the scale of :func:`shadowmath.normal_offset`'s offset (computed
            per fragment in the shader; :data:`NORMAL_OFFSET` by default, 0 for none).
        cascade_colors: also render the cascade-coloured picture.
        ambient, background: shading as in :func:`render_scene`.
        light_size: the sun's angular radius in radians, ``>= 0``: PCSS when ``> 0``.
        scene_fit: None (default): :func:`shadowmath.fit_cascades` over ``scene_bounds``,
            every body drawn into every cascade. ``"draw_lists"``: the renderer as a client
            of :class:`shadowmath.ShadowScene`: the bodies added as one object each, the
            cascades of :meth:`~shadowmath.ShadowScene.fit_cascades` (over the scene's
            bounds: no ``scene_bounds``), each cascade drawn only the bodies of its draw
            list. Not with ``warp`` nor with ``light_size > 0`` unless ``stable`` (the
            lists are culled to the unwarped, unwidened maps). ``"every_caster"``: the
            same scene fit, every body drawn into every cascade (what the draw lists are
            compared with).
        ctx: a moderngl context; default the shared EGL :func:`standalone_context`.

    Returns:
        :class:`CascadeFrame`.

    Raises:
        ValueError: bad bodies, matrices, sizes or options; a light that is not
            directional; more than :data:`MAX_CASCADES` cascades; ``scene_fit`` with
            ``scene_bounds``, or ``"draw_lists"`` with ``warp`` or an unstable
            ``light_size > 0``; and whatever :func:`shadowmath.fit_cascades` raises.
        GLUnavailableError: no OpenGL context could be created.

    Example:
        >>> from shadowmath.meshes import box, grid
        >>> from shadowmath.render import Body, Light, look_at, perspective
        >>> ground = Body(*grid((100.0, 100.0), segments=(1, 1)))
        >>> tower = Body(*box((2.0, 2.0, 8.0)), to_world=np.array(
        ...     [[1, 0, 0, 5], [0, 1, 0, 20], [0, 0, 1, 4], [0, 0, 0, 1.0]]))
        >>> view = look_at([0, -40, 3], [0, 0, 1], [0, 0, 1])
        >>> frame = render_cascades([ground, tower], Light(direction=(1, 1, 2)), view,
        ...                         perspective(50.0, 1.0, 0.5, 100.0), image_size=64)
        >>> frame.shadow.shape, frame.cascades.world_to_clip.shape
        ((64, 64), (4, 4, 4))
    """
    options = cascade_options(
        layout=layout, pcf_radius=pcf_radius, depth_bias=depth_bias,
        normal_offset=normal_offset, ambient=ambient, background=background,
        cascade_colors=cascade_colors, light_size=light_size,
    )  # fmt: skip
    fit_options = fit_keywords(locals())
    scene = describe_cascades(
        bodies, light, view, projection, options=options, fit_options=fit_options,
        scene_fit=scene_fit,
    )  # fmt: skip
    size = _image_size("image_size", image_size)
    texels = _image_size("map_size", map_size)
    gl = resolve_context(ctx)
    v, p = scene.view, scene.projection
    with GpuScene(gl, scene.bodies, (), [scene.sun], p @ v, size=size, map_size=texels) as gpu:
        return _draw(gpu, scene)


def _draw(scene: GpuScene, described: CascadePass) -> CascadeFrame:
    """The maps (cascade ``i`` the bodies ``draws[i]``), the lit pass, the mask and
    subtractive passes, the debug tint; read back."""
    (sun,) = scene.lights
    options, fit = described.options, described.fit
    draw_lit(scene, options.ambient, options.background)
    back_faces = options.light_size > 0
    depths = draw_cascade_maps(scene, described.maps, fit.texture_size, back_faces=back_faces)
    maps = _depth_array(scene.ctx, depths)
    block = scene.ctx.buffer(described.frame.tobytes())
    try:
        scene.clear_mask()
        scene.bind_mask()
        _shade(scene, block, maps, mode=0)
        shadow = read_texture(scene.mask_tex, 1)[..., 0]
        subtract_light(scene, sun, tuple(range(len(scene.bodies))))
        color = read_texture(scene.color_tex, 4)[..., :3]
        tinted = None
        if options.cascade_colors:
            scene.use(scene.color_fbo)
            scene.color_fbo.depth_mask = False
            scene.surface_tex.use(location=1)
            scene.blend(moderngl.FUNC_ADD)
            scene.ctx.blend_func = moderngl.DST_COLOR, moderngl.ZERO  # multiply
            _shade(scene, block, maps, mode=1)
            tinted = np.clip(read_texture(scene.color_tex, 4)[..., :3], 0.0, 1.0)
    finally:
        block.release()
        maps.release()
        finish(scene)
    position, normal, body = scene.read_record()
    return CascadeFrame(
        color=np.clip(color, 0.0, 1.0).astype(np.float32),
        cascade_color=None if tinted is None else tinted.astype(np.float32),
        shadow=shadow.astype(np.float32),
        cascade=cascade_index(position, described.view, np.asarray(fit.splits)),
        position=position,
        normal=normal,
        body=body,
        cascades=fit,
        shadow_maps=depths,
        draws=described.draws,
    )


def draw_cascade_maps(
    scene: GpuScene,
    maps: Sequence[MapDraw],
    size: tuple[int, int],
    *,
    back_faces: bool = False,
) -> NDArray[np.float32]:
    """Each :class:`MapDraw`'s bodies into its layer and viewport of depth maps of
    ``size``: ``(layers, h, w)`` window depths, row 0 ``t = 0`` (one layer per cascade, or
    one atlas layer); no polygon offset (``cascades.frag`` biases each receiver);
    ``back_faces``: only the faces turned from the sun (:func:`cull_faces_toward_light`)."""
    gl = scene.ctx
    prog = program(gl, "depth_map.vert", "depth_map.frag")
    layers = []
    for layer in range(max(m.layer for m in maps) + 1):
        tex = gl.depth_texture(size)
        fbo = gl.framebuffer(depth_attachment=tex)
        try:
            begin_depth_pass(gl, fbo, (0.0, 0.0))
            for drawn in (m for m in maps if m.layer == layer):
                fbo.viewport = drawn.viewport
                for b, body_to_clip in zip(drawn.bodies, drawn.body_to_clip, strict=True):
                    if back_faces:
                        cull_faces_toward_light(gl, body_to_clip)
                    set_matrix(prog, "body_to_clip", body_to_clip)
                    scene.meshes[b].render(prog)
            data = np.frombuffer(tex.read(alignment=1), dtype=np.float32)
            layers.append(data.reshape(size[1], size[0]).copy())
        finally:
            gl.polygon_offset = (0.0, 0.0)
            gl.disable(moderngl.CULL_FACE)
            fbo.release()
            tex.release()
    return np.stack(layers)


def _depth_array(gl: moderngl.Context, depths: NDArray[np.float32]) -> moderngl.TextureArray:
    """The ``(layers, h, w)`` depths as an R32F texture array (nearest, clamped)."""
    n, h, w = depths.shape
    tex = gl.texture_array((w, h, n), 1, np.ascontiguousarray(depths).tobytes(), dtype="f4")
    tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
    tex.repeat_x = False
    tex.repeat_y = False
    return tex


def _shade(
    scene: GpuScene, block: moderngl.Buffer, maps: moderngl.TextureArray, *, mode: int
) -> None:
    """Every body through ``cascades.frag`` in ``mode`` (0 the mask, 1 the cascade tint),
    into the bound target (the lit pass's record on unit 1, the maps on unit 0, the
    description's uniform block :data:`FRAME_DTYPE` bound to block 0)."""
    prog = program(scene.ctx, "surface.vert", "cascades.frag")
    colors = np.array([CASCADE_COLORS[i % len(CASCADE_COLORS)] for i in range(MAX_CASCADES)])
    set_matrix(prog, "world_to_clip", scene.world_to_clip)
    set_uniform(prog, "maps", 0)
    set_uniform(prog, "mode", mode)
    uniform(prog, "colors").write(colors.astype(np.float32).tobytes())
    bind_block(prog, "Frame", block)
    maps.use(location=0)
    for i, (body, mesh) in enumerate(zip(scene.bodies, scene.meshes, strict=True)):
        set_matrix(prog, "body_to_world", body.to_world)
        scene.bind_record(prog, i)
        mesh.render(prog)
