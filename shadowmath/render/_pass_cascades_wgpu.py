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
from shadowmath import column_major_bytes

from ._cascade_pass import (
    FLOAT_DEPTH_RESOLUTION as FLOAT_DEPTH_RESOLUTION,
)
from ._cascade_pass import (
    NORMAL_OFFSET,
    CascadePass,
    cascade_index,
    cascade_options,
    describe_cascades,
    fit_keywords,
)
from ._context import image_size as _image_size
from ._map_draws import DrawLists
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
from ._scene_fit import SceneFit


class WgpuCascadeFrame(NamedTuple):
    """What :func:`render_cascades_wgpu` returns; images have row 0 at the *top*.

    Attributes:
        shadow: ``(H, W)`` float32 shadow mask, as in :class:`CascadeFrame` (0 on the
            background).
        cascade, position, normal, body: as in :class:`CascadeFrame`.
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
    fit_options = fit_keywords(locals())
    scene = describe_cascades(
        bodies, light, view, projection, options=options, fit_options=fit_options, api="webgpu",
        scene_fit=scene_fit,
    )  # fmt: skip
    size = _image_size("image_size", image_size)
    device = wgpu_device()
    buffers = vertex_buffers(device, scene.bodies)
    maps, depths = _draw_maps(device, scene, buffers)
    targets = _draw_camera(device, scene, buffers, maps, size=size)
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
    device: Any, scene: CascadePass, buffers: Sequence[tuple[Any, int]]
) -> tuple[Any, NDArray[np.float32]]:
    """Each :class:`MapDraw`'s bodies into its layer and viewport of a ``depth32float``
    texture array (one layer per cascade, or one atlas layer; with PCSS only the faces
    turned from the sun, as the 2D PCSS pass's map); the texture and its ``(layers, h,
    w)`` depths read back."""
    (w, h), layers = scene.fit.texture_size, scene.fit.texture_layers
    usage = wgpu.TextureUsage
    texture = device.create_texture(
        size=(w, h, layers), format="depth32float",
        usage=usage.RENDER_ATTACHMENT | usage.TEXTURE_BINDING | usage.COPY_SRC,
    )  # fmt: skip
    pipelines = {cull: depth_pipeline(device, cull_mode=cull) for cull in ("none", "back", "front")}
    cleared = set()
    for drawn in scene.maps:
        draws = [(m, *buffers[b]) for b, m in zip(drawn.bodies, drawn.body_to_clip, strict=True)]
        target = texture.create_view(
            dimension="2d", base_array_layer=drawn.layer, array_layer_count=1
        )
        if drawn.layer not in cleared:
            draw_depth(device, pipelines["none"], target, [])  # clear the layer
            cleared.add(drawn.layer)
        if scene.options.light_size > 0:
            draw_faces_away(device, pipelines, target, draws, drawn.viewport)
        else:
            draw_depth(device, pipelines["none"], target, draws, drawn.viewport)
    depths = np.stack(
        [read_wgpu_texture(device, texture, (w, h), 1, layer)[..., 0] for layer in range(layers)]
    )
    return texture, depths.astype(np.float32)


def _body_uniforms(body_to_world: NDArray[np.float64], body_id: int) -> bytes:
    """``struct Body`` of cascades.wgsl: two mat4x4 and the id (144 bytes)."""
    normal = column_major_bytes(normal_to_world(body_to_world))
    tail = np.array([body_id, 0, 0, 0], dtype=np.float32)
    return column_major_bytes(body_to_world) + normal + tail.tobytes()


def _draw_camera(
    device: Any,
    scene: CascadePass,
    buffers: Sequence[tuple[Any, int]],
    maps: Any,
    *,
    size: tuple[int, int],
) -> list[Any]:
    """Every body from the camera through cascades.wgsl (:func:`draw_camera`), the
    description's uniform block (:data:`FRAME_DTYPE`) bound as ``frame``."""
    frame = uniform_buffer(device, scene.frame.tobytes())
    maps_view = maps.create_view(dimension="2d-array")
    draws = []
    for i, (body, (vbo, n)) in enumerate(zip(scene.bodies, buffers, strict=True)):
        buffer = uniform_buffer(device, _body_uniforms(body.to_world, i))
        entries = [{"binding": 0, "resource": {"buffer": frame}},
                   {"binding": 1, "resource": maps_view},
                   {"binding": 2, "resource": {"buffer": buffer}}]  # fmt: skip
        draws.append((entries, vbo, n))
    return draw_camera(device, "cascades.wgsl", size, draws)
