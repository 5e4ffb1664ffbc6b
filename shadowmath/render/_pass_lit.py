"""The lit pass (every body, ambient plus Lambert from every light, and the per-pixel
record) and the subtractive pass that composes each light's shadow mask into it."""

from __future__ import annotations

from collections.abc import Sequence

import moderngl
import numpy as np

from ._context import program, set_matrix, set_uniform, uniform
from ._resources import GpuScene, PreparedLight

#: The most lights one :func:`render_scene` call lights with (a shader array size).
MAX_LIGHTS = 8


def draw_lit(scene: GpuScene, ambient: float, background: tuple[float, float, float]) -> None:
    """Ambient plus Lambert diffuse from every light, depth-tested (``<``), into the colour
    target; also writes each pixel's world position with body id + 1, and face normal."""
    gl = scene.ctx
    prog = program(gl, "surface.vert", "surface_lit.frag")
    scene.use(scene.main_fbo)
    gl.disable(moderngl.BLEND | moderngl.CULL_FACE)
    gl.enable(moderngl.DEPTH_TEST)
    gl.depth_func = "<"
    gl.polygon_offset = (0.0, 0.0)
    scene.main_fbo.depth_mask = True
    scene.main_fbo.clear(*background, 0.0, depth=1.0)
    set_matrix(prog, "world_to_clip", scene.world_to_clip)
    lights = [light.homogeneous for light in scene.lights]
    colors = [light.color for light in scene.lights]
    padding = MAX_LIGHTS - len(scene.lights)
    set_uniform(prog, "light_count", len(scene.lights))
    uniform(prog, "light").write(np.array(lights + [np.zeros(4)] * padding, np.float32).tobytes())
    uniform(prog, "light_color").write(
        np.array(colors + [np.zeros(3)] * padding, np.float32).tobytes()
    )
    set_uniform(prog, "ambient", float(ambient))
    for i, body in enumerate(scene.bodies):
        set_matrix(prog, "body_to_world", body.to_world)
        set_uniform(prog, "albedo", tuple(body.color))
        set_uniform(prog, "body_id", float(i))
        scene.meshes[i].render(prog)


def subtract_light(scene: GpuScene, light: PreparedLight, bodies: Sequence[int]) -> None:
    """Remove ``light``'s diffuse term where its mask is set (``FUNC_REVERSE_SUBTRACT``),
    on the given bodies: each light subtracts only what it added, once per pixel."""
    prog = program(scene.ctx, "surface.vert", "receiver_subtract.frag")
    scene.use(scene.color_fbo)
    scene.color_fbo.depth_mask = False
    scene.surface_tex.use(location=1)
    scene.mask_tex.use(location=2)
    scene.blend(moderngl.FUNC_REVERSE_SUBTRACT)
    set_matrix(prog, "world_to_clip", scene.world_to_clip)
    set_uniform(prog, "mask", 2)
    set_uniform(prog, "light", tuple(light.homogeneous))
    set_uniform(prog, "light_color", tuple(light.color))
    for i in bodies:
        body = scene.bodies[i]
        set_matrix(prog, "body_to_world", body.to_world)
        set_uniform(prog, "albedo", tuple(body.color))
        scene.bind_record(prog, i)
        scene.meshes[i].render(prog)


def finish(scene: GpuScene) -> None:
    """Leave the context's blending as moderngl's default for the next user."""
    scene.ctx.blend_equation = (moderngl.FUNC_ADD, moderngl.FUNC_ADD)
    scene.ctx.disable(moderngl.BLEND)
