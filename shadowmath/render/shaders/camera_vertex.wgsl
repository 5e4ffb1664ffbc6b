// The vertex stage of a WebGPU camera pass whose `frame` uniform begins with the camera's
// world_to_clip (`#include "camera_vertex.wgsl"` after "surface.wgsl"): the vertex placed
// in the world and in the camera's clip space.
struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) @interpolate(flat) face_normal: vec3<f32>,
};

@vertex
fn vs_main(@location(0) position: vec3<f32>, @location(1) face_normal: vec3<f32>) -> VertexOut {
    let v = place(position, face_normal);
    return VertexOut(frame.world_to_clip * v.world, v.world.xyz / v.world.w, v.face_normal);
}
