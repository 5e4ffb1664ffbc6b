"""Many shadowed lights through one shadow atlas on WebGPU (``wgpu``): :func:`render_atlas_wgpu`.

The WebGPU counterpart of :func:`render_atlas`, a client of the public API:
:func:`shadowmath.allocate_atlas` and :func:`shadowmath.fit_atlas` with ``api="webgpu"``
(clip depth ``0..w``, texture and viewport origin at the first row in memory); every
caster's depth (with ``scene_fit="draw_lists"``, each tile's draw list of a
:class:`shadowmath.ShadowScene` of the bodies) is drawn into each tile's viewport
(scissored to it) of one ``depth32float`` texture with the pipeline's depth bias, and the
camera pass ``shaders/atlas.wgsl`` picks each light's tile, biases and filters as
``shaders/atlas.frag`` does.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, NamedTuple

import numpy as np
import wgpu
from numpy.typing import NDArray

import shadowmath as sm
from shadowmath import api_convention, column_major_bytes

from ._atlas_pass import NORMAL_OFFSET, AtlasLight, AtlasPass, describe_atlas
from ._context import image_size as _image_size
from ._map_draws import DrawLists
from ._pass_wgpu import (
    CameraDraw,
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
from ._resources import Body
from ._scene_fit import SceneFit


class WgpuAtlasFrame(NamedTuple):
    """What :func:`render_atlas_wgpu` returns; images have row 0 at the *top*.

    Attributes:
        shadow, position, normal, body, atlas, draws: as in :class:`AtlasFrame`.
        fit: the :class:`shadowmath.AtlasFit` (``api="webgpu"``) drawn and sampled.
        shadow_map: ``(A, A)`` float32 depths of the whole atlas, row 0 its first row in
            memory (WebGPU's ``t = 0``); 1 where nothing was drawn.
        adapter: the adapter's description.
    """

    shadow: NDArray[np.float32]
    position: NDArray[np.float32]
    normal: NDArray[np.float32]
    body: NDArray[np.int32]
    atlas: sm.ShadowAtlas
    fit: sm.AtlasFit
    shadow_map: NDArray[np.float32]
    adapter: str
    draws: DrawLists = ()


def render_atlas_wgpu(
    bodies: Sequence[Body],
    lights: Sequence[AtlasLight],
    view: Any,
    projection: Any,
    *,
    casters: Sequence[bool] | None = None,
    coverage: Any = None,
    atlas_size: int = 2048,
    budget: float = 1.0,
    previous: sm.ShadowAtlas | None = None,
    pcf_radius: int = 1,
    depth_bias: tuple[float, float] | None = None,
    normal_offset: float = NORMAL_OFFSET,
    image_size: int | tuple[int, int] = (512, 384),
    light_size: Any = None,
    scene_fit: SceneFit = None,
) -> WgpuAtlasFrame:
    """Render each light's shadow on the bodies through one shadow atlas, in WebGPU.

    :func:`render_atlas`'s shadow masks on a second graphics API: the same arguments
    (``view`` and ``projection`` in OpenGL's conventions, as :func:`look_at` and
    :func:`perspective` give them), the same atlas, the tiles fitted with
    ``api="webgpu"``, the camera converted by ``api_convention(api="webgpu").gl_clip_to_clip``.
    The atlas is a ``depth32float`` texture; tile ``t`` is drawn with
    ``set_viewport(viewports[t])`` and ``set_scissor_rect(viewports[t])``. No picture:
    one camera pass per light, its mask.

    Arguments:
        bodies, lights, view, projection, casters, coverage, atlas_size, budget, previous,
            pcf_radius, normal_offset, image_size, scene_fit: as in :func:`render_atlas`.
        depth_bias: ``(factor, units)`` as in :func:`render_atlas`: the pipeline's
            ``depthBiasSlopeScale`` and ``depthBias`` (an integer in WebGPU: ``units`` is
            rounded; its unit is ``2^(e - 23)`` at a triangle's largest depth ``z`` with
            ``2^e <= z``, ``2^-24`` near depth 1 as a 24-bit buffer's).
        light_size: ``(L,)`` each light's radius, PCSS as in :func:`render_atlas`: each
            tile's ``K`` and ``d_near`` from :func:`shadowmath.pcss_parameters` of the fit
            (atlas texels), the tiles drawn with only the faces turned from the light, the
            search and filter of ``pcss.wgsl`` with every tap clamped to the tile.

    Returns:
        :class:`WgpuAtlasFrame`.

    Raises:
        ValueError: as :func:`render_atlas`.
        WgpuUnavailableError: no WebGPU adapter.

    Example:
        >>> import shadowmath as sm
        >>> from shadowmath.meshes import box, grid
        >>> from shadowmath.render import Body, look_at, perspective
        >>> ground = Body(*grid((20.0, 20.0), segments=(1, 1)))
        >>> cube = Body(*box((2.0, 2.0, 2.0)), to_world=np.array(
        ...     [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 1], [0, 0, 0, 1.0]]))
        >>> lights = [sm.PointLight(np.array([3.0, 0.0, 4.0])),
        ...           sm.DirectionalLight(np.array([1.0, 1.0, 2.0]))]
        >>> frame = render_atlas_wgpu([ground, cube], lights,
        ...                           look_at([0, -12, 8], [0, 0, 0], [0, 0, 1]),
        ...                           perspective(50.0, 1.0, 0.5, 50.0), casters=[False, True],
        ...                           image_size=64, atlas_size=512)
        >>> frame.shadow.shape, frame.atlas.tile_light.tolist()
        ((2, 64, 64), [0, 0, 0, 0, 0, 0, 1])
    """
    scene = describe_atlas(
        bodies, lights, view, projection, casters=casters, colors=None, coverage=coverage,
        atlas_size=atlas_size, budget=budget, previous=previous, pcf_radius=pcf_radius,
        depth_bias=depth_bias, normal_offset=normal_offset, light_size=light_size,
        api="webgpu", scene_fit=scene_fit,
    )  # fmt: skip
    size = _image_size("image_size", image_size)
    device = wgpu_device()
    buffers = vertex_buffers(device, scene.bodies)
    texture = _draw_atlas(device, scene, buffers)
    draws = _body_draws(device, scene, buffers, texture)
    shadow = []
    for light in range(len(scene.lights)):
        targets = _draw_camera(device, scene, draws, size, light)
        mask, position, normal, body = read_record(device, targets, size)
        shadow.append(mask)
    return WgpuAtlasFrame(
        shadow=np.stack(shadow),
        position=position,
        normal=normal,
        body=body,
        atlas=scene.atlas,
        fit=scene.fit,
        shadow_map=read_wgpu_texture(device, texture, scene.fit.texture_size, 1)[..., 0],
        adapter=adapter_description(),
        draws=scene.draws,
    )


def _draw_atlas(device: Any, scene: AtlasPass, buffers: Sequence[tuple[Any, int]]) -> Any:
    """Each :class:`MapDraw`'s bodies (a tile's draw list) into its viewport (scissored) of
    one ``depth32float`` texture cleared to 1, with the polygon offset ``scene.bias``;
    returns the texture."""
    width, height = scene.fit.texture_size
    usage = wgpu.TextureUsage
    texture = device.create_texture(
        size=(width, height, 1), format="depth32float",
        usage=usage.RENDER_ATTACHMENT | usage.TEXTURE_BINDING | usage.COPY_SRC,
    )  # fmt: skip
    target = texture.create_view()
    pipelines = {c: depth_pipeline(device, scene.bias, c) for c in ("none", "back", "front")}
    draw_depth(device, pipelines["none"], target, [])  # clear
    for drawn in scene.maps:
        draws = [(m, *buffers[b]) for b, m in zip(drawn.bodies, drawn.body_to_clip, strict=True)]
        if scene.pcss is None:
            draw_depth(device, pipelines["none"], target, draws, drawn.viewport)
        else:
            draw_faces_away(device, pipelines, target, draws, drawn.viewport)
    return texture


def _storage(device: Any, data: bytes) -> Any:
    return device.create_buffer_with_data(data=data, usage=wgpu.BufferUsage.STORAGE)


def _body_draws(
    device: Any, scene: AtlasPass, buffers: Sequence[tuple[Any, int]], texture: Any
) -> list[CameraDraw]:
    """Each body's bind group entries of atlas.wgsl but the frame's (bindings 1 to 4), its
    vertex buffer and count."""
    tiles, lights = (_storage(device, t.tobytes()) for t in (scene.tiles, scene.lights))
    view = texture.create_view()
    draws = []
    for i, (body, (vbo, n)) in enumerate(zip(scene.bodies, buffers, strict=True)):
        data = column_major_bytes(body.to_world) + column_major_bytes(
            normal_to_world(body.to_world)
        )
        data += np.array([i, scene.cast[i], 0.0, 0.0], dtype=np.float32).tobytes()
        own = uniform_buffer(device, data)
        entries = [{"binding": 1, "resource": view},
                   {"binding": 2, "resource": {"buffer": tiles}},
                   {"binding": 3, "resource": {"buffer": lights}},
                   {"binding": 4, "resource": {"buffer": own}}]  # fmt: skip
        draws.append((entries, vbo, n))
    return draws


def _draw_camera(
    device: Any,
    scene: AtlasPass,
    draws: Sequence[CameraDraw],
    size: tuple[int, int],
    which: int,
) -> list[Any]:
    """Every body (:func:`_body_draws`) from the camera through atlas.wgsl, light ``which``'s
    mask (:func:`draw_camera`)."""
    camera = api_convention(api="webgpu").gl_clip_to_clip @ scene.projection @ scene.view
    head = np.array([which, scene.pcf_radius], dtype=np.int32).tobytes()
    head += np.array([scene.normal_offset, 0.0], dtype=np.float32).tobytes()
    frame = {
        "binding": 0,
        "resource": {"buffer": uniform_buffer(device, column_major_bytes(camera) + head)},
    }
    return draw_camera(device, "atlas.wgsl", size, [([frame, *e], vbo, n) for e, vbo, n in draws])
