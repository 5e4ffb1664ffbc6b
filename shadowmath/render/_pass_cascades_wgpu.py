"""Cascaded shadow maps on WebGPU (``wgpu``): :func:`render_cascades_wgpu`.

The WebGPU counterpart of :func:`render_cascades`, a client of the public API:
:func:`shadowmath.fit_cascades` with ``api="webgpu"`` gives every matrix and viewport in
WebGPU's conventions (clip depth ``0..w``, texture and viewport origin at the first row
in memory); each cascade's depth (with ``scene_fit="draw_lists"``, of its draw list of a
:class:`shadowmath.ShadowScene` of the bodies) is drawn into a layer of a ``depth32float``
texture array (or a tile of one atlas layer, through ``viewports[i]``) with no depth bias, and the
camera pass ``shaders/cascades.wgsl`` picks, blends, biases and filters as
``shaders/cascades.frag`` does.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Literal, NamedTuple

import numpy as np
import wgpu
from numpy.typing import NDArray

import shadowmath as sm
from shadowmath import api_convention, column_major_bytes

from ._context import image_size as _image_size
from ._pass_atlas import DrawLists, SceneFit
from ._pass_cascades import (
    MAX_CASCADES,
    NORMAL_OFFSET,
    CascadeOptions,
    CascadeScene,
    cascade_index,
    cascade_options,
    cascade_pcss_parameters,
    prepare_cascades,
)
from ._pass_wgpu import (
    adapter_description,
    depth_pipeline,
    draw_camera,
    draw_depth,
    draw_faces_away,
    normal_to_world,
    read_record,
    read_wgpu_texture,
    uniform_buffer,
    vertex_buffers,
    wgpu_device,
)
from ._resources import Body, Light

#: The resolution ``r_min`` of a ``depth32float`` buffer near depth 1 (as
#: :func:`shadowmath.slope_scaled_bias` with ``depth_bits=None``): ``depth_bias``'s unit.
FLOAT_DEPTH_RESOLUTION = 2.0**-24


class WgpuCascadeFrame(NamedTuple):
    """What :func:`render_cascades_wgpu` returns; images have row 0 at the *top*.

    Attributes:
        shadow: ``(H, W)`` float32 shadow mask (1 shadowed, 0 lit; PCF and the blend
            bands give fractions; 0 on the background).
        cascade: ``(H, W)`` int32, the cascade serving each pixel's view depth (``-1``
            on the background and beyond the last split).
        position: ``(H, W, 3)`` float32 world position of the visible surface (NaN on
            the background).
        normal: ``(H, W, 3)`` float32 unit face normal (NaN on the background).
        body: ``(H, W)`` int32, which body is visible (``-1`` the background).
        cascades: the :class:`shadowmath.Cascades` (``api="webgpu"``) drawn and sampled.
        shadow_maps: ``(layers, h, w)`` float32 depths, row 0 is WebGPU's ``t = 0``: one
            layer per cascade, or the whole atlas as one layer.
        adapter: the adapter's description.
        draws: as in :class:`CascadeFrame`.
    """

    shadow: NDArray[np.float32]
    cascade: NDArray[np.int32]
    position: NDArray[np.float32]
    normal: NDArray[np.float32]
    body: NDArray[np.int32]
    cascades: sm.Cascades
    shadow_maps: NDArray[np.float32]
    adapter: str
    draws: DrawLists = ()


def render_cascades_wgpu(
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
    light_size: float = 0.0,
    scene_fit: SceneFit = None,
) -> WgpuCascadeFrame:
    """Render bodies under a sun with cascaded shadow maps, in WebGPU.

    :func:`render_cascades` on a second graphics API: the same arguments (``view`` and
    ``projection`` in OpenGL's conventions, as :func:`look_at` and :func:`perspective`
    give them), the cascades fitted with ``api="webgpu"``, the camera converted by
    ``api_convention(api="webgpu").gl_clip_to_clip``. Every body casts and receives.

    Arguments:
        bodies: every body casts and receives.
        light: a directional :class:`Light` (``Light(direction=...)``, toward the sun).
        view, projection: the camera, in OpenGL's conventions, as in :func:`render_cascades`.
        scene_bounds, image_size, map_size: as in :func:`render_cascades`.
        count, splits, scheme, lam, max_distance, overlap, stable, warp, orientation,
            layout: as in :func:`shadowmath.fit_cascades` (at most :data:`MAX_CASCADES`
            cascades), but the splits default to the practical scheme with ``lam = 0.5``
            (three.js's); ``scheme="auto", lam=None`` is ``fit_cascades``'s default.
        pcf_radius, normal_offset: as in :func:`render_cascades`.
        depth_bias: as in :func:`render_cascades`, ``units`` counting
            :data:`FLOAT_DEPTH_RESOLUTION` (``depth32float`` maps).
        light_size: the sun's angular radius in radians, ``>= 0``: PCSS when ``> 0``, as
            in :func:`render_cascades` (the cascades widened by
            :func:`shadowmath.widen_cascades` unless ``stable``, the maps holding the faces
            turned from the sun, ``pcss.wgsl`` with each cascade's ``K`` and near depth of
            :func:`shadowmath.pcss_parameters`, taps clamped to the cascade's tile).
        scene_fit: as in :func:`render_cascades`: ``"draw_lists"`` fits the cascades by
            :meth:`shadowmath.ShadowScene.fit_cascades` (``api="webgpu"``) and draws each
            cascade's draw list, ``"every_caster"`` the same fit with every body.

    Returns:
        :class:`WgpuCascadeFrame`.

    Raises:
        ValueError: as :func:`render_cascades`.
        WgpuUnavailableError: no WebGPU adapter.

    Example:
        >>> from shadowmath.meshes import box, grid
        >>> from shadowmath.render import Body, Light, look_at, perspective
        >>> ground = Body(*grid((100.0, 100.0), segments=(1, 1)))
        >>> tower = Body(*box((2.0, 2.0, 8.0)), to_world=np.array(
        ...     [[1, 0, 0, 5], [0, 1, 0, 20], [0, 0, 1, 4], [0, 0, 0, 1.0]]))
        >>> view = look_at([0, -40, 3], [0, 0, 1], [0, 0, 1])
        >>> frame = render_cascades_wgpu([ground, tower], Light(direction=(1, 1, 2)), view,
        ...                              perspective(50.0, 1.0, 0.5, 100.0), image_size=64,
        ...                              map_size=256, layout="atlas")
        >>> frame.shadow.shape, frame.shadow_maps.shape
        ((64, 64), (1, 512, 512))
    """
    options = cascade_options(layout=layout, pcf_radius=pcf_radius, depth_bias=depth_bias,
                              normal_offset=normal_offset, light_size=light_size)  # fmt: skip
    fit_options = {
        "scene_bounds": scene_bounds, "map_size": map_size, "count": count, "splits": splits,
        "scheme": scheme, "lam": lam, "max_distance": max_distance, "overlap": overlap,
        "stable": stable, "warp": warp, "orientation": orientation,
    }  # fmt: skip
    scene = prepare_cascades(
        bodies, light, view, projection, options=options, fit_options=fit_options, api="webgpu",
        scene_fit=scene_fit,
    )  # fmt: skip
    size = _image_size("image_size", image_size)
    device = wgpu_device()
    buffers = vertex_buffers(device, scene.bodies)
    maps, depths = _draw_maps(
        device, scene, buffers, atlas=options.layout == "atlas", back_faces=options.light_size > 0
    )
    targets = _draw_camera(device, scene, options, buffers, maps, size=size)
    shadow, position, normal, body = read_record(device, targets, size)
    return WgpuCascadeFrame(
        shadow=shadow,
        cascade=cascade_index(position, scene.view, np.asarray(scene.fit.splits)),
        position=position,
        normal=normal,
        body=body,
        cascades=scene.fit,
        shadow_maps=depths,
        adapter=adapter_description(),
        draws=scene.draws,
    )


def _draw_maps(
    device: Any,
    scene: CascadeScene,
    buffers: Sequence[tuple[Any, int]],
    *,
    atlas: bool,
    back_faces: bool,
) -> tuple[Any, NDArray[np.float32]]:
    """The depth of the bodies ``scene.draws[i]`` into each cascade ``i``'s map: a
    ``depth32float`` texture array of one layer per cascade, or of one atlas layer with
    each cascade in its viewport (only the faces turned from the sun with ``back_faces``,
    as the 2D PCSS pass's map); the texture and its ``(layers, h, w)`` depths read back."""
    fit = scene.fit
    ports = np.asarray(fit.viewports, dtype=np.int64)
    clip = np.asarray(fit.world_to_clip, dtype=np.float64)
    (w, h), layers = fit.texture_size, fit.texture_layers
    usage = wgpu.TextureUsage
    texture = device.create_texture(
        size=(w, h, layers), format="depth32float",
        usage=usage.RENDER_ATTACHMENT | usage.TEXTURE_BINDING | usage.COPY_SRC,
    )  # fmt: skip
    pipelines = {cull: depth_pipeline(device, cull_mode=cull) for cull in ("none", "back", "front")}
    for i, port in enumerate(ports):
        draws = [(clip[i] @ scene.bodies[b].to_world, *buffers[b]) for b in scene.draws[i].tolist()]
        layer = 0 if atlas else i
        target = texture.create_view(dimension="2d", base_array_layer=layer, array_layer_count=1)
        if not atlas or i == 0:
            draw_depth(device, pipelines["none"], target, [])  # clear the layer
        x, y, tw, th = (int(c) for c in port)
        if not back_faces:
            draw_depth(device, pipelines["none"], target, draws, (x, y, tw, th))
            continue
        draw_faces_away(device, pipelines, target, draws, (x, y, tw, th))
    depths = np.stack(
        [read_wgpu_texture(device, texture, (w, h), 1, layer)[..., 0] for layer in range(layers)]
    )
    return texture, depths.astype(np.float32)


def _frame_uniforms(scene: CascadeScene, options: CascadeOptions) -> bytes:
    """``struct Frame`` of cascades.wgsl (1024 bytes): with PCSS, each cascade's ``K``
    and near depth (:func:`cascade_pcss_parameters`)."""
    fit = scene.fit
    conv = api_convention(api="webgpu")
    camera = conv.gl_clip_to_clip @ scene.projection @ scene.view
    head = np.zeros(16, dtype=np.float32)
    head[:4] = -scene.view[2]
    head[4:8] = scene.sun.homogeneous
    ints = np.array([len(fit.viewports), options.pcf_radius, options.layout == "atlas"], np.int32)
    floats = np.array([options.normal_offset, *options.bias], dtype=np.float32)
    floats[2] *= FLOAT_DEPTH_RESOLUTION  # constant_bias in depth units
    pcss = np.array([options.light_size > 0], np.int32)
    data = column_major_bytes(camera) + head[:8].tobytes() + ints.tobytes() + floats.tobytes()
    data += pcss.tobytes()
    data += bytes(128 - len(data))
    splits = np.asarray(fit.splits, dtype=np.float32)
    band = np.asarray(fit.band_end, dtype=np.float32)
    n = len(fit.viewports)
    k, near = np.zeros((n, 2)), np.zeros(n)
    if options.light_size > 0:
        p = cascade_pcss_parameters(fit, options.light_size)
        k, near = np.asarray(p.texels_per_depth), np.asarray(p.near_depth)
    for i, port in enumerate(np.asarray(fit.viewports, dtype=np.int32)):
        tail = np.array([splits[i], splits[i + 1], band[i], 0.0, *k[i], near[i], 0.0], np.float32)
        data += column_major_bytes(fit.world_to_texture[i]) + port.tobytes() + tail.tobytes()
    return data + bytes(112 * (MAX_CASCADES - n))


def _body_uniforms(body_to_world: NDArray[np.float64], body_id: int) -> bytes:
    """``struct Body`` of cascades.wgsl: two mat4x4 and the id (144 bytes)."""
    normal = column_major_bytes(normal_to_world(body_to_world))
    tail = np.array([body_id, 0, 0, 0], dtype=np.float32)
    return column_major_bytes(body_to_world) + normal + tail.tobytes()


def _draw_camera(
    device: Any,
    scene: CascadeScene,
    options: CascadeOptions,
    buffers: Sequence[tuple[Any, int]],
    maps: Any,
    *,
    size: tuple[int, int],
) -> list[Any]:
    """Every body from the camera through cascades.wgsl (:func:`draw_camera`)."""
    frame = uniform_buffer(device, _frame_uniforms(scene, options))
    maps_view = maps.create_view(dimension="2d-array")
    draws = []
    for i, (body, (vbo, n)) in enumerate(zip(scene.bodies, buffers, strict=True)):
        buffer = uniform_buffer(device, _body_uniforms(body.to_world, i))
        entries = [{"binding": 0, "resource": {"buffer": frame}},
                   {"binding": 1, "resource": maps_view},
                   {"binding": 2, "resource": {"buffer": buffer}}]  # fmt: skip
        draws.append((entries, vbo, n))
    return draw_camera(device, "cascades.wgsl", size, draws)
