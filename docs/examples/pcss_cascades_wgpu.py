"""PCSS cascades with WebGPU (wgpu-py): a box on a floor under a sun of angular radius 3
degrees, three cascades fitted to the camera, tiles of one depth atlas.

Run ``python docs/examples/pcss_cascades_wgpu.py`` (the shaders are read from this
folder; the map pass's shader is pcss_wgpu.py's).
"""

from typing import NamedTuple

import numpy as np
import wgpu
from pcss_scene import CASCADES_PROJECTION, CASCADES_VIEW, TRIANGLES, Vector, normals, shader
from pcss_wgpu import DEPTH_TEST, MAP_SHADER, POSITIONS, column_major, lookup_pass

import shadowmath as sm

MAX_CASCADES = 4
ANGLE = float(np.radians(3.0))  # the sun's angular radius

LOOKUP_SHADER = (
    shader("pcss.wgsl")
    + """
struct Cascade {
    world_to_texture: mat4x4<f32>,  // cascades.world_to_texture[i] (api="webgpu")
    tile: vec4<i32>,                // cascades.viewports[i] as (x0, y0, x1, y1)
    k: vec2<f32>,                   // pcss_parameters(cascades) of cascade i
    d_near: f32,
    far: f32,                       // cascades.splits[i + 1]
};
struct Uniforms {
    camera: mat4x4<f32>,  // world to the camera's WebGPU clip space
    sun: vec4<f32>,       // toward the sun
    view_z: vec4<f32>,    // -view[2]: the view depth d = dot(view_z, (p, 1))
    near: f32,            // cascades.splits[0]
    count: i32,
    bias: f32,
    cascades: array<Cascade, 4>,
};
@group(0) @binding(0) var<uniform> u: Uniforms;
@group(0) @binding(1) var shadow_map: texture_depth_2d;  // the atlas: cascade i in tile i

struct Varyings {
    @builtin(position) position: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
};

@vertex
fn vs_main(@location(0) position: vec3<f32>, @location(1) normal: vec3<f32>) -> Varyings {
    return Varyings(u.camera * vec4<f32>(position, 1.0), position, normal);
}

@fragment
fn fs_main(v: Varyings) -> @location(0) vec4<f32> {  // rgb the shaded colour, a the lit fraction
    let diffuse = max(dot(normalize(v.normal), normalize(u.sun.xyz)), 0.0);
    let d = dot(u.view_z, vec4<f32>(v.world, 1.0));
    var lit = 0.0;  // faces turned from the sun are unlit: no lookup
    if (diffuse > 0.0) {
        lit = 1.0;  // beyond the last cascade: no shadow
        var start = u.near;
        for (var i = 0; i < u.count; i++) {
            let c = u.cascades[i];
            if (d >= start && d < c.far) {
                let str = (c.world_to_texture * vec4<f32>(v.world, 1.0)).xyz;  // w = 1: a sun
                lit = pcss(shadow_map, c.tile, str, c.k, c.d_near, u.bias,
                           pcss_angle(v.position.xy));
            }
            start = c.far;
        }
    }
    return vec4<f32>(vec3<f32>(0.15 + 0.85 * diffuse * lit), lit);
}
"""
)


class Picture(NamedTuple):
    color: np.ndarray  # (H, W, 3) the shaded picture, row 0 at the top
    lit: np.ndarray  # (H, W) the lit fraction PCSS found (0 off the lit surfaces)
    cascades: sm.Cascades
    parameters: sm.PcssParameters


def uniform_bytes(
    camera: np.ndarray,
    sun: Vector,
    view: np.ndarray,
    cascades: sm.Cascades,
    pcss: sm.PcssParameters,
    bias: float,
) -> bytes:
    """``struct Uniforms`` of LOOKUP_SHADER: 112 bytes, then 96 per cascade."""
    head = np.zeros(28, "f4")
    head[:16] = np.asarray(camera, "f4").T.ravel()
    head[16:19], head[20:24], head[24], head[26] = sun, -view[2], cascades.splits[0], bias
    head[25:26] = np.array([len(cascades.viewports)], "i4").view("f4")
    body = np.zeros((MAX_CASCADES, 24), "f4")
    for i, (x, y, w, h) in enumerate(np.asarray(cascades.viewports)):
        body[i, :16] = np.asarray(cascades.world_to_texture[i], "f4").T.ravel()
        body[i, 16:20] = np.array([x, y, x + w - 1, y + h - 1], "i4").view("f4")
        body[i, 20:22] = pcss.texels_per_depth[i]
        body[i, 22], body[i, 23] = pcss.near_depth[i], cascades.splits[i + 1]
    return head.tobytes() + body.tobytes()


def render(
    device: wgpu.GPUDevice,
    view: np.ndarray,
    projection: np.ndarray,
    *,
    sun: Vector = (-1.5, 1.0, 1.0),
    angle: float = ANGLE,
    map_size: int = 512,
    size: int = 128,
) -> Picture:
    """The scene through the camera ``projection @ view`` (OpenGL's clip conventions),
    shadowed by PCSS cascades."""
    bounds = np.array([TRIANGLES.min(axis=0), TRIANGLES.max(axis=0)])
    cascades = sm.fit_cascades(
        sun,
        view,
        projection,
        bounds,
        map_size,
        count=3,
        layout="atlas",
        api="webgpu",
        camera_api="opengl",
    )
    cascades = sm.widen_cascades(cascades, angular_radius=angle)
    pcss = sm.pcss_parameters(cascades, angular_radius=angle)  # K (3, 2), near depth (3,)
    bias = float(
        sm.slope_scaled_bias(
            cascades.world_to_texture[0],
            TRIANGLES[0],
            [0, 0, 1],
            map_size=map_size,
            slope_factor=0.0,
        )
    )
    usage = wgpu.BufferUsage.VERTEX
    vertices = device.create_buffer_with_data(data=TRIANGLES.astype("f4"), usage=usage)
    data = np.hstack([TRIANGLES, normals(TRIANGLES)]).astype("f4")
    vertex_data = device.create_buffer_with_data(data=data, usage=usage)
    count = len(TRIANGLES)

    # Pass 1, the maps: cascade i into tile i of one depth texture, the faces turned from
    # the sun (culled by the sign of det(world_to_clip[i]), as pcss_wgpu.py's).
    shadow_map = device.create_texture(
        size=(*cascades.texture_size, 1),
        format="depth32float",
        usage=wgpu.TextureUsage.RENDER_ATTACHMENT | wgpu.TextureUsage.TEXTURE_BINDING,
    )
    module = device.create_shader_module(code=MAP_SHADER)
    encoder = device.create_command_encoder()
    rp = encoder.begin_render_pass(
        color_attachments=[],
        depth_stencil_attachment={
            "view": shadow_map.create_view(),
            "depth_clear_value": 1.0,
            "depth_load_op": "clear",
            "depth_store_op": "store",
        },
    )
    for i, port in enumerate(np.asarray(cascades.viewports)):
        light_clip = np.asarray(cascades.world_to_clip[i])
        cull = "front" if np.linalg.det(light_clip) < 0 else "back"
        pipeline = device.create_render_pipeline(
            layout="auto",
            vertex={
                "module": module,
                "entry_point": "vs_main",
                "buffers": [POSITIONS],
            },
            primitive={"topology": "triangle-list", "front_face": "ccw", "cull_mode": cull},
            depth_stencil=DEPTH_TEST,
        )
        buffer = device.create_buffer_with_data(
            data=column_major(light_clip), usage=wgpu.BufferUsage.UNIFORM
        )
        group = device.create_bind_group(
            layout=pipeline.get_bind_group_layout(0),
            entries=[{"binding": 0, "resource": {"buffer": buffer}}],
        )
        x, y, w, h = (int(v) for v in port)
        rp.set_viewport(x, y, w, h, 0.0, 1.0)
        rp.set_scissor_rect(x, y, w, h)
        rp.set_pipeline(pipeline)
        rp.set_bind_group(0, group)
        rp.set_vertex_buffer(0, vertices)
        rp.draw(count)
    rp.end()
    device.queue.submit([encoder.finish()])

    # Pass 2, the lookup: every surface from the camera, in the cascade of its view depth.
    to_webgpu = np.asarray(sm.api_convention(api="webgpu").gl_clip_to_clip)
    uniforms = uniform_bytes(to_webgpu @ projection @ view, sun, view, cascades, pcss, bias)
    pixels = lookup_pass(
        device,
        LOOKUP_SHADER,
        uniforms=uniforms,
        shadow_map=shadow_map,
        vertices=vertex_data,
        count=count,
        size=size,
    )
    return Picture(pixels[..., :3].copy(), pixels[..., 3].copy(), cascades, pcss)


if __name__ == "__main__":
    picture = render(wgpu.utils.get_default_device(), CASCADES_VIEW, CASCADES_PROJECTION, size=256)
    print(f"splits {picture.cascades.splits}, lit fraction {picture.lit.mean():.3f}")
