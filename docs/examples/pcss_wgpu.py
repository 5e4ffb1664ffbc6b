"""PCSS with WebGPU (wgpu-py): a box on a floor under a point light of radius 0.25.

Run ``python docs/examples/pcss_wgpu.py`` (the shaders are read from this folder).
"""

from typing import NamedTuple

import numpy as np
import wgpu
from pcss_scene import CASTER, TRIANGLES, Vector, look_at, normals, perspective, shader

import shadowmath as sm

MAP_SHADER = """
@group(0) @binding(0) var<uniform> light_clip: mat4x4<f32>;  // world to the light's clip
@vertex
fn vs_main(@location(0) position: vec3<f32>) -> @builtin(position) vec4<f32> {
    return light_clip * vec4<f32>(position, 1.0);
}
"""

LOOKUP_SHADER = (
    shader("pcss.wgsl")
    + """
struct Uniforms {
    camera: mat4x4<f32>,            // world to the camera's WebGPU clip space
    world_to_texture: mat4x4<f32>,  // fit.world_to_texture (api="webgpu")
    light: vec4<f32>,               // the light's position
    k: vec2<f32>,
    d_near: f32,
    bias: f32,
};
@group(0) @binding(0) var<uniform> u: Uniforms;
@group(0) @binding(1) var shadow_map: texture_depth_2d;

struct Varyings {
    @builtin(position) position: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) strq: vec4<f32>,
};

@vertex
fn vs_main(@location(0) position: vec3<f32>, @location(1) normal: vec3<f32>) -> Varyings {
    let p = vec4<f32>(position, 1.0);
    return Varyings(u.camera * p, position, normal, u.world_to_texture * p);
}

@fragment
fn fs_main(v: Varyings) -> @location(0) vec4<f32> {  // rgb the shaded colour, a the lit fraction
    let diffuse = max(dot(normalize(v.normal), normalize(u.light.xyz - v.world)), 0.0);
    var lit = 0.0;  // faces turned from the light are unlit: no lookup
    if (diffuse > 0.0) {
        let size = vec2<i32>(textureDimensions(shadow_map));
        let str = v.strq.xyz / v.strq.w;
        lit = pcss(shadow_map, vec4<i32>(0, 0, size - 1), str, u.k, u.d_near, u.bias,
                   pcss_angle(v.position.xy));
    }
    return vec4<f32>(vec3<f32>(0.15 + 0.85 * diffuse * lit), lit);
}
"""
)


#: The vertex buffers' layouts (float32 positions; positions and normals), the depth test.
POSITIONS = {
    "array_stride": 12,
    "attributes": [{"format": "float32x3", "offset": 0, "shader_location": 0}],
}
POSITIONS_NORMALS = {
    "array_stride": 24,
    "attributes": [
        {"format": "float32x3", "offset": 0, "shader_location": 0},
        {"format": "float32x3", "offset": 12, "shader_location": 1},
    ],
}
DEPTH_TEST = {"format": "depth32float", "depth_write_enabled": True, "depth_compare": "less"}


class Picture(NamedTuple):
    color: np.ndarray  # (H, W, 3) the shaded picture, row 0 at the top
    lit: np.ndarray  # (H, W) the lit fraction PCSS found (0 off the lit surfaces)
    fit: sm.ShadowSetup
    parameters: sm.PcssParameters


def column_major(m: np.ndarray) -> bytes:
    return np.asarray(m, "f4").T.tobytes()


def lookup_pass(
    device: wgpu.GPUDevice,
    code: str,
    *,
    uniforms: bytes,
    shadow_map: wgpu.GPUTexture,
    vertices: wgpu.GPUBuffer,
    count: int,
    size: int,
) -> np.ndarray:
    """The triangles (positions and normals) through ``code``'s vs_main and fs_main, its
    bindings the ``uniforms`` and the map, into a ``(size, size, 4)`` float picture with a
    depth test; row 0 at the top."""
    target = device.create_texture(
        size=(size, size, 1),
        format="rgba32float",
        usage=wgpu.TextureUsage.RENDER_ATTACHMENT | wgpu.TextureUsage.COPY_SRC,
    )
    depth = device.create_texture(
        size=(size, size, 1), format="depth32float", usage=wgpu.TextureUsage.RENDER_ATTACHMENT
    )
    module = device.create_shader_module(code=code)
    pipeline = device.create_render_pipeline(
        layout="auto",
        vertex={
            "module": module,
            "entry_point": "vs_main",
            "buffers": [POSITIONS_NORMALS],
        },
        primitive={"topology": "triangle-list"},
        depth_stencil=DEPTH_TEST,
        fragment={
            "module": module,
            "entry_point": "fs_main",
            "targets": [{"format": "rgba32float"}],
        },
    )
    group = device.create_bind_group(
        layout=pipeline.get_bind_group_layout(0),
        entries=[
            {
                "binding": 0,
                "resource": {
                    "buffer": device.create_buffer_with_data(
                        data=uniforms, usage=wgpu.BufferUsage.UNIFORM
                    )
                },
            },
            {"binding": 1, "resource": shadow_map.create_view()},
        ],
    )
    encoder = device.create_command_encoder()
    rp = encoder.begin_render_pass(
        color_attachments=[
            {
                "view": target.create_view(),
                "clear_value": (0, 0, 0, 0),
                "load_op": "clear",
                "store_op": "store",
            }
        ],
        depth_stencil_attachment={
            "view": depth.create_view(),
            "depth_clear_value": 1.0,
            "depth_load_op": "clear",
            "depth_store_op": "store",
        },
    )
    rp.set_pipeline(pipeline)
    rp.set_bind_group(0, group)
    rp.set_vertex_buffer(0, vertices)
    rp.draw(count)
    rp.end()
    device.queue.submit([encoder.finish()])
    pixels = device.queue.read_texture(
        {"texture": target, "origin": (0, 0, 0)},
        {"offset": 0, "bytes_per_row": 16 * size},
        (size, size, 1),
    )
    return np.frombuffer(pixels, "f4").reshape(size, size, 4)


def render(
    device: wgpu.GPUDevice,
    camera: np.ndarray,
    *,
    light: Vector = (-1.6, 1.4, 4.5),
    radius: float = 0.25,
    map_size: int = 512,
    size: int = 128,
    reversed_z: bool = False,
) -> Picture:
    """The scene seen through ``camera`` (world to OpenGL clip), shadowed by PCSS
    (``reversed_z``: the map's depth 1 at the near plane)."""
    receivers = sm.Triangles(TRIANGLES.reshape(-1, 3, 3))
    options = {"receivers": receivers, "api": "webgpu", "reversed_z": reversed_z}
    fit = sm.fit_shadow(light, CASTER, map_size, **options)
    border = sm.pcss_border_texels(sm.pcss_parameters(fit, light_radius=radius))
    fit = sm.fit_shadow(light, CASTER, map_size, border_texels=border, **options)
    pcss = sm.pcss_parameters(fit, light_radius=radius)
    world_to_texture = np.asarray(fit.world_to_texture)
    light_clip = np.asarray(fit.blocker_to_clip) @ np.linalg.inv(fit.blocker_to_world)
    # The bias: the map holds the faces turned from the light, so no lit point is
    # compared with its own surface: only the depths' rounding (no slope term).
    bias = float(
        sm.slope_scaled_bias(
            world_to_texture, TRIANGLES[0], [0, 0, 1], map_size=map_size, slope_factor=0.0
        )
    )
    usage = wgpu.BufferUsage.VERTEX
    vertices = device.create_buffer_with_data(data=TRIANGLES.astype("f4"), usage=usage)
    data = np.hstack([TRIANGLES, normals(TRIANGLES)]).astype("f4")
    vertex_data = device.create_buffer_with_data(data=data, usage=usage)
    count = len(TRIANGLES)

    # Pass 1, the map: depth only, the faces turned from the light. Cull the faces that
    # face the light: the front faces (counter-clockwise) where det(light_clip) < 0 (as
    # every projection that looks down -z does), the back faces where det > 0. Reversed Z
    # negates the depth row, and with it the determinant but not the winding: there the
    # other way round.
    shadow_map = device.create_texture(
        size=(map_size, map_size, 1),
        format="depth32float",
        usage=wgpu.TextureUsage.RENDER_ATTACHMENT | wgpu.TextureUsage.TEXTURE_BINDING,
    )
    sgn = -1.0 if reversed_z else 1.0
    cull = "front" if sgn * np.linalg.det(light_clip) < 0 else "back"
    map_pipeline = device.create_render_pipeline(
        layout="auto",
        vertex={
            "module": device.create_shader_module(code=MAP_SHADER),
            "entry_point": "vs_main",
            "buffers": [POSITIONS],
        },
        primitive={"topology": "triangle-list", "front_face": "ccw", "cull_mode": cull},
        depth_stencil={**DEPTH_TEST, "depth_compare": "greater" if reversed_z else "less"},
    )
    map_uniforms = device.create_buffer_with_data(
        data=column_major(light_clip), usage=wgpu.BufferUsage.UNIFORM
    )
    map_group = device.create_bind_group(
        layout=map_pipeline.get_bind_group_layout(0),
        entries=[{"binding": 0, "resource": {"buffer": map_uniforms}}],
    )
    encoder = device.create_command_encoder()
    rp = encoder.begin_render_pass(
        color_attachments=[],
        depth_stencil_attachment={
            "view": shadow_map.create_view(),
            "depth_clear_value": 0.0 if reversed_z else 1.0,
            "depth_load_op": "clear",
            "depth_store_op": "store",
        },
    )
    rp.set_pipeline(map_pipeline)
    rp.set_bind_group(0, map_group)
    rp.set_vertex_buffer(0, vertices)
    rp.draw(count)
    rp.end()
    device.queue.submit([encoder.finish()])

    # Pass 2, the lookup: every surface from the camera; the map is read by textureLoad.
    to_webgpu = np.asarray(sm.api_convention(api="webgpu").gl_clip_to_clip)
    uniforms = column_major(to_webgpu @ camera) + column_major(world_to_texture)
    tail = [*light, 1.0, *pcss.texels_per_depth, float(pcss.near_depth), bias]
    uniforms += np.asarray(tail, "f4").tobytes()
    pixels = lookup_pass(
        device,
        LOOKUP_SHADER,
        uniforms=uniforms,
        shadow_map=shadow_map,
        vertices=vertex_data,
        count=count,
        size=size,
    )
    return Picture(pixels[..., :3].copy(), pixels[..., 3].copy(), fit, pcss)


if __name__ == "__main__":
    gpu_device = wgpu.utils.get_default_device()
    view = look_at((3.0, -5.0, 4.0), (-0.3, 0.0, 0.3))
    picture = render(gpu_device, perspective(45.0, 1.0, 0.5, 30.0) @ view, size=256)
    print(f"K = {picture.parameters.texels_per_depth}, lit fraction {picture.lit.mean():.3f}")
