// Cascaded shadow maps of a sun, the camera pass, in WebGPU: the shadow at each visible
// point, the same selection, blend, bias and PCF as cascades.frag.
//
// The uniforms are sm.fit_cascades(..., api="webgpu")'s outputs, as they are (texture
// t = 0 and viewport y = 0 are the first row in memory):
//   cascades[i].world_to_texture  world point to (s, t, r, 1): s, t in the texture (the
//                                 whole atlas with layout="atlas"), r the stored depth
//   cascades[i].viewport          viewports[i], the tile (x, y, w, h) in texels
//                                 (layout="layers": (0, 0, W, H), the whole layer i)
//   cascades[i].near, .far        splits[i], splits[i + 1]: cascade i serves [near, far)
//   cascades[i].band_end          band_end[i] > far: in [far, band_end] both i and i + 1
//                                 are sampled, i's weight falling linearly from 1 to 0
// and view_depth, the camera's view depth as a row: d = dot(view_depth, (p, 1)), that is
// -view[2] for an OpenGL-style view matrix looking down -z.
//
// Bias (docs/depth-maps.md): both are shadowmath's formulas, per fragment, for a lookup
// that reaches c = k + 1/2 texels per axis (a box PCF of radius k):
//   the normal offset, sm.normal_offset: the point is looked up moved along its unit
//   normal by o = scale c (|gr . (gt x n)| / W + |gr . (n x gs)| / H) / |gr . (gs x gt)|;
//   the slope-scaled bias, sm.slope_scaled_bias: the lifted point's depth r minus
//   b = constant + slope_factor max(|gr . (gt x n)| / W, |gr . (n x gs)| / H) / |(gs x gt) . n|
//   is compared with the map (gs, gt, gr: the gradients of s, t, r at the point; W x H
//   the texture's size in texels). The maps are drawn with no depth bias.
// PCF: the (2k + 1)^2 texels around the point's texel, each clamped to the cascade's tile,
// so no tap reads a neighbour's tile in an atlas. Outside the tile, or beyond the map's
// depth range, or beyond the last split: lit.
// PCSS (pcss = 1, the maps holding the faces turned from the sun): in cascade i the
// blocker search and filter of pcss.wgsl with cascades[i].k and cascades[i].d_near
// (sm.pcss_parameters of the cascades: one world penumbra in every cascade), every tap
// clamped to the cascade's tile, the constant bias only (as cascades.frag).
//
// Renderer-specific: the outputs are the shadow (1 shadowed, 0 lit) and a record of the
// visible surface (world position with body id + 1, face normal) for the tests.
#include "constants.wgsl"

struct Cascade {
    world_to_texture: mat4x4<f32>,
    viewport: vec4<i32>,
    near: f32,
    far: f32,
    band_end: f32,
    k: vec2<f32>,                 // PCSS: texels per unit of stored depth
    d_near: f32,                  // PCSS: the near plane's stored depth
};

struct Frame {
    world_to_clip: mat4x4<f32>,   // the camera, in WebGPU clip space
    view_depth: vec4<f32>,
    light: vec4<f32>,             // (x, y, z, 0): toward the sun
    count: i32,                   // n, the number of cascades
    pcf_radius: i32,              // k
    atlas: i32,                   // 1: every cascade is a tile of layer 0
    normal_offset: f32,           // scale of sm.normal_offset (1: the derived minimum)
    slope_factor: f32,            // of sm.slope_scaled_bias (2c: the derived minimum)
    constant_bias: f32,           // its constant term, in depth units (constant * r_min)
    pcss: i32,                    // 1: percentage-closer soft shadows
    cascades: array<Cascade, MAX_CASCADES>,
};

struct Body {
    body_to_world: mat4x4<f32>,
    normal_to_world: mat4x4<f32>,  // inverse transpose of body_to_world's 3x3
    body_id: f32,
};

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var maps: texture_depth_2d_array;  // layer i, or 0 (the atlas)
@group(0) @binding(2) var<uniform> body: Body;

#include "surface.wgsl"
#include "camera_vertex.wgsl"
#include "pcss.wgsl"

// The tile and layer pcss_depth reads (set before each pcss_lit).
var<private> pcss_tile: vec4<i32>;
var<private> pcss_layer: i32;

fn pcss_depth(uv: vec2<f32>) -> f32 {
    let texel = vec2<i32>(floor(uv * vec2<f32>(textureDimensions(maps))));
    let tap = clamp(texel, pcss_tile.xy, pcss_tile.xy + pcss_tile.zw - 1);
    return textureLoad(maps, tap, pcss_layer, 0);
}

// PCSS in cascade i at p: 0 lit .. 1 shadowed (outside the tile or its depth range: lit).
fn pcss_shadow_in(i: i32, p: vec3<f32>, phi: f32) -> f32 {
    let cascade = frame.cascades[i];
    let size = vec2<f32>(textureDimensions(maps));
    let h = cascade.world_to_texture * vec4<f32>(p, 1.0);
    let str = h.xyz / h.w;
    pcss_tile = cascade.viewport;
    pcss_layer = select(i, 0, frame.atlas == 1);
    let texel = vec2<i32>(floor(str.xy * size));
    if (str.z > 1.0 || any(texel < pcss_tile.xy) || any(texel >= pcss_tile.xy + pcss_tile.zw)) {
        return 0.0;
    }
    return 1.0 - pcss_lit(str, size, cascade.k, cascade.d_near, frame.constant_bias, phi);
}

struct Pick {
    cascade: i32,    // the cascade serving the depth, -1 none
    previous: f32,   // the weight of cascade - 1 in its band
};

fn pick(d: f32) -> Pick {
    for (var i = 0; i < frame.count; i++) {
        let c = frame.cascades[i];
        let last = i == frame.count - 1;
        if (d >= c.near && (d < c.far || (last && d <= c.far))) {
            var previous = 0.0;
            if (i > 0) {
                let end = frame.cascades[i - 1].band_end;
                if (d <= end && end > c.near) {
                    previous = (end - d) / (end - c.near);
                }
            }
            return Pick(i, previous);
        }
    }
    return Pick(-1, 0.0);
}

// The gradients of s, t, r at p, columns 0, 1, 2: grad u = (m_u - u m_q) / q, with m_u the
// first three entries of row u of M (perspective maps too, although cascades are affine).
fn texture_gradients(M: mat4x4<f32>, p: vec3<f32>) -> mat3x3<f32> {
    let h = M * vec4<f32>(p, 1.0);
    let str = h.xyz / h.w;
    let rows = transpose(mat3x3<f32>(M[0].xyz, M[1].xyz, M[2].xyz));  // rows[u]: row u
    let mq = vec3<f32>(M[0][3], M[1][3], M[2][3]);
    return mat3x3<f32>(rows[0] - str.x * mq, rows[1] - str.y * mq, rows[2] - str.z * mq)
        * (1.0 / h.w);
}

// The shadow of point p (unit normal n, facing the sun) in cascade i: 0 lit .. 1 shadowed.
fn shadow_in(i: i32, p: vec3<f32>, n: vec3<f32>, phi: f32) -> f32 {
    if (frame.pcss == 1) {
        return pcss_shadow_in(i, p, phi);
    }
    let cascade = frame.cascades[i];
    let size = vec2<f32>(textureDimensions(maps));
    let g = texture_gradients(cascade.world_to_texture, p);
    let D = cross(g[0], g[1]);
    let rise_s = abs(dot(g[2], cross(g[1], n))) / size.x;  // depth per texel along s
    let rise_t = abs(dot(g[2], cross(n, g[0]))) / size.y;
    let c = f32(frame.pcf_radius) + 0.5;
    let offset = frame.normal_offset * c * (rise_s + rise_t) / abs(dot(g[2], D));
    let bias = frame.constant_bias + frame.slope_factor * max(rise_s, rise_t) / abs(dot(D, n));

    let h = cascade.world_to_texture * vec4<f32>(p + offset * n, 1.0);
    let str = h.xyz / h.w;
    let tile = cascade.viewport;
    let texel = vec2<i32>(floor(str.xy * size));
    if (str.z > 1.0 || any(texel < tile.xy) || any(texel >= tile.xy + tile.zw)) {
        return 0.0;
    }
    let layer = select(i, 0, frame.atlas == 1);
    let k = frame.pcf_radius;
    var lit = 0.0;
    for (var y = -k; y <= k; y++) {
        for (var x = -k; x <= k; x++) {
            let tap = clamp(texel + vec2<i32>(x, y), tile.xy, tile.xy + tile.zw - 1);
            lit += select(0.0, 1.0, str.z - bias <= textureLoad(maps, tap, layer, 0));
        }
    }
    return 1.0 - lit / f32((2 * k + 1) * (2 * k + 1));
}

@fragment
fn fs_main(in: VertexOut) -> FragmentOut {
    var out = record(in.world, in.face_normal);
    let n = normalize(in.face_normal);
    let picked = pick(dot(frame.view_depth, vec4<f32>(in.world, 1.0)));
    let i = picked.cascade;
    if (i < 0 || dot(n, frame.light.xyz) <= 0.0) {  // turned from the sun: unlit anyway
        return out;
    }
    let phi = pixel_angle(in.clip.xy);
    out.mask = shadow_in(i, in.world, n, phi);
    if (picked.previous > 0.0) {
        out.mask = mix(out.mask, shadow_in(i - 1, in.world, n, phi), picked.previous);
    }
    return out;
}
