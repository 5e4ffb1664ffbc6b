"""Percentage-closer soft shadows on WebGPU: :class:`PcssPass`'s map and quantities, the
blocker search and filter of ``pcss.wgsl`` (``pcss.glsl`` in WGSL, tap for tap)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ._context import check_matrix
from ._context import image_size as _image_size
from ._pass_pcss import PcssPass, PcssUniforms, map_parameters, pcss_uniforms
from ._pass_wgpu import (
    WgpuFrame,
    camera_frame,
    depth_map_texture,
    depth_pipeline,
    draw_depth,
    light_map_draws,
    uniform_buffer,
    vertex_buffers,
    wgpu_device,
)
from ._resources import Body, Light, prepare_bodies, prepare_light


def back_face_map(
    device: Any, texels: tuple[int, int], bias: tuple[float, float], draws: Any
) -> Any:
    """A ``depth32float`` map of the faces turned from the light: each ``(body_to_clip,
    vertex buffer, count)`` culls its counter-clockwise (outside) faces where
    ``body_to_clip`` keeps orientation, its clockwise ones where it reverses it
    (``det < 0``, as :func:`cull_faces_toward_light`); the second group loads the first's."""
    depth_tex = depth_map_texture(device, texels)
    view = depth_tex.create_view()
    for i, cull in enumerate(("back", "front")):
        group = [d for d in draws if (np.linalg.det(d[0]) < 0) == (cull == "front")]
        viewport = None if i == 0 else (0, 0, *texels)
        draw_depth(device, depth_pipeline(device, bias, cull), view, group, viewport)
    return depth_tex


def pcss_body_uniforms(
    matrices: bytes, light: NDArray[np.float64], body_id: int, uniforms: PcssUniforms
) -> bytes:
    """``struct Body`` of pcss_scene.wgsl: the four matrices, then ``light: vec4`` (w = 0
    a directional light), ``body_id: f32``, ``k: vec2`` (at byte 280), ``d_near: f32``;
    304 bytes."""
    tail = np.zeros(12, dtype=np.float32)
    tail[:4], tail[4] = light, body_id
    tail[6:8], tail[8] = uniforms.k, uniforms.d_near
    return matrices + tail.tobytes()


def render_pcss_wgpu(
    receivers: Sequence[Body],
    blockers: Sequence[Body],
    light: Light,
    world_to_clip: Any,
    *,
    light_size: float,
    image_size: int | tuple[int, int] = (512, 384),
    map_size: int | tuple[int, int] = 256,
    depth_bias: tuple[float, float] | None = None,
) -> WgpuFrame:
    """``render_scene(..., method="pcss")`` on WebGPU: one light's percentage-closer soft
    shadows.

    The light's setup, border and ``K``, ``d_near`` are :class:`PcssPass`'s
    (:func:`shadowmath.pcss_parameters`); the map, converted with
    ``api_convention(api="webgpu")``, holds the faces turned from the light
    (:func:`back_face_map`); every body is drawn from the camera and searched and
    filtered over Vogel disks rotated per pixel (``pcss_scene.wgsl``, ``pcss.wgsl``).

    Arguments:
        receivers, blockers: as in :func:`render_scene`.
        light: one point light (``light_size`` its radius) or directional light
            (``light_size`` its angular radius in radians).
        world_to_clip: ``(4, 4)`` the camera in OpenGL's clip conventions.
        light_size: ``>= 0``.
        image_size, map_size: ``size`` or ``(width, height)`` in pixels and texels.
        depth_bias: ``(factor, units)``; default :data:`PCSS_POLYGON_OFFSET`.

    Returns:
        :class:`WgpuFrame` (``depth_map`` row 0 is ``t = 0``, WebGPU's top row).

    Raises:
        ValueError: bad input, as :func:`render_scene`.
        WgpuUnavailableError: no WebGPU adapter.
    """
    camera = check_matrix("world_to_clip", world_to_clip)
    size, texels = _image_size("image_size", image_size), _image_size("map_size", map_size)
    options = PcssPass(light_size, depth_bias)
    recv, block = prepare_bodies("receivers", receivers), prepare_bodies("blockers", blockers)
    lit = prepare_light("light", light)
    (setup,) = options.fit(recv, block, lit, texels)
    uniforms = pcss_uniforms(map_parameters(setup, lit, options.light_size, texels))
    bodies, device = recv + block, wgpu_device()
    buffers = vertex_buffers(device, bodies)
    drawn = light_map_draws(setup, camera, bodies, buffers)
    depth_tex = back_face_map(device, texels, options.bias, drawn.map)
    view = depth_tex.create_view()
    camera_draws = []
    for i, ((vbo, count), matrices) in enumerate(zip(buffers, drawn.matrices, strict=True)):
        data = pcss_body_uniforms(matrices, lit.homogeneous, i, uniforms)
        entries = [
            {"binding": 0, "resource": {"buffer": uniform_buffer(device, data)}},
            {"binding": 1, "resource": view},
        ]
        camera_draws.append((entries, vbo, count))
    return camera_frame(
        device, "pcss_scene.wgsl", camera_draws, size=size, depth_map=depth_tex, setup=setup
    )
