#version 330
// Many lights, one shadow atlas (sm.allocate_atlas, sm.fit_atlas): the camera-view pass.
// Every light's shadow map is a tile of the atlas, a cube light's six faces six tiles. For
// a visible point p and light l:
//   * the light reaches p when p's face turns toward it and, for a spot, p lies in its cone;
//   * the tile: light_tiles[l][face], face 0 for a 2D map, sm.cube_face's rule for a cube
//     light (the major axis of p - light; ties to z, then y, as Vulkan's);
//   * world_to_texture[tile] @ (p, 1) = (s q, t q, r q, q): (s, t) in the atlas, r the depth
//     stored there for a caster at p;
//   * Williams' comparison r <= stored over a (2k + 1)^2 box of texels (PCF), every tap
//     clamped into the tile's texels: the tile's border is empty (2D) or holds the
//     neighbouring faces' depths (the cube ring), so no tap reads another light's map.
//   * with PCSS (the tile's row 5 (K_s, K_t, d_near, 1), render_atlas's light_size): the
//     blocker search and filter of pcss.glsl instead of the box, K in atlas texels, every
//     tap clamped into the tile's texels (its border holds the widest search).
// No shadow behind the light (q <= 0), outside the depth range or the tile (lit by this map).
//   mode 0: the shadow mask of light `which` (1 shadowed, 0 lit or not reached);
//   mode 1: the picture, albedo (ambient + sum over lights of colour max(n.l, 0) (1 - shadow)).
#include "pcss.glsl"

uniform sampler2D atlas;     // the depth atlas, window depths (1.0 where nothing was drawn)
// The tiles' and lights' tables of the pass's description (shadowmath/render/_atlas_pass.py,
// TILE_ROWS and LIGHT_ROWS; atlas.wgsl reads the same floats), one row a texel:
uniform sampler2D tiles;     // (world_to_texture's 4 columns, (x, y, n, 0), PCSS row) per tile
uniform sampler2D lights;    // (light, colour, (spot axis, cos), (cube, 0, 0, 0), the tiles
                             // of faces 0..3, of faces 4, 5 (-1 none)) per light
uniform sampler2D surface;   // the lit pass's position record (w = body id + 1)
uniform float body_id;
uniform int light_count;
uniform int pcf_radius;
uniform int mode;
uniform int which;
uniform vec3 albedo;
uniform float ambient;
uniform float casts;          // 1: this body is drawn in the maps (only casters self-shadow)
uniform float normal_offset;  // in texels of the light's map at the point

in vec3 v_world;
in vec3 v_normal;
flat in vec3 v_face_normal;

out vec4 result;

ivec3 tile_rect;  // the tile pcss_depth reads: (x, y, n) texels

float pcss_depth(vec2 uv) {
    ivec2 texel = ivec2(floor(uv * vec2(textureSize(atlas, 0))));
    return texelFetch(atlas, clamp(texel, tile_rect.xy, tile_rect.xy + tile_rect.z - 1), 0).r;
}

int cube_face(vec3 d) {
    vec3 a = abs(d);
    if (a.z >= a.x && a.z >= a.y) return d.z > 0.0 ? 4 : 5;
    if (a.y >= a.x) return d.y > 0.0 ? 2 : 3;
    return d.x > 0.0 ? 0 : 1;
}

// How much of light l's map says p is shadowed (0 lit .. 1 shadowed).
float shadow_of(int l, vec3 p) {
    vec4 light = texelFetch(lights, ivec2(0, l), 0);
    bool cube = texelFetch(lights, ivec2(3, l), 0).x > 0.5;
    int face = cube ? cube_face(p - light.xyz) : 0;
    int t = int(texelFetch(lights, ivec2(4 + face / 4, l), 0)[face % 4]);
    if (t < 0) return 0.0;
    mat4 M;  // world_to_texture
    for (int column = 0; column < 4; ++column) M[column] = texelFetch(tiles, ivec2(column, t), 0);
    mat4 rows = transpose(M);  // rows[u]: row u of world_to_texture
    vec4 c = vec4(p, 1.0) * rows;  // = world_to_texture @ (p, 1)
    if (c.w <= 0.0) return 0.0;
    // The normal-offset bias: look p up moved along its face normal by normal_offset
    // texels' world size there. s = (R0 . p) / (R3 . p) has the world gradient
    // (R0 - s R3).xyz / q, so one texel (1 / A in s) spans 1 / (A |grad s|) of world
    // along it; the larger of the s and t texels.
    vec3 gs = (rows[0].xyz - c.x / c.w * rows[3].xyz) / c.w;
    vec3 gt = (rows[1].xyz - c.y / c.w * rows[3].xyz) / c.w;
    float texel_world = 1.0 / (float(textureSize(atlas, 0).x) * max(min(length(gs), length(gt)), 1e-30));
    vec3 n = normalize(v_face_normal);
    float cosine = clamp(dot(n, normalize(light.xyz - light.w * p)), 0.0, 1.0);
    float offset = casts * normal_offset * texel_world * sqrt(1.0 - cosine * cosine);
    c = vec4(p + offset * n, 1.0) * rows;
    if (c.w <= 0.0) return 0.0;
    vec3 str = c.xyz / c.w;
    ivec3 rect = ivec3(texelFetch(tiles, ivec2(4, t), 0).xyz);
    ivec2 texel = ivec2(floor(str.xy * vec2(textureSize(atlas, 0))));
    if (str.z < 0.0 || str.z > 1.0 || any(lessThan(texel, rect.xy))
        || any(greaterThanEqual(texel, rect.xy + rect.z))) {
        return 0.0;
    }
    vec4 pcss = texelFetch(tiles, ivec2(5, t), 0);  // (K_s, K_t, d_near, 1) or 0
    if (pcss.w > 0.5) {
        tile_rect = rect;
        vec2 size = vec2(textureSize(atlas, 0));
        return 1.0 - pcss_lit(str, size, pcss.xy, pcss.z, 0.0, pixel_angle(gl_FragCoord.xy));
    }
    float lit = 0.0;
    for (int j = -pcf_radius; j <= pcf_radius; ++j) {
        for (int i = -pcf_radius; i <= pcf_radius; ++i) {
            ivec2 tap = clamp(texel + ivec2(i, j), rect.xy, rect.xy + rect.z - 1);
            lit += str.z <= texelFetch(atlas, tap, 0).r ? 1.0 : 0.0;
        }
    }
    float taps = float((2 * pcf_radius + 1) * (2 * pcf_radius + 1));
    return 1.0 - lit / taps;
}

// Whether light l reaches p on a face of normal n (front face, inside a spot's cone), and
// the unit vector toward it.
bool reaches(int l, vec3 p, vec3 n, out vec3 toward) {
    vec4 light = texelFetch(lights, ivec2(0, l), 0);
    vec4 spot = texelFetch(lights, ivec2(2, l), 0);  // w = -2: not a spot
    toward = normalize(light.xyz - light.w * p);
    if (dot(n, toward) <= 0.0) return false;
    return spot.w < -1.5 || dot(-toward, spot.xyz) >= spot.w;
}

void main() {
    if (texelFetch(surface, ivec2(gl_FragCoord.xy), 0).w != body_id + 1.0) discard;
    vec3 toward;
    if (mode == 0) {
        float shadow = reaches(which, v_world, v_face_normal, toward) ? shadow_of(which, v_world) : 0.0;
        result = vec4(shadow);
        return;
    }
    vec3 n = normalize(v_normal);
    vec3 light_sum = vec3(ambient);
    for (int l = 0; l < light_count; ++l) {
        if (!reaches(l, v_world, v_face_normal, toward)) continue;
        vec3 color = texelFetch(lights, ivec2(1, l), 0).rgb;
        light_sum += color * max(dot(n, toward), 0.0) * (1.0 - shadow_of(l, v_world));
    }
    result = vec4(albedo * light_sum, 1.0);
}
