// Percentage-closer soft shadows (Fernando 2005) on a depth map read as plain window
// depths (sampler2D, no comparison), with the quantities of shadowmath.pcss_parameters:
// k (texels per unit of window depth, per axis) and d_near (the near plane's depth):
//   blocker search region   k |d_R - d_near|           texels (radius)
//   penumbra (PCF radius)   k max(d_R - d_B, 0)        texels (radius)
// d_R the receiver's depth, d_B the mean depth of the blockers the search found. Both
// kernels are Vogel disks (golden-angle spirals) rotated per pixel by phi.
const float GOLDEN_ANGLE = 2.39996322972865332;
const int PCSS_SEARCH_TAPS = 32;
const int PCSS_FILTER_TAPS = 64;

// Jimenez's interleaved gradient noise: a per-pixel angle in [0, 2 pi).
float pixel_angle(vec2 pixel) {
    return 6.28318530718 * fract(52.9829189 * fract(dot(pixel, vec2(0.06711056, 0.00583715))));
}

// Tap i of count on the unit disk: radius sqrt((i + 1/2) / count), angle i golden angles.
vec2 vogel_tap(int i, int count, float phi) {
    float a = float(i) * GOLDEN_ANGLE + phi;
    return sqrt((float(i) + 0.5) / float(count)) * vec2(cos(a), sin(a));
}

// The lit fraction at str = (s, t, d_R): 1 where the search finds no blocker.
float pcss_lit(sampler2D depth_map, vec3 str, vec2 k, float d_near, float phi) {
    vec2 texel = 1.0 / vec2(textureSize(depth_map, 0));
    vec2 search = k * abs(str.z - d_near) * texel;
    float blocker_sum = 0.0;
    int blockers = 0;
    for (int i = 0; i < PCSS_SEARCH_TAPS; ++i) {
        vec2 uv = str.xy + vogel_tap(i, PCSS_SEARCH_TAPS, phi) * search;
        float d = textureLod(depth_map, uv, 0.0).r;
        if (d < str.z) {
            blocker_sum += d;
            blockers += 1;
        }
    }
    if (blockers == 0) return 1.0;
    vec2 radius = k * max(str.z - blocker_sum / float(blockers), 0.0) * texel;
    float lit = 0.0;
    for (int i = 0; i < PCSS_FILTER_TAPS; ++i) {
        vec2 uv = str.xy + vogel_tap(i, PCSS_FILTER_TAPS, phi) * radius;
        float d = textureLod(depth_map, uv, 0.0).r;
        lit += step(str.z, d);  // 1 where d_R <= the stored depth
    }
    return lit / float(PCSS_FILTER_TAPS);
}
