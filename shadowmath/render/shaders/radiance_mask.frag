#version 330
// Heckbert and Herf's radiance texture on its receiver (into the light's shadow mask,
// MAX blending): the fraction of the area light blocked at this point is one minus the
// texture's visibility at the point's (u, v) in the receiver's parallelogram. No shadow
// on faces turned from the light's centre (their diffuse term is already zero).
uniform sampler2D radiance;  // visibility in [0, 1], (u, v) in [0, 1]^2, clamp to edge
uniform sampler2D surface;   // the lit pass's position record (w = body id + 1)
uniform float body_id;
uniform vec3 light_position;  // the area light's centre

in vec3 v_world;
in vec3 v_normal;
flat in vec3 v_face_normal;
in vec4 v_stq;  // (u, v, 0, 1): body_to_texture maps the receiver onto its parallelogram

out float mask;

void main() {
    if (texelFetch(surface, ivec2(gl_FragCoord.xy), 0).w != body_id + 1.0) discard;
    if (dot(v_face_normal, light_position - v_world) <= 0.0) {
        mask = 0.0;
        return;
    }
    mask = 1.0 - texture(radiance, v_stq.xy / v_stq.w).r;
}
