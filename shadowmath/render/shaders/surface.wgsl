// What the WebGPU camera passes share (`#include "surface.wgsl"`, after the shader's `body`
// uniform with body_to_world, normal_to_world and body_id): a body's vertex placed in the
// world, and the fragment's outputs, the pass's shadow mask beside the per-pixel record of
// the visible surface (world position with body id + 1, unit face normal; read_record).
struct Placed {
    world: vec4<f32>,        // the vertex in the world, homogeneous
    face_normal: vec3<f32>,  // its face's normal in the world (not unit)
};

fn place(position: vec3<f32>, face_normal: vec3<f32>) -> Placed {
    let world = body.body_to_world * vec4<f32>(position, 1.0);
    return Placed(world, (body.normal_to_world * vec4<f32>(face_normal, 0.0)).xyz);
}

struct FragmentOut {
    @location(0) mask: f32,
    @location(1) position: vec4<f32>,
    @location(2) normal: vec4<f32>,
};

// The record of the surface at world point p with face normal n, its mask 0 (lit).
fn record(p: vec3<f32>, n: vec3<f32>) -> FragmentOut {
    return FragmentOut(0.0, vec4<f32>(p, body.body_id + 1.0), vec4<f32>(normalize(n), 0.0));
}
