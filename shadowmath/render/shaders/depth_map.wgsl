// Williams' shadow z-buffer in WebGPU, pass 1: every caster in its local coordinates to
// the light's WebGPU clip space (depth 0..1). Depth only: no fragment stage; the
// pipeline's depthBias / depthBiasSlopeScale are the polygon offset.
struct Body {
    body_to_clip: mat4x4<f32>,  // C_webgpu @ blocker_to_clip @ inv(blocker_to_world) @ body_to_world
};

@group(0) @binding(0) var<uniform> body: Body;

@vertex
fn vs_main(@location(0) position: vec3<f32>) -> @builtin(position) vec4<f32> {
    return body.body_to_clip * vec4<f32>(position, 1.0);
}
