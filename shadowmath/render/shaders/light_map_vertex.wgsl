// The vertex stage of a WebGPU camera pass that looks one light's map up
// (`#include "light_map_vertex.wgsl"` after "surface.wgsl", the shader's `body` uniform
// with world_to_clip and body_to_texture): the vertex placed in the world and in the
// camera's clip space, with the map's homogeneous (s q, t q, r q, q).
struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) @interpolate(flat) face_normal: vec3<f32>,
    @location(2) strq: vec4<f32>,
};

@vertex
fn vs_main(@location(0) position: vec3<f32>, @location(1) face_normal: vec3<f32>) -> VertexOut {
    let v = place(position, face_normal);
    let strq = body.body_to_texture * vec4<f32>(position, 1.0);
    return VertexOut(body.world_to_clip * v.world, v.world.xyz / v.world.w, v.face_normal, strq);
}
