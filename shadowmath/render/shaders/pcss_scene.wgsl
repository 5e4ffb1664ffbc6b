// Percentage-closer soft shadows in WebGPU, pass 2, from the camera: pcss.wgsl's blocker
// search and filter around each visible point's (s, t, d_R) in the light's map, written
// as the shadow mask with the per-pixel record (as depth_scene.wgsl). The map holds the
// faces turned from the light (as pcss_mask.frag's); texture coordinates follow WebGPU
// (t = 0 the map's first row); taps read the nearest texel, clamped to the map. Lit
// behind the light (q <= 0), outside the map or its depth range, and on faces turned
// from the light.
struct Body {
    world_to_clip: mat4x4<f32>,    // the camera, in WebGPU clip space
    body_to_world: mat4x4<f32>,
    normal_to_world: mat4x4<f32>,  // inverse transpose of body_to_world's 3x3
    body_to_texture: mat4x4<f32>,  // WebGPU (s q, t q, r q, q) of the light's map
    light: vec4<f32>,              // (x, y, z, 1) a point light, (x, y, z, 0) a directional one
    body_id: f32,
    k: vec2<f32>,                  // texels per unit of window depth, per axis
    d_near: f32,                   // the window depth of the near plane
};

@group(0) @binding(0) var<uniform> body: Body;
@group(0) @binding(1) var depth_map: texture_depth_2d;

#include "surface.wgsl"
#include "light_map_vertex.wgsl"
#include "pcss.wgsl"

fn pcss_depth(uv: vec2<f32>) -> f32 {
    let size = vec2<i32>(textureDimensions(depth_map));
    let texel = clamp(vec2<i32>(floor(uv * vec2<f32>(size))), vec2<i32>(0), size - 1);
    return textureLoad(depth_map, texel, 0);
}

@fragment
fn fs_main(in: VertexOut) -> FragmentOut {
    var out = record(in.world, in.face_normal);
    let q = in.strq.w;
    if (q <= 0.0 || dot(in.face_normal, body.light.xyz - body.light.w * in.world) <= 0.0) {
        return out;
    }
    let str = in.strq.xyz / q;
    if (any(str < vec3<f32>(0.0)) || any(str > vec3<f32>(1.0))) {
        return out;
    }
    let size = vec2<f32>(textureDimensions(depth_map));
    out.mask = 1.0 - pcss_lit(str, size, body.k, body.d_near, 0.0, pixel_angle(in.clip.xy));
    return out;
}
