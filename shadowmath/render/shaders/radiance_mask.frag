#version 330
// Heckbert and Herf's radiance texture on its receiver (into the light's shadow mask,
// MAX blending): the fraction of the area light blocked at this point is one minus the
// texture's visibility at the point's (u, v) in the receiver's parallelogram. No shadow
// on faces turned from the light's centre (their diffuse term is already zero). v_stq is
// (u, v, 0, 1): body_to_texture maps the receiver onto its parallelogram.
#include "mask_pass.glsl"

uniform sampler2D radiance;  // visibility in [0, 1], (u, v) in [0, 1]^2, clamp to edge
uniform vec3 light_position;  // the area light's centre

void main() {
    if (!visible()) discard;
    if (dot(v_face_normal, light_position - v_world) <= 0.0) {
        mask = 0.0;
        return;
    }
    mask = 1.0 - texture(radiance, v_stq.xy / v_stq.w).r;
}
