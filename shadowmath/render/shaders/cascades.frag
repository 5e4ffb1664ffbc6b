#version 330
// Cascaded shadow maps of a sun, the camera pass: the shadow at each visible point.
//
// The uniforms are sm.fit_cascades' outputs, as they are (OpenGL conventions):
//   splits[0..n]          view depths; cascade i serves [splits[i], splits[i + 1])
//   band_end[0..n-1]      cascade i was fitted out to band_end[i] > splits[i + 1]: in
//                         [splits[i + 1], band_end[i]] both i and i + 1 are sampled and
//                         mixed, i's weight falling linearly from 1 to 0
//   world_to_texture[i]   world point to (s, t, r, 1): s, t in the texture (the whole
//                         atlas with layout="atlas"), r the depth stored in the map
//   viewports[i]          cascade i's tile (x, y, w, h) in texels (layout="layers":
//                         (0, 0, W, H), the whole layer i)
// and view_depth, the camera's view depth as a row: d = dot(view_depth, (p, 1)), that is
// -view[2] for an OpenGL camera looking down -z.
//
// Bias (docs/depth-maps.md): both are shadowmath's formulas, per fragment, for a lookup
// that reaches c = k + 1/2 texels per axis (a box PCF of radius k):
//   the normal offset, sm.normal_offset: the point is looked up moved along its unit
//   normal by o = scale c (|gr . (gt x n)| / W + |gr . (n x gs)| / H) / |gr . (gs x gt)|;
//   the slope-scaled bias, sm.slope_scaled_bias: the lifted point's depth r minus
//   b = constant + slope_factor max(|gr . (gt x n)| / W, |gr . (n x gs)| / H) / |(gs x gt) . n|
//   is compared with the map (gs, gt, gr: the gradients of s, t, r at the point; W x H
//   the texture's size in texels). The maps are drawn with no polygon offset.
// PCF: the (2k + 1)^2 texels around the point's texel, each clamped to the cascade's tile,
// so no tap reads a neighbour's tile in an atlas. Outside the tile, or beyond the map's
// depth range, or beyond the last split: lit.
//
// PCSS (pcss = 1, the maps holding the faces turned from the sun): in cascade i the
// blocker search and filter of pcss.glsl with pcss_k[i] and pcss_near[i]
// (sm.pcss_parameters of the cascades: one world penumbra in every cascade), every tap
// clamped to the cascade's tile, the constant bias only.
//
// Renderer-specific: this pass draws every body again over the lit pass's record
// (`surface`: world position, w = body id + 1) and keeps the fragment that is visible;
// mode 0 writes the shadow (1 shadowed, 0 lit), mode 1 the cascade's debug colour.
#include "constants.glsl"
uniform sampler2DArray maps;  // R32F depths, 1.0 where nothing was drawn; layer i, or 0
uniform int atlas;            // 1: every cascade is a tile of layer 0
uniform int count;            // n, the number of cascades
uniform float splits[MAX_CASCADES + 1];
uniform float band_end[MAX_CASCADES];
uniform mat4 world_to_texture[MAX_CASCADES];
uniform ivec4 viewports[MAX_CASCADES];
uniform vec4 view_depth;
uniform vec4 light;           // (x, y, z, 0): toward the sun
uniform int pcf_radius;       // k
uniform float normal_offset;  // scale of sm.normal_offset (1: the derived minimum)
uniform float slope_factor;   // of sm.slope_scaled_bias (2c: the derived minimum)
uniform float constant_bias;  // its constant term, in depth units (constant * r_min)

uniform sampler2D surface;
uniform float body_id;
uniform int mode;
uniform vec3 colors[MAX_CASCADES];
uniform int pcss;                    // 1: percentage-closer soft shadows
uniform vec2 pcss_k[MAX_CASCADES];   // texels per unit of stored depth, per cascade
uniform float pcss_near[MAX_CASCADES];

in vec3 v_world;
flat in vec3 v_face_normal;

out vec4 result;

#include "pcss.glsl"

// The tile and layer pcss_depth reads (set before each pcss_lit).
ivec4 pcss_tile;
int pcss_layer;

float pcss_depth(vec2 uv) {
    ivec2 texel = ivec2(floor(uv * vec2(textureSize(maps, 0).xy)));
    ivec2 tap = clamp(texel, pcss_tile.xy, pcss_tile.xy + pcss_tile.zw - 1);
    return texelFetch(maps, ivec3(tap, pcss_layer), 0).r;
}

// PCSS in cascade i at p: 0 lit .. 1 shadowed (outside the tile or its depth range: lit).
float pcss_shadow_in(int i, vec3 p) {
    vec2 size = vec2(textureSize(maps, 0).xy);
    vec4 h = world_to_texture[i] * vec4(p, 1.0);
    vec3 str = h.xyz / h.w;
    pcss_tile = viewports[i];
    pcss_layer = atlas == 1 ? 0 : i;
    ivec2 texel = ivec2(floor(str.xy * size));
    if (str.z > 1.0 || any(lessThan(texel, pcss_tile.xy))
        || any(greaterThanEqual(texel, pcss_tile.xy + pcss_tile.zw))) {
        return 0.0;
    }
    float phi = pixel_angle(gl_FragCoord.xy);
    return 1.0 - pcss_lit(str, size, pcss_k[i], pcss_near[i], constant_bias, phi);
}

// The cascade serving view depth d (-1: none), and the weight of cascade i - 1 in its band.
int pick(float d, out float previous) {
    previous = 0.0;
    for (int i = 0; i < count; ++i) {
        bool last = i == count - 1;
        if (d >= splits[i] && (d < splits[i + 1] || (last && d <= splits[i + 1]))) {
            if (i > 0 && d <= band_end[i - 1] && band_end[i - 1] > splits[i]) {
                previous = (band_end[i - 1] - d) / (band_end[i - 1] - splits[i]);
            }
            return i;
        }
    }
    return -1;
}

// The gradients of s, t, r at p, columns 0, 1, 2: grad u = (m_u - u m_q) / q, with m_u the
// first three entries of row u of M (perspective maps too, although cascades are affine).
mat3 texture_gradients(mat4 M, vec3 p) {
    vec4 h = M * vec4(p, 1.0);
    vec3 str = h.xyz / h.w;
    mat3 rows = transpose(mat3(M));  // rows[u] = row u's first three entries
    vec3 mq = vec3(M[0][3], M[1][3], M[2][3]);
    return mat3(rows[0] - str.x * mq, rows[1] - str.y * mq, rows[2] - str.z * mq) / h.w;
}

// The shadow of point p (unit normal n, facing the sun) in cascade i: 0 lit .. 1 shadowed.
float shadow_in(int i, vec3 p, vec3 n) {
    if (pcss == 1) return pcss_shadow_in(i, p);
    vec2 size = vec2(textureSize(maps, 0).xy);
    mat3 g = texture_gradients(world_to_texture[i], p);
    vec3 D = cross(g[0], g[1]);
    float rise_s = abs(dot(g[2], cross(g[1], n))) / size.x;  // depth per texel along s
    float rise_t = abs(dot(g[2], cross(n, g[0]))) / size.y;
    float c = float(pcf_radius) + 0.5;
    float offset = normal_offset * c * (rise_s + rise_t) / abs(dot(g[2], D));
    float bias = constant_bias + slope_factor * max(rise_s, rise_t) / abs(dot(D, n));

    vec4 h = world_to_texture[i] * vec4(p + offset * n, 1.0);
    vec3 str = h.xyz / h.w;
    ivec4 tile = viewports[i];
    ivec2 texel = ivec2(floor(str.xy * size));
    if (str.z > 1.0 || any(lessThan(texel, tile.xy))
        || any(greaterThanEqual(texel, tile.xy + tile.zw))) {
        return 0.0;
    }
    int layer = atlas == 1 ? 0 : i;
    float lit = 0.0;
    for (int y = -pcf_radius; y <= pcf_radius; ++y) {
        for (int x = -pcf_radius; x <= pcf_radius; ++x) {
            ivec2 tap = clamp(texel + ivec2(x, y), tile.xy, tile.xy + tile.zw - 1);
            lit += str.z - bias <= texelFetch(maps, ivec3(tap, layer), 0).r ? 1.0 : 0.0;
        }
    }
    return 1.0 - lit / float((2 * pcf_radius + 1) * (2 * pcf_radius + 1));
}

void main() {
    if (texelFetch(surface, ivec2(gl_FragCoord.xy), 0).w != body_id + 1.0) discard;
    float previous;
    int i = pick(dot(view_depth, vec4(v_world, 1.0)), previous);
    if (mode == 1) {
        vec3 tint = i < 0 ? vec3(1.0) : colors[i];
        result = vec4(previous > 0.0 ? mix(tint, colors[i - 1], previous) : tint, 1.0);
        return;
    }
    vec3 n = normalize(v_face_normal);
    if (i < 0 || dot(n, light.xyz) <= 0.0) {  // turned from the sun: unlit anyway
        result = vec4(0.0);
        return;
    }
    float shadow = shadow_in(i, v_world, n);
    if (previous > 0.0) shadow = mix(shadow, shadow_in(i - 1, v_world, n), previous);
    result = vec4(shadow);
}
