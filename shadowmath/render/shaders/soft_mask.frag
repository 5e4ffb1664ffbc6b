#version 330
// Soft shadows as seed 003 makes them, pass 2 for one light sample (into the light's
// shadow mask, ADD blending): the sample's hard shadow, Williams' depth comparison over a
// (2k + 1)^2 box of texels as in depth_mask.frag, weighted by 1 / count so that the
// count samples' hard shadows add up to the fraction of the light that is blocked.
uniform sampler2DShadow depth_map;  // compare_func <=: 1.0 where r <= stored depth (lit)
uniform sampler2D surface;          // the lit pass's position record (w = body id + 1)
uniform float body_id;
uniform vec3 light_position;        // this sample
uniform vec3 light_centre;          // the area light's centre: the lit pass's Lambert term
uniform int pcf_radius;
uniform float weight;               // 1 / count

in vec3 v_world;
in vec3 v_normal;
flat in vec3 v_face_normal;
in vec4 v_stq;

out float mask;

void main() {
    if (texelFetch(surface, ivec2(gl_FragCoord.xy), 0).w != body_id + 1.0) discard;
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
    vec2 texel = 1.0 / vec2(textureSize(depth_map, 0));
    float lit = 0.0;
    for (int j = -pcf_radius; j <= pcf_radius; ++j) {
        for (int i = -pcf_radius; i <= pcf_radius; ++i) {
            lit += texture(depth_map, vec3(str.xy + vec2(i, j) * texel, str.z));
        }
    }
    float taps = float((2 * pcf_radius + 1) * (2 * pcf_radius + 1));
    mask = weight * (1.0 - lit / taps);
}
