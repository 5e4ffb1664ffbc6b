// Many lights, one shadow atlas (sm.allocate_atlas, sm.fit_atlas(..., api="webgpu")): the
// camera pass in WebGPU, the shadow mask of light `which`, the same logic as atlas.frag.
// Every light's shadow map is a tile of the atlas, a cube light's six faces six tiles. For
// a visible point p and light l:
//   * the light reaches p when p's face turns toward it and, for a spot, p lies in its cone;
//   * the tile: light_tiles[l][face], face 0 for a 2D map, sm.cube_face's rule for a cube
//     light (the major axis of p - light; ties to z, then y, as Vulkan's);
//   * world_to_texture[tile] * (p, 1) = (s q, t q, r q, q): (s, t) in the atlas (t = 0 its
//     first row in memory, WebGPU's), r the depth stored there for a caster at p;
//   * Williams' comparison r <= stored over a (2k + 1)^2 box of texels (PCF), every tap
//     clamped into the tile's texels: the tile's border is empty (2D) or holds the
//     neighbouring faces' depths (the cube ring), so no tap reads another light's map.
// With PCSS (the tile's pcss row (K_s, K_t, d_near, 1), render_atlas_wgpu's light_size):
// the blocker search and filter of pcss.wgsl instead of the box, K in atlas texels, every
// tap clamped into the tile, on maps of the faces turned from the light.
// No shadow behind the light (q <= 0), outside the depth range or the tile (lit by this map).
// Bias: the maps are drawn with the pipeline's depthBias / depthBiasSlopeScale (the polygon
// offset of atlas.frag's maps); a caster's point is looked up moved along its face normal
// by normal_offset texels' world size there, times the sine of the angle to the light.
//
// Renderer-specific: the outputs are the mask (1 shadowed, 0 lit or not reached) and a
// record of the visible surface (world position with body id + 1, face normal).
struct Frame {
    world_to_clip: mat4x4<f32>,  // the camera, in WebGPU clip space
    which: i32,                  // the light whose mask is drawn
    pcf_radius: i32,             // k
    normal_offset: f32,          // in texels of the light's map at the point
};

// The tiles' and lights' tables of the pass's description (shadowmath/render/_atlas_pass.py,
// TILE_ROWS and LIGHT_ROWS; atlas.frag reads the same floats as data textures).
struct Tile {
    world_to_texture: mat4x4<f32>,
    rect: vec4<f32>,             // (x, y, n, 0): the tile's texels, x, y from the first row
    pcss: vec4<f32>,             // (K_s, K_t, d_near, 1) with PCSS, 0 without
};

struct Light {
    light: vec4<f32>,            // (x, y, z, 1) a position, (x, y, z, 0) toward a sun
    color: vec4<f32>,            // (r, g, b, 0), the picture's (atlas.frag)
    spot: vec4<f32>,             // (unit axis, cos angle); w = -2: not a spot
    kind: vec4<f32>,             // x = 1: a cube light
    faces: vec4<f32>,            // the tiles of faces 0..3 (-1 none); face 0 of a 2D map
    faces_cube: vec4<f32>,       // the tiles of faces 4, 5
};

struct Body {
    body_to_world: mat4x4<f32>,
    normal_to_world: mat4x4<f32>,  // inverse transpose of body_to_world's 3x3
    body_id: f32,
    casts: f32,                    // 1: this body is drawn in the maps (only casters self-shadow)
};

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var atlas: texture_depth_2d;  // window depths, 1.0 where nothing was drawn
@group(0) @binding(2) var<storage, read> tiles: array<Tile>;
@group(0) @binding(3) var<storage, read> lights: array<Light>;
@group(0) @binding(4) var<uniform> body: Body;

#include "surface.wgsl"
#include "camera_vertex.wgsl"
#include "pcss.wgsl"

var<private> pcss_rect: vec4<i32>;  // the tile pcss_depth reads: (x, y, n, 0) texels

fn pcss_depth(uv: vec2<f32>) -> f32 {
    let texel = vec2<i32>(floor(uv * vec2<f32>(textureDimensions(atlas))));
    return textureLoad(atlas, clamp(texel, pcss_rect.xy, pcss_rect.xy + pcss_rect.zz - 1), 0);
}

fn cube_face(d: vec3<f32>) -> i32 {
    let a = abs(d);
    if (a.z >= a.x && a.z >= a.y) { return select(5, 4, d.z > 0.0); }
    if (a.y >= a.x) { return select(3, 2, d.y > 0.0); }
    return select(1, 0, d.x > 0.0);
}

fn tile_of(light: Light, p: vec3<f32>) -> i32 {
    if (light.kind.x < 0.5) { return i32(light.faces.x); }
    let face = cube_face(p - light.light.xyz);
    if (face < 4) { return i32(light.faces[face]); }
    return i32(light.faces_cube[face - 4]);
}

// How much of light l's map says p (face normal n) is shadowed (0 lit .. 1 shadowed).
fn shadow_of(l: i32, p: vec3<f32>, n_face: vec3<f32>, pixel: vec2<f32>) -> f32 {
    let light = lights[l];
    let t = tile_of(light, p);
    if (t < 0) { return 0.0; }
    let M = tiles[t].world_to_texture;
    let rows = transpose(M);  // rows[u]: row u of world_to_texture
    var c = M * vec4<f32>(p, 1.0);
    if (c.w <= 0.0) { return 0.0; }
    // The normal-offset bias: s = (R0 . p) / (R3 . p) has the world gradient
    // (R0 - s R3).xyz / q, so one texel (1 / A in s) spans 1 / (A |grad s|) of world
    // along it; the larger of the s and t texels.
    let size = vec2<f32>(textureDimensions(atlas));
    let gs = (rows[0].xyz - c.x / c.w * rows[3].xyz) / c.w;
    let gt = (rows[1].xyz - c.y / c.w * rows[3].xyz) / c.w;
    let texel_world = 1.0 / (size.x * max(min(length(gs), length(gt)), 1e-30));
    let n = normalize(n_face);
    let cosine = clamp(dot(n, normalize(light.light.xyz - light.light.w * p)), 0.0, 1.0);
    let offset = body.casts * frame.normal_offset * texel_world * sqrt(1.0 - cosine * cosine);
    c = M * vec4<f32>(p + offset * n, 1.0);
    if (c.w <= 0.0) { return 0.0; }
    let str = c.xyz / c.w;
    let rect = vec4<i32>(tiles[t].rect);
    let texel = vec2<i32>(floor(str.xy * size));
    if (str.z < 0.0 || str.z > 1.0 || any(texel < rect.xy) || any(texel >= rect.xy + rect.zz)) {
        return 0.0;
    }
    let pcss = tiles[t].pcss;
    if (pcss.w > 0.5) {
        pcss_rect = rect;
        return 1.0 - pcss_lit(str, size, pcss.xy, pcss.z, 0.0, pixel_angle(pixel));
    }
    let k = frame.pcf_radius;
    var lit = 0.0;
    for (var j = -k; j <= k; j++) {
        for (var i = -k; i <= k; i++) {
            let tap = clamp(texel + vec2<i32>(i, j), rect.xy, rect.xy + rect.zz - 1);
            lit += select(0.0, 1.0, str.z <= textureLoad(atlas, tap, 0));
        }
    }
    return 1.0 - lit / f32((2 * k + 1) * (2 * k + 1));
}

// Whether light l reaches p on a face of normal n (front face, inside a spot's cone).
fn reaches(l: i32, p: vec3<f32>, n: vec3<f32>) -> bool {
    let light = lights[l];
    let toward = normalize(light.light.xyz - light.light.w * p);
    if (dot(n, toward) <= 0.0) { return false; }
    return light.spot.w < -1.5 || dot(-toward, light.spot.xyz) >= light.spot.w;
}

@fragment
fn fs_main(in: VertexOut) -> FragmentOut {
    var out = record(in.world, in.face_normal);
    if (reaches(frame.which, in.world, in.face_normal)) {
        out.mask = shadow_of(frame.which, in.world, in.face_normal, in.clip.xy);
    }
    return out;
}
