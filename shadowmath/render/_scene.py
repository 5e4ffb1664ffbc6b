"""The whole method from a camera: the lit pass, then per light its shadow system's mask
and the subtractive pass. Each shadow system is a pass module (``_pass_texture``,
``_pass_planar``, ...), a subclass of :class:`ShadowPass` picked by ``method``."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, Literal, NamedTuple

import moderngl
import numpy as np
from numpy.typing import NDArray

from shadowmath import ShadowSetup

from ._context import check_matrix, resolve_context
from ._context import image_size as _image_size
from ._pass_depth import DepthPass
from ._pass_lit import MAX_LIGHTS, draw_lit, finish, subtract_light
from ._pass_omni import OmniPass
from ._pass_omni_pcss import OmniPcssPass
from ._pass_pcss import PcssPass
from ._pass_planar import PlanarPass
from ._pass_soft import RadiancePass, SoftPass
from ._pass_texture import TexturePass
from ._resources import (
    Body,
    GpuScene,
    Light,
    PassOptions,
    ShadowPass,
    prepare_bodies,
    prepare_light,
    read_texture,
)

#: The shadow systems that draw directional lights (``Light(direction=...)``).
DIRECTIONAL_METHODS = ("planar", "depth", "pcss")

#: The shadow systems by ``method`` name: each takes the options of :func:`render_scene`
#: it uses (``pcf_radius``, ``depth_bias``) and ignores the others.
PASSES: dict[str, Callable[[PassOptions], ShadowPass]] = {
    "texture": lambda _: TexturePass(),
    "planar": lambda _: PlanarPass(),
    "depth": lambda o: DepthPass(o.pcf_radius, o.depth_bias),
    "omni": lambda o: (
        OmniPcssPass(o.light_size, o.depth_bias) if o.light_size else OmniPass(o.depth_bias)
    ),
    "soft": lambda o: SoftPass(o.samples, o.seed, o.pcf_radius, o.depth_bias),
    "radiance": lambda o: RadiancePass(o.samples, o.seed),
    "pcss": lambda o: PcssPass(o.light_size, o.depth_bias),
}


class Frame(NamedTuple):
    """What :func:`render_scene` returns; images have row 0 at the *top* (as saved).

    Attributes:
        color: ``(H, W, 3)`` float32 in ``[0, 1]``, the final picture.
        shadow: ``(H, W, L)`` float32, light ``l``'s combined shadow mask on the visible
            receivers (1 shadowed, 0 lit; 0 on blockers and background). With
            ``method="depth"`` on every visible body, and PCF gives fractions.
        position: ``(H, W, 3)`` float32 world position of the visible surface (NaN on
            the background).
        normal: ``(H, W, 3)`` float32 unit face normal of the visible surface (NaN on
            the background).
        body: ``(H, W)`` int32, which body is visible: ``0 .. R-1`` the receivers,
            ``R .. R+B-1`` the blockers, ``-1`` the background.
        setups: ``setups[l][b]`` the :class:`ShadowSetup` of light ``l`` and blocker ``b``
            (``method="depth"``: ``setups[l][0]``, one per light, fitted to all blockers;
            ``method="omni"`` and ``"radiance"``: none, ``setups[l] == ()``;
            ``method="soft"``: one ``method="depth"`` setup per light sample;
            ``method="pcss"``: as ``"depth"``).
        shadow_maps: ``shadow_maps[l][b]`` the ``(h, w)`` pass-1 mask, as
            :func:`render_shadow_map` returns it (row 0 is ``t = 0``);
            ``method="depth"``: ``shadow_maps[l][0]`` the light's depth map, window
            depths in ``[0, 1]`` (1 where nothing was drawn); ``method="omni"``: the six
            cube faces ``+X, -X, +Y, -Y, +Z, -Z``, window depths, row 0 is ``t = 0``;
            ``method="soft"``: none; ``method="radiance"``: ``shadow_maps[l][r]``
            receiver ``r``'s visibility texture (:func:`radiance_texture`);
            ``method="pcss"``: as ``"depth"``, of the faces turned from the light.
    """

    color: NDArray[np.float32]
    shadow: NDArray[np.float32]
    position: NDArray[np.float32]
    normal: NDArray[np.float32]
    body: NDArray[np.int32]
    setups: tuple[tuple[ShadowSetup, ...], ...]
    shadow_maps: tuple[tuple[NDArray[np.float32], ...], ...]


def render_scene(
    receivers: Sequence[Body],
    blockers: Sequence[Body],
    lights: Sequence[Light],
    world_to_clip: Any,
    *,
    image_size: int | tuple[int, int] = (512, 384),
    map_size: int | tuple[int, int] = 256,
    method: Literal["texture", "planar", "depth", "omni", "soft", "radiance", "pcss"] = "texture",
    ambient: float = 0.15,
    background: tuple[float, float, float] = (0.06, 0.07, 0.09),
    setups: Sequence[Sequence[ShadowSetup]] | None = None,
    pcf_radius: int = 0,
    depth_bias: tuple[float, float] | None = None,
    samples: int = 16,
    seed: int | None = 0,
    light_size: float = 0.0,
    ctx: moderngl.Context | None = None,
) -> Frame:
    r"""Render receivers in the shadows of blockers, the article's passes on the GPU.

    1. **Lit pass**: every body with ambient plus Lambert diffuse from each light
       (``albedo (a + sum_l c_l max(0, n . l))``), depth-tested; it also records the
       visible body's id, world position and face normal per pixel.
    2. Per light, per blocker: the **shadow map** (:func:`render_shadow_map`'s pass,
       with ``setup.blocker_to_clip``), then the **shadow mask**: with
       ``method="texture"`` each receiver is drawn again with the map as a
       projective texture through ``receiver_texture_matrix(setup, to_world)``
       (``textureProj``, clamp to edge, no shadow where ``q <= 0`` or on faces with
       ``N . (L - P) <= 0``); with ``method="planar"`` (pass 3) the blocker is
       flattened onto each receiver's plane with :func:`planar_projection`, drawn with
       a polygon offset of :data:`PLANAR_POLYGON_OFFSET` against z-fighting, and
       skipped for a light on the other side of the plane than the camera (the
       visible face is unlit: Blinn's back-face case). With ``method="depth"``
       (Williams' shadow z-buffer) one setup per light fits all blockers, its depth
       range enclosing every body inside the map's sides (``fit_shadow(...,
       receivers=)``; orthographic for a directional light); **every body** (receivers and
       blockers) is drawn into a depth texture with ``glPolygonOffset(*depth_bias)``
       and every body is then shadowed by comparing its light depth ``r`` with the
       map (``sampler2DShadow``) over a ``(2k + 1)^2`` box of texels (PCF,
       ``k = pcf_radius``); outside the map, behind the light and on faces turned
       from the light: lit. With ``method="omni"`` the light shines in every
       direction: every body is drawn into a GL **cube depth map**, six square
       ``map_size`` faces through ``cube_face_projection(near, far, map_size) @
       cube_face_views(light)[i]`` with ``glPolygonOffset(*depth_bias)``, and every body
       is shadowed by ``samplerCubeShadow`` along ``p - light`` against its window depth
       on the selected face (:func:`cube_face_depth`'s ``depth``); ``far`` is just
       beyond the farthest body vertex, ``near = 1e-3 far``.
       **Soft shadows** need area lights (``Light(centre, edge_u=..., edge_v=...)``),
       sampled at ``samples`` stratified jittered points
       (:func:`shadowmath.area_light_samples`, ``seed``); the mask is the blocked
       fraction of the light. ``method="soft"`` (seed 003): per sample, the
       ``method="depth"`` map and comparison from that sample (every body casts and
       receives), added into the mask with weight ``1 / samples``.
       ``method="radiance"`` (Heckbert and Herf): per receiver (each needs a ``plane``),
       a radiance texture of ``map_size`` texels over the rectangle around it in its
       plane (:func:`radiance_texture`), drawn onto it. The lit pass lights from the
       area light's centre.
       ``method="pcss"`` (Fernando's percentage-closer soft shadows, real time): one
       ``method="depth"`` map per light of ``light_size`` (a point light's radius, a
       directional light's angular radius in radians), holding the faces turned from the
       light (closed casters: the surface nearest the receiver, so the shadow hardens
       where a caster touches it), with a border as wide as the widest blocker search;
       each visible point searches the map for blockers over ``K |d_R - d_near|`` texels
       and filters over ``K (d_R - d_B)`` (``K``, ``d_near``:
       :func:`shadowmath.pcss_parameters`; ``d_B`` the found blockers' mean depth), each
       over a Vogel disk rotated per pixel (interleaved gradient noise).
       ``method="omni"`` with ``light_size > 0``: the same PCSS through the point
       light's cube map (a sphere of that radius), each face fitted with
       :func:`shadowmath.cube_depth_range` to every body and a border ring as wide as
       the widest search, searched and filtered in the texture coordinates of the face
       that sees the point (:func:`shadowmath.pcss_parameters` of the range: one ``K``
       for every face).
    3. **Subtractive pass** per light (pass 4): each shadowed body drawn again with
       ``FUNC_REVERSE_SUBTRACT`` blending removes that light's diffuse term where its
       mask is set, so the shadows of several lights compose correctly.

    **No stencil in moderngl 5**: the seeds use the stencil buffer twice, to confine
    planar shadows to the receiver and to darken overlapping shadows once. Here the
    lit pass writes each pixel's body id into a float attachment, and the mask
    passes discard fragments whose pixel shows another body (the stencil test);
    the mask passes blend with ``MAX`` into a one-channel float texture, so a pixel
    covered by several flattened triangles, or by the shadows of several blockers
    of the same light, is marked once, and the subtractive pass then darkens it
    once. The mask and subtractive passes share the lit pass's depth buffer and
    vertex shader (``invariant gl_Position``) and test ``LEQUAL`` without writing
    depth, the article's advice for multipass rendering.

    Arguments:
        receivers: the bodies that receive shadows.
        blockers: the bodies that cast them (drawn lit, not shadowed).
        lights: up to :data:`MAX_LIGHTS` lights: points (``Light(position)``), or
            with ``method="planar"``, ``"depth"`` and ``"pcss"`` also directional lights
            (``Light(direction=...)``, toward the light; the depth map is then
            orthographic, from ``fit_shadow((x, y, z, 0), ...)``).
        world_to_clip: ``(4, 4)`` the camera, e.g. ``perspective(...) @ look_at(...)``.
        image_size: ``size`` or ``(width, height)`` of the picture in pixels.
        map_size: ``size`` or ``(width, height)`` of each shadow map in texels.
        method: ``"texture"`` (Nagy's projective shadow texture), ``"planar"``
            (Blinn's planar projection: every receiver needs a ``plane``) or
            ``"depth"`` (Williams' shadow z-buffer: every body casts and receives) or
            ``"omni"`` (a cube depth map: every body casts and receives, in every
            direction from the light; ``map_size`` must be square), ``"soft"`` (the
            averaged depth-map shadows of an area light's samples), ``"radiance"``
            (Heckbert and Herf's radiance textures: every receiver needs a ``plane``) or
            ``"pcss"`` (percentage-closer soft shadows of a light of ``light_size``).
        ambient: the ambient term ``a``.
        background: RGB of empty pixels.
        setups: ``setups[l][b]`` to use instead of ``fit_shadow(light, blocker, map_size,
            blocker_to_world=to_world)`` (e.g. matrices computed with JAX);
            ``method="depth"``: one per light, world coordinates to the light's clip
            (``blocker_to_clip @ inv(blocker_to_world)``) with a depth range that
            encloses the receivers.
        pcf_radius: ``method="depth"``: the PCF kernel's radius ``k`` in texels.
        depth_bias: ``method="depth"``, ``"omni"`` and ``"pcss"``: ``(factor, units)`` of
            the depth map's polygon offset (slope-scaled and constant); default
            ``(2.5 + 2 k, 4.0)``, with ``"pcss"`` :data:`PCSS_POLYGON_OFFSET`.
        samples: ``method="soft"`` and ``"radiance"``: points per area light, ``>= 1``.
        seed: ``method="soft"`` and ``"radiance"``: the samples' jitter seed (None: fresh
            jitter each call).
        light_size: ``method="pcss"``: a point light's radius (world units) or a
            directional light's angular radius (radians), ``>= 0`` (0: hard shadows);
            ``method="omni"``: the point light's radius (0: the hard cube-map shadow).
        ctx: a moderngl context; default the shared EGL :func:`standalone_context`.

    Returns:
        :class:`Frame`.

    Raises:
        ValueError: bad meshes, matrices, sizes, colours; no lights or too many; a
            receiver without a plane under ``method="planar"`` or ``"radiance"``; a
            directional light under another method than ``"planar"``, ``"depth"`` and
            ``"pcss"``; a point light or bad ``samples`` under ``method="soft"`` or
            ``"radiance"``; a negative or non-finite ``light_size`` under ``"pcss"`` or
            ``"omni"``;
            ``setups`` of the wrong shape; and whatever :func:`fit_shadow` raises for a
            light and a blocker.
        GLUnavailableError: no OpenGL context could be created.

    Example:
        >>> from shadowmath.meshes import grid, sphere
        >>> from shadowmath.render import Body, Light, look_at, perspective, render_scene
        >>> floor = Body(*grid((6.0, 6.0)), plane=(0, 0, 1, 0))
        >>> ball = Body(*sphere(0.5), to_world=np.array(
        ...     [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 1.5], [0, 0, 0, 1.0]]))
        >>> camera = perspective(50.0, 1.0, 0.1, 50.0) @ look_at([0, -6, 5], [0, 0, 0], [0, 0, 1])
        >>> frame = render_scene([floor], [ball], [Light([0, 0, 5])], camera,
        ...                      image_size=64)
        >>> frame.color.shape, frame.shadow.shape
        ((64, 64, 3), (64, 64, 1))
    """
    if method not in PASSES:
        raise ValueError(f"method: expected one of {', '.join(map(repr, PASSES))}, got {method!r}")
    shadow_pass = PASSES[method](PassOptions(pcf_radius, depth_bias, samples, seed, light_size))
    if not 1 <= len(lights) <= MAX_LIGHTS:
        raise ValueError(f"lights: expected 1 to {MAX_LIGHTS} lights, got {len(lights)}")
    if not (np.isfinite(ambient) and ambient >= 0):
        raise ValueError(f"ambient: must be finite and >= 0, got {ambient!r}")
    camera = check_matrix("world_to_clip", world_to_clip)
    size = _image_size("image_size", image_size)
    map_texels = _image_size("map_size", map_size)
    recv, block = prepare_bodies("receivers", receivers), prepare_bodies("blockers", blockers)
    shadow_pass.check(recv)
    light_data = [prepare_light(f"lights[{i}]", light) for i, light in enumerate(lights)]
    for i, light in enumerate(light_data):
        if light.directional and method not in DIRECTIONAL_METHODS:
            raise ValueError(
                f"lights[{i}].direction: method={method!r} takes point lights only; "
                f"directional lights are drawn by {' and '.join(map(repr, DIRECTIONAL_METHODS))}"
            )
    count = shadow_pass.setup_count(block)
    if setups is None:
        all_setups = tuple(shadow_pass.fit(recv, block, light, map_texels) for light in light_data)
    else:
        all_setups = tuple(tuple(per_light) for per_light in setups)
        if len(all_setups) != len(lights) or any(len(s) != count for s in all_setups):
            raise ValueError(
                f"setups: expected {len(lights)} lists (one per light) of {count} "
                f"ShadowSetups each (method={method!r})"
            )

    gl = resolve_context(ctx)
    with GpuScene(gl, recv, block, light_data, camera, size=size, map_size=map_texels) as scene:
        return _draw(scene, shadow_pass, all_setups, ambient, background)


def _draw(
    scene: GpuScene,
    shadow_pass: ShadowPass,
    setups: tuple[tuple[ShadowSetup, ...], ...],
    ambient: float,
    background: tuple[float, float, float],
) -> Frame:
    draw_lit(scene, ambient, background)
    shadowed = shadow_pass.shadowed(scene)
    shadows, maps = [], []
    for light, light_setups in zip(scene.lights, setups, strict=True):
        scene.clear_mask()
        maps.append(shadow_pass.draw_mask(scene, light, light_setups))
        shadows.append(read_texture(scene.mask_tex, 1)[..., 0])
        subtract_light(scene, light, shadowed)
    finish(scene)
    color = read_texture(scene.color_tex, 4)[..., :3]
    position, normal, body = scene.read_record()
    return Frame(
        color=np.clip(color, 0.0, 1.0).astype(np.float32),
        shadow=np.stack(shadows, axis=-1).astype(np.float32),
        position=position,
        normal=normal,
        body=body,
        setups=setups,
        shadow_maps=tuple(maps),
    )
