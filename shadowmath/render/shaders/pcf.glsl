// Williams' comparison over a (2k + 1)^2 box of texels around (s, t) (percentage-closer
// filtering, radius k): the fraction of the taps where r <= the stored depth (lit).
float pcf_lit(sampler2DShadow depth_map, vec3 str, int k) {
    vec2 texel = 1.0 / vec2(textureSize(depth_map, 0));
    float lit = 0.0;
    for (int j = -k; j <= k; ++j) {
        for (int i = -k; i <= k; ++i) {
            lit += texture(depth_map, vec3(str.xy + vec2(i, j) * texel, str.z));
        }
    }
    return lit / float((2 * k + 1) * (2 * k + 1));
}
