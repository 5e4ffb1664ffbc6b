#version 330
// Cascaded shadow maps, the camera-view pass. The fragment's view depth picks the cascade
// (cascade i serves [splits[i], splits[i + 1])); in cascade i - 1's band, view depths in
// [splits[i], band_end[i - 1]], the shadows of both cascades are blended, the weight of
// i - 1 falling from 1 to 0 across the band. Each cascade's shadow is Williams' comparison
// of the point's stored-depth coordinate r with the map, over a (2k + 1)^2 box of texels
// (PCF, k = pcf_radius), taps clamped to the cascade's tile (its layer of the array, or
// its viewport in an atlas). The maps were drawn with a polygon offset (the bias), and the
// point is looked up moved off its face along the normal by a cascade's normal_offset (a
// fraction of its texel's world size: the normal-offset bias, against acne where the
// polygon offset of one triangle does not cover its neighbour's, as at a box's ridge).
//   mode 0: the shadow mask (1 shadowed, 0 lit), into the light's mask target;
//   mode 1: the cascade colours, multiplied into the picture (debug view).
// No shadow beyond the last split, outside a cascade's tile, or on faces turned from the
// light (their diffuse term is already zero).
const int MAX_CASCADES = 8;
uniform sampler2DArray maps;  // R32F window depths; 1.0 where nothing was drawn
uniform sampler2D surface;    // the lit pass's position record (w = body id + 1)
uniform float body_id;
uniform vec4 light;           // (x, y, z, 0): toward the sun
uniform vec4 view_depth;      // the camera's view depth as a row: depth = dot(row, (p, 1))
uniform int count;
uniform float splits[MAX_CASCADES + 1];
uniform float band_end[MAX_CASCADES];
uniform mat4 world_to_texture[MAX_CASCADES];  // world to (s, t, r, 1)
uniform ivec4 viewport[MAX_CASCADES];         // each cascade's tile (x, y, w, h) in texels
uniform int atlas;                            // 1: every cascade in layer 0
uniform int pcf_radius;
uniform float normal_offset[MAX_CASCADES];   // world length along the face normal
uniform int mode;
uniform vec3 colors[MAX_CASCADES];

in vec3 v_world;
flat in vec3 v_face_normal;

out vec4 result;

// The cascade serving depth d (-1: none) and the weight of the one before it (its band).
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

float shadow_in(int i) {
    vec3 p = v_world + normal_offset[i] * normalize(v_face_normal);
    vec4 stq = world_to_texture[i] * vec4(p, 1.0);
    vec3 str = stq.xyz / stq.w;
    ivec4 tile = viewport[i];
    vec2 texel = str.xy * vec2(textureSize(maps, 0).xy);
    ivec2 c = ivec2(floor(texel));
    if (str.z < 0.0 || str.z > 1.0 || any(lessThan(c, tile.xy))
        || any(greaterThanEqual(c, tile.xy + tile.zw))) {
        return 0.0;
    }
    int layer = atlas == 1 ? 0 : i;
    float lit = 0.0;
    for (int j = -pcf_radius; j <= pcf_radius; ++j) {
        for (int k = -pcf_radius; k <= pcf_radius; ++k) {
            ivec2 p = clamp(c + ivec2(k, j), tile.xy, tile.xy + tile.zw - 1);
            lit += str.z <= texelFetch(maps, ivec3(p, layer), 0).r ? 1.0 : 0.0;
        }
    }
    float taps = float((2 * pcf_radius + 1) * (2 * pcf_radius + 1));
    return 1.0 - lit / taps;
}

void main() {
    if (texelFetch(surface, ivec2(gl_FragCoord.xy), 0).w != body_id + 1.0) discard;
    float previous;
    int i = pick(dot(view_depth, vec4(v_world, 1.0)), previous);
    if (mode == 1) {
        vec3 tint = i < 0 ? vec3(1.0) : colors[i];
        if (previous > 0.0) tint = mix(tint, colors[i - 1], previous);
        result = vec4(tint, 1.0);
        return;
    }
    if (i < 0 || dot(v_face_normal, light.xyz) <= 0.0) {
        result = vec4(0.0);
        return;
    }
    float shadow = shadow_in(i);
    if (previous > 0.0) shadow = mix(shadow, shadow_in(i - 1), previous);
    result = vec4(shadow);
}
