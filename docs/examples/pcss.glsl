// Percentage-closer soft shadows (Fernando 2005), with shadowmath's quantities.
//
//   shadowMap  the light's depth texture of the faces turned from the light, read as
//              plain depths: a sampler2D over a texture that does NOT compare (moderngl:
//              texture.compare_func = ''), nearest filtering
//   tile       the texels (x0, y0, x1, y1) the taps may read, inclusive: (0, 0, W-1, H-1)
//              for a whole map, a cascade's viewport in an atlas
//   str        (s, t, r) of the receiver point: (world_to_texture @ p).xyz / .w
//   K, dNear   sm.pcss_parameters(fit).texels_per_depth and .near_depth of this map
//   bias       in stored-depth units (the programs: sm.slope_scaled_bias's constant term)
//   phi        the disks' rotation at this pixel: pcss_angle(gl_FragCoord.xy)
// returns the lit fraction in [0, 1].
//
//   search radius   K |r - dNear|                 texels, along s and t
//   penumbra        K max(sgn (r - dBlocker), 0)   texels, sgn = 1 - 2 dNear (reversed Z: -1)
const int PCSS_SEARCH_TAPS = 32;
const int PCSS_FILTER_TAPS = 64;

// Jimenez's interleaved gradient noise: a per-pixel angle in [0, 2 pi).
float pcss_angle(vec2 pixel) {
    return 6.28318530718 * fract(52.9829189 * fract(dot(pixel, vec2(0.06711056, 0.00583715))));
}

// Tap i of n of a Vogel disk (a golden-angle spiral, equal areas) of radius 1, turned by phi.
vec2 pcss_vogel(int i, int n, float phi) {
    float a = float(i) * 2.39996322972865332 + phi;
    return sqrt((float(i) + 0.5) / float(n)) * vec2(cos(a), sin(a));
}

// The stored depth of the texel at uv, clamped to the tile.
float pcss_depth(sampler2D shadowMap, ivec4 tile, vec2 uv) {
    vec2 size = vec2(textureSize(shadowMap, 0));
    vec2 lo = (vec2(tile.xy) + 0.5) / size, hi = (vec2(tile.zw) + 0.5) / size;
    return textureLod(shadowMap, clamp(uv, lo, hi), 0.0).r;
}

float pcss(sampler2D shadowMap, ivec4 tile, vec3 str, vec2 K, float dNear, float bias,
           float phi) {
    vec2 size = vec2(textureSize(shadowMap, 0));
    float sgn = 1.0 - 2.0 * dNear;
    float receiver = sgn * str.z - bias;  // a texel holds a blocker if sgn * d < receiver
    vec2 search = K * abs(str.z - dNear) / size;
    float sum = 0.0;
    int count = 0;
    for (int i = 0; i < PCSS_SEARCH_TAPS; ++i) {
        vec2 uv = str.xy + pcss_vogel(i, PCSS_SEARCH_TAPS, phi) * search;
        float d = pcss_depth(shadowMap, tile, uv);
        if (sgn * d < receiver) {
            sum += d;
            count += 1;
        }
    }
    if (count == 0) return 1.0;  // nothing nearer the light in the search region
    vec2 radius = K * max(sgn * (str.z - sum / float(count)), 0.0) / size;
    float lit = 0.0;
    for (int i = 0; i < PCSS_FILTER_TAPS; ++i) {
        vec2 uv = str.xy + pcss_vogel(i, PCSS_FILTER_TAPS, phi) * radius;
        lit += sgn * pcss_depth(shadowMap, tile, uv) < receiver ? 0.0 : 1.0;
    }
    return lit / float(PCSS_FILTER_TAPS);
}
