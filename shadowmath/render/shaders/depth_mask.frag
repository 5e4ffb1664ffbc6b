#version 330
// Williams' shadow z-buffer, pass 2 (into the light's shadow mask, MAX blending): compare
// each visible point's light depth r with the depth map, over a (2k + 1)^2 box of texels
// (percentage-closer filtering, radius k = pcf_radius). The map was drawn with a polygon
// offset (constant + slope-scaled bias), so a lit surface passes its own comparison.
// No shadow behind the light (q <= 0), outside the map or its depth range (lit by this
// map), nor on faces turned from the light (their diffuse term is already zero).
uniform sampler2DShadow depth_map;  // compare_func <=: 1.0 where r <= stored depth (lit)
uniform sampler2D surface;          // the lit pass's position record (w = body id + 1)
uniform float body_id;
uniform vec4 light;  // (x, y, z, 1) a point light, (x, y, z, 0) a directional one
uniform int pcf_radius;

in vec3 v_world;
in vec3 v_normal;
flat in vec3 v_face_normal;
in vec4 v_stq;

out float mask;

void main() {
    if (texelFetch(surface, ivec2(gl_FragCoord.xy), 0).w != body_id + 1.0) discard;
    float q = v_stq.w;
    if (q <= 0.0 || dot(v_face_normal, light.xyz - light.w * v_world) <= 0.0) {
        mask = 0.0;
        return;
    }
    vec3 str = v_stq.xyz / q;  // (s, t, r): texture coordinates and the [0, 1] light depth
    if (any(lessThan(str, vec3(0.0))) || any(greaterThan(str, vec3(1.0)))) {
        mask = 0.0;
        return;
    }
    vec2 texel = 1.0 / vec2(textureSize(depth_map, 0));
    float lit = 0.0;
    for (int j = -pcf_radius; j <= pcf_radius; ++j) {
        for (int i = -pcf_radius; i <= pcf_radius; ++i) {
            lit += texture(depth_map, vec3(str.xy + vec2(i, j) * texel, str.z));
        }
    }
    float taps = float((2 * pcf_radius + 1) * (2 * pcf_radius + 1));
    mask = 1.0 - lit / taps;
}
