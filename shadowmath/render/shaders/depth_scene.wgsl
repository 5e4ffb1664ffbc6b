// Williams' shadow z-buffer in WebGPU, pass 2, from the camera: each visible point's
// light depth r compared with the depth map over a (2k + 1)^2 box of texels (PCF,
// k = pcf_radius), written as the shadow mask with the per-pixel record (world position
// with body id + 1, face normal). Texture coordinates follow WebGPU: t = 0 is the map's
// first (top) row. As depth_mask.frag: lit behind the light (q <= 0), outside the map or
// its depth range, and on faces turned from the light.
struct Body {
    world_to_clip: mat4x4<f32>,    // the camera, in WebGPU clip space
    body_to_world: mat4x4<f32>,
    normal_to_world: mat4x4<f32>,  // inverse transpose of body_to_world's 3x3
    body_to_texture: mat4x4<f32>,  // WebGPU (s q, t q, r q, q) of the light's map
    light_position: vec3<f32>,
    body_id: f32,
    pcf_radius: i32,
};

@group(0) @binding(0) var<uniform> body: Body;
@group(0) @binding(1) var depth_map: texture_depth_2d;
@group(0) @binding(2) var depth_compare: sampler_comparison;  // less-equal: 1 where lit

#include "surface.wgsl"
#include "light_map_vertex.wgsl"

@fragment
fn fs_main(in: VertexOut) -> FragmentOut {
    var out = record(in.world, in.face_normal);
    let q = in.strq.w;
    if (q <= 0.0 || dot(in.face_normal, body.light_position - in.world) <= 0.0) {
        return out;
    }
    let str = in.strq.xyz / q;
    if (any(str < vec3<f32>(0.0)) || any(str > vec3<f32>(1.0))) {
        return out;
    }
    let texel = 1.0 / vec2<f32>(textureDimensions(depth_map));
    let k = body.pcf_radius;
    var lit = 0.0;
    for (var j = -k; j <= k; j++) {
        for (var i = -k; i <= k; i++) {
            let st = str.xy + vec2<f32>(f32(i), f32(j)) * texel;
            lit += textureSampleCompareLevel(depth_map, depth_compare, st, str.z);
        }
    }
    out.mask = 1.0 - lit / f32((2 * k + 1) * (2 * k + 1));
    return out;
}
