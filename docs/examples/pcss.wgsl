// Percentage-closer soft shadows (Fernando 2005), with shadowmath's quantities: pcss.glsl
// in WGSL, tap for tap.
//
//   shadow_map  the light's depth32float texture of the faces turned from the light, bound
//               as texture_depth_2d and read by textureLoad (no sampler; never a
//               sampler_comparison, which returns the comparison's 0 or 1, not the depth)
//   tile        the texels (x0, y0, x1, y1) the taps may read, inclusive
//   str         (s, t, r) of the receiver point: (world_to_texture @ p).xyz / .w, the fit's
//               world_to_texture for api="webgpu" (t = 0 the texture's first row)
//   k, d_near   sm.pcss_parameters(fit).texels_per_depth and .near_depth of this map
//   bias        in stored-depth units
//   phi         the disks' rotation at this pixel: pcss_angle(position.xy)
// returns the lit fraction in [0, 1].
const PCSS_SEARCH_TAPS: i32 = 32;
const PCSS_FILTER_TAPS: i32 = 64;

// Jimenez's interleaved gradient noise: a per-pixel angle in [0, 2 pi).
fn pcss_angle(pixel: vec2<f32>) -> f32 {
    return 6.28318530718 * fract(52.9829189 * fract(dot(pixel, vec2<f32>(0.06711056, 0.00583715))));
}

// Tap i of n of a Vogel disk (a golden-angle spiral, equal areas) of radius 1, turned by phi.
fn pcss_vogel(i: i32, n: i32, phi: f32) -> vec2<f32> {
    let a = f32(i) * 2.39996322972865332 + phi;
    return sqrt((f32(i) + 0.5) / f32(n)) * vec2<f32>(cos(a), sin(a));
}

// The stored depth of the texel at uv, clamped to the tile.
fn pcss_depth(shadow_map: texture_depth_2d, tile: vec4<i32>, uv: vec2<f32>) -> f32 {
    let size = vec2<f32>(textureDimensions(shadow_map));
    let texel = clamp(vec2<i32>(floor(uv * size)), tile.xy, tile.zw);
    return textureLoad(shadow_map, texel, 0);
}

fn pcss(shadow_map: texture_depth_2d, tile: vec4<i32>, str: vec3<f32>, k: vec2<f32>,
        d_near: f32, bias: f32, phi: f32) -> f32 {
    let size = vec2<f32>(textureDimensions(shadow_map));
    let sgn = 1.0 - 2.0 * d_near;
    let receiver = sgn * str.z - bias;  // a texel holds a blocker if sgn * d < receiver
    let search = k * abs(str.z - d_near) / size;
    var sum = 0.0;
    var count = 0;
    for (var i = 0; i < PCSS_SEARCH_TAPS; i++) {
        let d = pcss_depth(shadow_map, tile, str.xy + pcss_vogel(i, PCSS_SEARCH_TAPS, phi) * search);
        if (sgn * d < receiver) {
            sum += d;
            count += 1;
        }
    }
    if (count == 0) {
        return 1.0;  // nothing nearer the light in the search region
    }
    let radius = k * max(sgn * (str.z - sum / f32(count)), 0.0) / size;
    var lit = 0.0;
    for (var i = 0; i < PCSS_FILTER_TAPS; i++) {
        let d = pcss_depth(shadow_map, tile, str.xy + pcss_vogel(i, PCSS_FILTER_TAPS, phi) * radius);
        lit += select(1.0, 0.0, sgn * d < receiver);
    }
    return lit / f32(PCSS_FILTER_TAPS);
}
