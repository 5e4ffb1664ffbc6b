// Percentage-closer soft shadows (Fernando 2005) in WGSL: pcss.glsl's blocker search and
// filter, tap for tap (the same Vogel disks, the same per-pixel angle), on a map of
// window depths with the quantities of shadowmath.pcss_parameters: k (texels per unit of
// window depth, per axis) and d_near (the near plane's depth):
//   blocker search region   k |d_R - d_near|           texels (radius)
//   penumbra (PCF radius)   k max(d_R - d_B, 0)        texels (radius)
// The including shader defines pcss_depth(uv): the stored depth at texture coordinates
// uv (1 where nothing was drawn).
// GOLDEN_ANGLE, PCSS_SEARCH_TAPS, PCSS_FILTER_TAPS and the noise's constants: from Python
// (shadowmath/render/_shader_constants.py), as pcss.glsl's.
#include "constants.wgsl"

// Jimenez's interleaved gradient noise: a per-pixel angle in [0, 2 pi).
fn pixel_angle(pixel: vec2<f32>) -> f32 {
    return TWO_PI * fract(NOISE_SCALE * fract(dot(pixel, vec2<f32>(NOISE_X, NOISE_Y))));
}

// Tap i of count on the unit disk: radius sqrt((i + 1/2) / count), angle i golden angles.
fn vogel_tap(i: i32, count: i32, phi: f32) -> vec2<f32> {
    let a = f32(i) * GOLDEN_ANGLE + phi;
    return sqrt((f32(i) + 0.5) / f32(count)) * vec2<f32>(cos(a), sin(a));
}

// The lit fraction at str = (s, t, d_R) of a map of size texels: 1 where the search
// finds no blocker; a tap is lit where d_R - bias <= the stored depth.
fn pcss_lit(str: vec3<f32>, size: vec2<f32>, k: vec2<f32>, d_near: f32, bias: f32, phi: f32) -> f32 {
    let receiver = str.z - bias;
    let search = k * abs(str.z - d_near) / size;
    var blocker_sum = 0.0;
    var blockers = 0;
    for (var i = 0; i < PCSS_SEARCH_TAPS; i++) {
        let d = pcss_depth(str.xy + vogel_tap(i, PCSS_SEARCH_TAPS, phi) * search);
        if (d < receiver) {
            blocker_sum += d;
            blockers += 1;
        }
    }
    if (blockers == 0) {
        return 1.0;
    }
    let radius = k * max(str.z - blocker_sum / f32(blockers), 0.0) / size;
    var lit = 0.0;
    for (var i = 0; i < PCSS_FILTER_TAPS; i++) {
        lit += step(receiver, pcss_depth(str.xy + vogel_tap(i, PCSS_FILTER_TAPS, phi) * radius));
    }
    return lit / f32(PCSS_FILTER_TAPS);
}
