"""Williams' shadow z-buffer on a second graphics API: WebGPU through ``wgpu``
(wgpu-native over Vulkan; Mesa's llvmpipe without a GPU).

The same scene, setup and bias as :class:`DepthPass`, with WebGPU's conventions
(:func:`shadowmath.api_convention` ``api="webgpu"``): clip depth ``0..w``,
framebuffer and texture origin at the top left. The OpenGL clip matrices of
:func:`fit_shadow` and the camera are converted by ``C = gl_clip_to_clip``, the
texture matrix is ``gl_clip_to_texture @ (world to the light's OpenGL clip)``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, NamedTuple

import numpy as np
import wgpu
from numpy.typing import NDArray

from shadowmath import ShadowSetup, api_convention, column_major_bytes

from ._context import check_matrix, shader_source
from ._context import image_size as _image_size
from ._pass_depth import DepthPass, fit_depth, world_to_light_clip
from ._resources import Body, Light, Prepared, prepare_bodies, prepare_light, vertex_data

#: Debian packages that provide a Vulkan driver without a GPU (Mesa's lavapipe/llvmpipe).
VULKAN_DEBIAN_PACKAGES = ("mesa-vulkan-drivers",)

_devices: list[Any] = []

#: One body of a camera pass: its bind group 0 entries, its vertex buffer and vertex count.
CameraDraw = tuple[list[Any], Any, int]


class WgpuUnavailableError(RuntimeError):
    """No WebGPU adapter could be found (no Vulkan driver)."""


class WgpuFrame(NamedTuple):
    """What :func:`render_depth_wgpu` returns; images have row 0 at the *top*.

    Attributes:
        shadow: ``(H, W)`` float32 shadow mask of the visible bodies (1 shadowed,
            PCF fractions, 0 lit and on the background).
        position: ``(H, W, 3)`` float32 world position of the visible surface (NaN on
            the background).
        normal: ``(H, W, 3)`` float32 unit face normal (NaN on the background).
        body: ``(H, W)`` int32: ``0 .. R-1`` receivers, ``R ..`` blockers, ``-1`` none.
        setup: the light's :class:`ShadowSetup` (OpenGL conventions, as fitted).
        depth_map: ``(h, w)`` float32 depths in ``[0, 1]``; row 0 is WebGPU's ``t = 0``,
            the *top* of the light's view (``depth_map[::-1]`` is OpenGL's layout).
        adapter: the adapter's description, e.g. ``"llvmpipe (LLVM 15.0.6, 256 bits)"``.
    """

    shadow: NDArray[np.float32]
    position: NDArray[np.float32]
    normal: NDArray[np.float32]
    body: NDArray[np.int32]
    setup: ShadowSetup
    depth_map: NDArray[np.float32]
    adapter: str


def wgpu_device() -> Any:
    """The shared WebGPU device, created on first use.

    Raises:
        WgpuUnavailableError: no adapter (on Debian: ``apt-get install -y
            mesa-vulkan-drivers``).
    """
    if not _devices:
        try:
            _vulkan_only()
            adapter = wgpu.gpu.request_adapter_sync(power_preference="high-performance")
            if adapter is None:
                raise RuntimeError("request_adapter_sync returned no adapter")
            device = adapter.request_device_sync()
        except Exception as err:  # wgpu raises several kinds
            raise WgpuUnavailableError(
                f"no WebGPU adapter through wgpu ({err}); on Debian/Ubuntu install "
                f"{', '.join(VULKAN_DEBIAN_PACKAGES)} "
                f"(apt-get install -y {' '.join(VULKAN_DEBIAN_PACKAGES)})"
            ) from err
        _devices.append((adapter, device))
    return _devices[0][1]


def _vulkan_only() -> None:
    """Keep wgpu-native off its OpenGL (EGL) backend: probing it makes wgpu's own EGL
    context current on this thread, and moderngl's shared context then fails."""
    from wgpu.backends.wgpu_native import extras

    try:
        extras.set_instance_extras(backends=["Vulkan"])
    except Exception:  # the instance exists already: keep it
        return


def adapter_description() -> str:
    """The shared device's adapter, as ``request_adapter_sync`` reports it."""
    wgpu_device()
    info = _devices[0][0].info
    return str(info.get("device", "")) or str(info)


def wgsl_module(device: Any, name: str) -> Any:
    return device.create_shader_module(label=name, code=shader_source(name))


def uniform_buffer(device: Any, data: bytes) -> Any:
    usage = wgpu.BufferUsage.UNIFORM | wgpu.BufferUsage.COPY_DST
    return device.create_buffer_with_data(data=data, usage=usage)


def normal_to_world(body_to_world: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(4, 4)`` the inverse transpose of ``body_to_world``'s 3x3: normals to world."""
    normal = np.eye(4)
    normal[:3, :3] = np.linalg.inv(body_to_world[:3, :3]).T
    return normal


def body_matrices(
    world_to_clip: NDArray[np.float64],
    body_to_world: NDArray[np.float64],
    body_to_texture: NDArray[np.float64],
) -> bytes:
    """The four ``mat4x4`` a camera pass's ``struct Body`` begins with (column-major):
    the camera, ``body_to_world``, :func:`normal_to_world` and ``body_to_texture``."""
    normal = normal_to_world(body_to_world)
    return b"".join(
        column_major_bytes(m) for m in (world_to_clip, body_to_world, normal, body_to_texture)
    )


def _scene_uniforms(
    matrices: bytes, light: NDArray[np.float64], *, body_id: int, pcf_radius: int
) -> bytes:
    """``struct Body`` of depth_scene.wgsl: the four mat4x4 ``matrices``
    (:func:`body_matrices`), vec3 + f32, i32."""
    tail = np.zeros(8, dtype=np.float32)
    tail[:3] = light
    tail[3] = body_id
    tail_bytes = bytearray(tail.tobytes())
    tail_bytes[16:20] = np.int32(pcf_radius).tobytes()
    return matrices + bytes(tail_bytes)


class LightMapDraws(NamedTuple):
    """A one-light camera pass's draws in WebGPU's conventions (:func:`light_map_draws`).

    Attributes:
        map: each body's ``(C @ world_to_light_clip @ to_world, vertex buffer, count)``
            (``C = gl_clip_to_clip``), to draw the light's map.
        matrices: each body's four ``mat4x4`` of the camera pass (:func:`body_matrices`:
            the camera ``C @ world_to_clip``, ``to_world``, its normal matrix and
            ``gl_clip_to_texture @ world_to_light_clip @ to_world``).
    """

    map: list[tuple[NDArray[np.float64], Any, int]]
    matrices: list[bytes]


def light_map_draws(
    setup: ShadowSetup,
    camera: NDArray[np.float64],
    bodies: Sequence[Prepared],
    buffers: Sequence[tuple[Any, int]],
) -> LightMapDraws:
    """The light's map and the camera pass of ``bodies`` (their :func:`vertex_buffers`)
    with the OpenGL ``setup`` and camera ``world_to_clip``, converted by
    ``api_convention(api="webgpu")``."""
    conv = api_convention(api="webgpu")
    light_clip = world_to_light_clip(setup)
    light_to_clip = conv.gl_clip_to_clip @ light_clip
    world_to_texture = conv.gl_clip_to_texture @ light_clip
    camera_clip = conv.gl_clip_to_clip @ camera
    draws = [(light_to_clip @ b.to_world, v, n) for b, (v, n) in zip(bodies, buffers, strict=True)]
    matrices = [
        body_matrices(camera_clip, b.to_world, world_to_texture @ b.to_world) for b in bodies
    ]
    return LightMapDraws(draws, matrices)


def camera_frame(
    device: Any,
    shader: str,
    draws: Sequence[CameraDraw],
    *,
    size: tuple[int, int],
    depth_map: Any,
    setup: ShadowSetup,
) -> WgpuFrame:
    """:func:`draw_camera` of ``shader``, read back with the light's ``depth_map`` texture
    as a :class:`WgpuFrame`."""
    targets = draw_camera(device, shader, size, draws)
    mask, position, normal, body = read_record(device, targets, size)
    texels = (depth_map.width, depth_map.height)
    depth = read_wgpu_texture(device, depth_map, texels, 1)[..., 0].astype(np.float32)
    return WgpuFrame(mask, position, normal, body, setup, depth, adapter_description())


#: The vertex buffers' layout (:func:`vertex_data`): position at 0, face normal at 1.
VERTEX_LAYOUT: dict[str, Any] = {
    "array_stride": 36,
    "step_mode": "vertex",
    "attributes": [
        {"format": "float32x3", "offset": 0, "shader_location": 0},
        {"format": "float32x3", "offset": 24, "shader_location": 1},
    ],
}


def vertex_buffers(device: Any, bodies: Sequence[Prepared]) -> list[tuple[Any, int]]:
    """Each body's un-indexed vertex buffer and its vertex count."""
    usage = wgpu.BufferUsage.VERTEX
    return [
        (device.create_buffer_with_data(data=vertex_data(b.vertices, b.triangles), usage=usage),
         3 * len(b.triangles))
        for b in bodies
    ]  # fmt: skip


def depth_pipeline(
    device: Any, bias: tuple[float, float] = (0.0, 0.0), cull_mode: str = "none"
) -> Any:
    """Depth only through ``depth_map.wgsl`` into ``depth32float``, test ``less``, the
    faces ``cull_mode`` keeps (``"none"``: both; front faces counter-clockwise), WebGPU's
    polygon offset ``bias = (factor, units)`` (``units`` rounded)."""
    return device.create_render_pipeline(
        layout="auto",
        vertex={
            "module": wgsl_module(device, "depth_map.wgsl"),
            "entry_point": "vs_main",
            "buffers": [{**VERTEX_LAYOUT, "attributes": VERTEX_LAYOUT["attributes"][:1]}],
        },
        primitive={"topology": "triangle-list", "cull_mode": cull_mode},
        depth_stencil={
            "format": "depth32float",
            "depth_write_enabled": True,
            "depth_compare": "less",
            "depth_bias": round(bias[1]),  # an integer in WebGPU
            "depth_bias_slope_scale": float(bias[0]),
            "depth_bias_clamp": 0.0,
        },
        fragment=None,
    )


def draw_faces_away(
    device: Any,
    pipelines: dict[str, Any],
    target: Any,
    draws: Sequence[tuple[NDArray[np.float64], Any, int]],
    viewport: tuple[int, int, int, int],
) -> None:
    """:func:`draw_depth` of only the faces turned from the light (PCSS's back-face maps):
    ``pipelines["back"]`` culls the counter-clockwise faces' backs, ``pipelines["front"]``
    serves the draws whose ``body_to_clip`` reverses orientation (``det < 0``: the
    Jacobian of ``p -> (M p)_xyz / (M p)_w`` is ``det M / w^4``, the winding turns)."""
    for cull in ("back", "front"):
        group = [d for d in draws if (np.linalg.det(d[0]) < 0) == (cull == "front")]
        draw_depth(device, pipelines[cull], target, group, viewport)


def draw_depth(
    device: Any,
    pipeline: Any,
    target: Any,
    draws: Sequence[tuple[NDArray[np.float64], Any, int]],
    viewport: tuple[int, int, int, int] | None = None,
) -> None:
    """Clear the depth view ``target`` to 1 (or only draw, with ``viewport``: a tile of it
    already cleared, the viewport and the scissor rect) and draw each ``(body_to_clip,
    vertex buffer, count)``."""
    encoder = device.create_command_encoder()
    rp = encoder.begin_render_pass(
        color_attachments=[],
        depth_stencil_attachment={
            "view": target,
            "depth_clear_value": 1.0,
            "depth_load_op": "clear" if viewport is None else "load",
            "depth_store_op": "store",
        },
    )
    rp.set_pipeline(pipeline)
    if viewport is not None:
        rp.set_viewport(*viewport, 0.0, 1.0)
        rp.set_scissor_rect(*viewport)
    layout = pipeline.get_bind_group_layout(0)
    for body_to_clip, vbo, count in draws:
        buf = uniform_buffer(device, column_major_bytes(body_to_clip))
        group = device.create_bind_group(
            layout=layout, entries=[{"binding": 0, "resource": {"buffer": buf}}]
        )
        rp.set_bind_group(0, group)
        rp.set_vertex_buffer(0, vbo)
        rp.draw(count)
    rp.end()
    device.queue.submit([encoder.finish()])


#: The camera passes' targets: the shadow, the position (w = body id + 1), the normal.
CAMERA_TARGETS = ("r32float", "rgba32float", "rgba32float")


def draw_camera(
    device: Any, shader: str, size: tuple[int, int], draws: Sequence[CameraDraw]
) -> list[Any]:
    """Each ``(bind group 0 entries, vertex buffer, count)`` through ``shader``'s ``vs_main``
    and ``fs_main`` with a depth test, into cleared :data:`CAMERA_TARGETS` of ``size``
    (returned, for :func:`read_record`)."""
    w, h = size
    usage = wgpu.TextureUsage.RENDER_ATTACHMENT | wgpu.TextureUsage.COPY_SRC
    targets = [device.create_texture(size=(w, h, 1), format=f, usage=usage) for f in CAMERA_TARGETS]
    depth = device.create_texture(size=(w, h, 1), format="depth32float",
                                  usage=wgpu.TextureUsage.RENDER_ATTACHMENT)  # fmt: skip
    module = wgsl_module(device, shader)
    pipeline = device.create_render_pipeline(
        layout="auto",
        vertex={"module": module, "entry_point": "vs_main", "buffers": [VERTEX_LAYOUT]},
        primitive={"topology": "triangle-list", "cull_mode": "none"},
        depth_stencil={"format": "depth32float", "depth_write_enabled": True,
                       "depth_compare": "less"},
        fragment={"module": module, "entry_point": "fs_main",
                  "targets": [{"format": f} for f in CAMERA_TARGETS]},
    )  # fmt: skip
    encoder = device.create_command_encoder()
    rp = encoder.begin_render_pass(
        color_attachments=[{"view": t.create_view(), "clear_value": (0.0, 0.0, 0.0, 0.0),
                            "load_op": "clear", "store_op": "store"} for t in targets],
        depth_stencil_attachment={"view": depth.create_view(), "depth_clear_value": 1.0,
                                  "depth_load_op": "clear", "depth_store_op": "store"},
    )  # fmt: skip
    rp.set_pipeline(pipeline)
    for entries, vbo, count in draws:
        layout = pipeline.get_bind_group_layout(0)
        rp.set_bind_group(0, device.create_bind_group(layout=layout, entries=entries))
        rp.set_vertex_buffer(0, vbo)
        rp.draw(count)
    rp.end()
    device.queue.submit([encoder.finish()])
    return targets


def read_record(
    device: Any, targets: Sequence[Any], size: tuple[int, int]
) -> tuple[NDArray[np.float32], NDArray[np.float32], NDArray[np.float32], NDArray[np.int32]]:
    """The camera pass's ``r32float`` shadow and ``rgba32float`` position (w = body id + 1)
    and normal targets, read back: shadow ``(H, W)``, position and normal ``(H, W, 3)``
    (NaN on the background), body ``(H, W)`` (``-1`` the background)."""
    shadow = read_wgpu_texture(device, targets[0], size, 1)[..., 0].astype(np.float32)
    surface = read_wgpu_texture(device, targets[1], size, 4)
    normal = read_wgpu_texture(device, targets[2], size, 4)[..., :3]
    body = np.rint(surface[..., 3]).astype(np.int32) - 1
    empty = (body < 0)[..., None]
    position = np.where(empty, np.float32(np.nan), surface[..., :3]).astype(np.float32)
    return shadow, position, np.where(empty, np.float32(np.nan), normal).astype(np.float32), body


def read_wgpu_texture(
    device: Any, texture: Any, size: tuple[int, int], components: int, layer: int = 0
) -> NDArray[Any]:
    """``(h, w, components)`` float32 of a texture's ``layer``, row 0 its first row."""
    w, h = size
    data = device.queue.read_texture(
        {"texture": texture, "mip_level": 0, "origin": (0, 0, layer)},
        {"offset": 0, "bytes_per_row": 4 * components * w},
        (w, h, 1),
    )
    return np.frombuffer(data, dtype=np.float32).reshape(h, w, components).copy()


def _depth_map(device: Any, texels: tuple[int, int], bias: tuple[float, float], draws: Any) -> Any:
    """A ``depth32float`` map drawn with the pipeline's depth bias ``(factor, units)``."""
    depth_tex = depth_map_texture(device, texels)
    draw_depth(device, depth_pipeline(device, bias), depth_tex.create_view(), draws)
    return depth_tex


def depth_map_texture(device: Any, texels: tuple[int, int]) -> Any:
    """A ``depth32float`` texture to draw a light's map into, sample and read back."""
    return device.create_texture(
        size=(*texels, 1),
        format="depth32float",
        usage=wgpu.TextureUsage.RENDER_ATTACHMENT
        | wgpu.TextureUsage.TEXTURE_BINDING
        | wgpu.TextureUsage.COPY_SRC,
    )


def _compare_sampler(device: Any) -> Any:
    """The map's comparison sampler: ``less-equal``, nearest texel, clamped to the edge."""
    return device.create_sampler(
        compare="less-equal",
        mag_filter="nearest",
        min_filter="nearest",
        address_mode_u="clamp-to-edge",
        address_mode_v="clamp-to-edge",
    )


def render_depth_wgpu(
    receivers: Sequence[Body],
    blockers: Sequence[Body],
    light: Light,
    world_to_clip: Any,
    *,
    image_size: int | tuple[int, int] = (512, 384),
    map_size: int | tuple[int, int] = 256,
    pcf_radius: int = 0,
    depth_bias: tuple[float, float] | None = None,
    setup: ShadowSetup | None = None,
) -> WgpuFrame:
    """Williams' shadow z-buffer with WebGPU: :func:`render_scene`'s ``method="depth"``
    on a second graphics API.

    The light's setup is the same as :class:`DepthPass`'s (one frustum fitted to the
    blockers, its far plane enclosing every body), converted with
    ``api_convention(api="webgpu")``: the depth map is drawn through
    ``C @ world_to_light_clip`` into a ``depth32float`` texture with the pipeline's
    ``depthBias = units`` and ``depthBiasSlopeScale = factor`` (WebGPU's polygon
    offset), then every body is drawn from the camera (``C @ world_to_clip``) and
    compared with ``textureSampleCompareLevel`` (``less-equal``) at
    ``gl_clip_to_texture @ world_to_light_clip``, over a ``(2k + 1)^2`` box.

    Arguments:
        receivers, blockers: as in :func:`render_scene`; every body casts and
            receives, the frustum's sides fit the blockers.
        light: one point light.
        world_to_clip: ``(4, 4)`` the camera in OpenGL's clip conventions (converted here).
        image_size, map_size: ``size`` or ``(width, height)`` in pixels and texels.
        pcf_radius: the PCF kernel's radius ``k`` in texels.
        depth_bias: ``(factor, units)``; default as :func:`render_scene`'s (WebGPU's
            ``depthBias`` is an integer: ``units`` is rounded).
        setup: the light's :class:`ShadowSetup` instead of the fitted one.

    Returns:
        :class:`WgpuFrame`.

    Raises:
        ValueError: bad input, as :func:`render_scene`.
        WgpuUnavailableError: no WebGPU adapter.
    """
    camera = check_matrix("world_to_clip", world_to_clip)
    size = _image_size("image_size", image_size)
    map_texels = _image_size("map_size", map_size)
    options = DepthPass(pcf_radius, depth_bias)  # checks both
    factor, units = options.bias
    k = options.pcf_radius
    recv, block = prepare_bodies("receivers", receivers), prepare_bodies("blockers", blockers)
    lit = prepare_light("light", light)
    if lit.directional:
        raise ValueError("light.direction: render_depth_wgpu takes a point light only")
    if setup is None:
        setup = fit_depth(recv, block, lit.position, map_texels, k)
    bodies, device = recv + block, wgpu_device()
    buffers = vertex_buffers(device, bodies)
    drawn = light_map_draws(setup, camera, bodies, buffers)
    depth_tex = _depth_map(device, map_texels, (factor, units), drawn.map)  # pass 1: the map
    # Pass 2: the bodies from the camera, compared with the map.
    sampler = _compare_sampler(device)
    depth_view = depth_tex.create_view()
    draws = []
    for i, ((vbo, count), matrices) in enumerate(zip(buffers, drawn.matrices, strict=True)):
        data = _scene_uniforms(matrices, lit.position, body_id=i, pcf_radius=k)
        entries = [
            {"binding": 0, "resource": {"buffer": uniform_buffer(device, data)}},
            {"binding": 1, "resource": depth_view},
            {"binding": 2, "resource": sampler},
        ]
        draws.append((entries, vbo, count))
    return camera_frame(
        device, "depth_scene.wgsl", draws, size=size, depth_map=depth_tex, setup=setup
    )
