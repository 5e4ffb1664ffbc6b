#version 330
// Williams' shadow z-buffer, pass 2 (into the light's shadow mask, MAX blending): compare
// each visible point's light depth r with the depth map, over a (2k + 1)^2 box of texels
// (percentage-closer filtering, radius k = pcf_radius). The map was drawn with a polygon
// offset (constant + slope-scaled bias), so a lit surface passes its own comparison.
// No shadow behind the light (q <= 0), outside the map or its depth range (lit by this
// map), nor on faces turned from the light (their diffuse term is already zero).
#include "mask_pass.glsl"
#include "pcf.glsl"

uniform sampler2DShadow depth_map;  // compare_func <=: 1.0 where r <= stored depth (lit)
uniform vec4 light;  // (x, y, z, 1) a point light, (x, y, z, 0) a directional one
uniform int pcf_radius;

void main() {
    if (!visible()) discard;
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
    mask = 1.0 - pcf_lit(depth_map, str, pcf_radius);
}
