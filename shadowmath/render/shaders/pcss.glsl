// Percentage-closer soft shadows (Fernando 2005) on a map of window depths, with the
// quantities of shadowmath.pcss_parameters: k (texels per unit of window depth, per
// axis) and d_near (the near plane's depth):
//   blocker search region   k |d_R - d_near|           texels (radius)
//   penumbra (PCF radius)   k max(d_R - d_B, 0)        texels (radius)
// d_R the receiver's depth, d_B the mean depth of the blockers the search found. Both
// kernels are Vogel disks (golden-angle spirals) rotated per pixel by phi. The including
// shader defines pcss_depth(uv): the stored depth at texture coordinates uv (1 where
// nothing was drawn), which may clamp to its tile.
// GOLDEN_ANGLE, PCSS_SEARCH_TAPS, PCSS_FILTER_TAPS and the noise's constants: from Python
// (shadowmath/render/_shader_constants.py), as pcss.wgsl's.
#include "constants.glsl"

float pcss_depth(vec2 uv);

// Jimenez's interleaved gradient noise: a per-pixel angle in [0, 2 pi).
float pixel_angle(vec2 pixel) {
    return TWO_PI * fract(NOISE_SCALE * fract(dot(pixel, vec2(NOISE_X, NOISE_Y))));
}

// Tap i of count on the unit disk: radius sqrt((i + 1/2) / count), angle i golden angles.
vec2 vogel_tap(int i, int count, float phi) {
    float a = float(i) * GOLDEN_ANGLE + phi;
    return sqrt((float(i) + 0.5) / float(count)) * vec2(cos(a), sin(a));
}

// The lit fraction at str = (s, t, d_R) of a map of size texels: 1 where the search
// finds no blocker; a tap is lit where d_R - bias <= the stored depth.
float pcss_lit(vec3 str, vec2 size, vec2 k, float d_near, float bias, float phi) {
    float receiver = str.z - bias;
    vec2 search = k * abs(str.z - d_near) / size;
    float blocker_sum = 0.0;
    int blockers = 0;
    for (int i = 0; i < PCSS_SEARCH_TAPS; ++i) {
        float d = pcss_depth(str.xy + vogel_tap(i, PCSS_SEARCH_TAPS, phi) * search);
        if (d < receiver) {
            blocker_sum += d;
            blockers += 1;
        }
    }
    if (blockers == 0) return 1.0;
    vec2 radius = k * max(str.z - blocker_sum / float(blockers), 0.0) / size;
    float lit = 0.0;
    for (int i = 0; i < PCSS_FILTER_TAPS; ++i) {
        lit += step(receiver, pcss_depth(str.xy + vogel_tap(i, PCSS_FILTER_TAPS, phi) * radius));
    }
    return lit / float(PCSS_FILTER_TAPS);
}
