#version 330
// Cascaded shadow maps of a sun, the camera pass: the shadow at each visible point.
//
// The uniform block Frame is the cascades pass's description (shadowmath/render/_cascade_pass.py,
// FRAME_DTYPE; cascades.wgsl reads the same bytes), sm.fit_cascades' outputs as they are
// (OpenGL conventions):
//   cascades[i].world_to_texture  world point to (s, t, r, 1): s, t in the texture (the
//                                 whole atlas with layout="atlas"), r the depth stored
//   cascades[i].viewport          viewports[i], the tile (x, y, w, h) in texels
//                                 (layout="layers": (0, 0, W, H), the whole layer i)
//   cascades[i].near, .far        splits[i], splits[i + 1]: cascade i serves [near, far)
//   cascades[i].band_end          band_end[i] > far: in [far, band_end] both i and i + 1
//                                 are sampled and mixed, i's weight falling linearly from 1 to 0
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
// blocker search and filter of pcss.glsl with cascades[i].k and cascades[i].d_near
// (sm.pcss_parameters of the cascades: one world penumbra in every cascade), every tap
// clamped to the cascade's tile, the constant bias only.
//
// Renderer-specific: this pass draws every body again over the lit pass's record
// (`surface`: world position, w = body id + 1) and keeps the fragment that is visible;
// mode 0 writes the shadow (1 shadowed, 0 lit), mode 1 the cascade's debug colour.
#include "constants.glsl"

struct Cascade {
    mat4 world_to_texture;
    ivec4 viewport;
    float near;
    float far;
    float band_end;
    vec2 k;                   // PCSS: texels per unit of stored depth
    float d_near;             // PCSS: the near plane's stored depth
};

layout(std140) uniform Frame {
    mat4 world_to_clip;       // the camera (read by cascades.wgsl; surface.vert has its own)
    vec4 view_depth;
    vec4 light;               // (x, y, z, 0): toward the sun
    int count;                // n, the number of cascades
    int pcf_radius;           // k
    int atlas;                // 1: every cascade is a tile of layer 0
    float normal_offset;      // scale of sm.normal_offset (1: the derived minimum)
    float slope_factor;       // of sm.slope_scaled_bias (2c: the derived minimum)
    float constant_bias;      // its constant term, in depth units (constant * r_min)
    int pcss;                 // 1: percentage-closer soft shadows
    Cascade cascades[MAX_CASCADES];
} frame;

uniform sampler2DArray maps;  // R32F depths, 1.0 where nothing was drawn; layer i, or 0
uniform sampler2D surface;
uniform float body_id;
uniform int mode;
uniform vec3 colors[MAX_CASCADES];

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
    vec4 h = frame.cascades[i].world_to_texture * vec4(p, 1.0);
    vec3 str = h.xyz / h.w;
    pcss_tile = frame.cascades[i].viewport;
    pcss_layer = frame.atlas == 1 ? 0 : i;
    ivec2 texel = ivec2(floor(str.xy * size));
    if (str.z > 1.0 || any(lessThan(texel, pcss_tile.xy))
        || any(greaterThanEqual(texel, pcss_tile.xy + pcss_tile.zw))) {
        return 0.0;
    }
    float phi = pixel_angle(gl_FragCoord.xy);
    Cascade c = frame.cascades[i];
    return 1.0 - pcss_lit(str, size, c.k, c.d_near, frame.constant_bias, phi);
}

// The cascade serving view depth d (-1: none), and the weight of cascade i - 1 in its band.
int pick(float d, out float previous) {
    previous = 0.0;
    for (int i = 0; i < frame.count; ++i) {
        bool last = i == frame.count - 1;
        Cascade c = frame.cascades[i];
        if (d >= c.near && (d < c.far || (last && d <= c.far))) {
            float end = i > 0 ? frame.cascades[i - 1].band_end : 0.0;
            if (i > 0 && d <= end && end > c.near) {
                previous = (end - d) / (end - c.near);
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
    if (frame.pcss == 1) return pcss_shadow_in(i, p);
    vec2 size = vec2(textureSize(maps, 0).xy);
    mat3 g = texture_gradients(frame.cascades[i].world_to_texture, p);
    vec3 D = cross(g[0], g[1]);
    float rise_s = abs(dot(g[2], cross(g[1], n))) / size.x;  // depth per texel along s
    float rise_t = abs(dot(g[2], cross(n, g[0]))) / size.y;
    int k = frame.pcf_radius;
    float c = float(k) + 0.5;
    float offset = frame.normal_offset * c * (rise_s + rise_t) / abs(dot(g[2], D));
    float bias = frame.constant_bias + frame.slope_factor * max(rise_s, rise_t) / abs(dot(D, n));

    vec4 h = frame.cascades[i].world_to_texture * vec4(p + offset * n, 1.0);
    vec3 str = h.xyz / h.w;
    ivec4 tile = frame.cascades[i].viewport;
    ivec2 texel = ivec2(floor(str.xy * size));
    if (str.z > 1.0 || any(lessThan(texel, tile.xy))
        || any(greaterThanEqual(texel, tile.xy + tile.zw))) {
        return 0.0;
    }
    int layer = frame.atlas == 1 ? 0 : i;
    float lit = 0.0;
    for (int y = -k; y <= k; ++y) {
        for (int x = -k; x <= k; ++x) {
            ivec2 tap = clamp(texel + ivec2(x, y), tile.xy, tile.xy + tile.zw - 1);
            lit += str.z - bias <= texelFetch(maps, ivec3(tap, layer), 0).r ? 1.0 : 0.0;
        }
    }
    return 1.0 - lit / float((2 * k + 1) * (2 * k + 1));
}

void main() {
    if (texelFetch(surface, ivec2(gl_FragCoord.xy), 0).w != body_id + 1.0) discard;
    float previous;
    int i = pick(dot(frame.view_depth, vec4(v_world, 1.0)), previous);
    if (mode == 1) {
        vec3 tint = i < 0 ? vec3(1.0) : colors[i];
        result = vec4(previous > 0.0 ? mix(tint, colors[i - 1], previous) : tint, 1.0);
        return;
    }
    vec3 n = normalize(v_face_normal);
    if (i < 0 || dot(n, frame.light.xyz) <= 0.0) {  // turned from the sun: unlit anyway
        result = vec4(0.0);
        return;
    }
    float shadow = shadow_in(i, v_world, n);
    if (previous > 0.0) shadow = mix(shadow, shadow_in(i - 1, v_world, n), previous);
    result = vec4(shadow);
}
