#version 330
// Soft shadows as seed 003 makes them, pass 2 for one light sample (into the light's
// shadow mask, ADD blending): the sample's hard shadow, Williams' depth comparison over a
// (2k + 1)^2 box of texels as in depth_mask.frag, weighted by 1 / count so that the
// count samples' hard shadows add up to the fraction of the light that is blocked.
#include "mask_pass.glsl"
#include "pcf.glsl"

uniform sampler2DShadow depth_map;  // compare_func <=: 1.0 where r <= stored depth (lit)
uniform vec3 light_position;        // this sample
uniform vec3 light_centre;          // the area light's centre: the lit pass's Lambert term
uniform int pcf_radius;
uniform float weight;               // 1 / count

void main() {
    if (!visible()) discard;
    float q = v_stq.w;
    // Faces turned from the light's centre get no diffuse term to remove; faces turned
    // from this sample only are in its shadow.
    if (q <= 0.0 || dot(v_face_normal, light_centre - v_world) <= 0.0) {
        mask = 0.0;
        return;
    }
    if (dot(v_face_normal, light_position - v_world) <= 0.0) {
        mask = weight;
        return;
    }
    vec3 str = v_stq.xyz / q;
    if (any(lessThan(str, vec3(0.0))) || any(greaterThan(str, vec3(1.0)))) {
        mask = 0.0;
        return;
    }
    mask = weight * (1.0 - pcf_lit(depth_map, str, pcf_radius));
}
