#version 330
// Pass 2 (into the light's shadow mask, MAX blending): the shadow map applied to a
// receiver as a projective texture. No shadow behind the light (q <= 0: the divide
// would mirror the map) nor on faces turned from the light (the article's back-face
// shadow elimination, N . (L - P) <= 0).
uniform sampler2D shadow_map;   // clamp to edge: outside the frustum reads the empty border
uniform sampler2D surface;      // the lit pass's position record (w = body id + 1)
uniform float body_id;
uniform vec3 light_position;

in vec3 v_world;
in vec3 v_normal;
flat in vec3 v_face_normal;
in vec4 v_stq;

out float mask;

void main() {
    // The stencil test moderngl lacks: shade only pixels where this receiver is visible.
    if (texelFetch(surface, ivec2(gl_FragCoord.xy), 0).w != body_id + 1.0) discard;
    float q = v_stq.w;
    if (q <= 0.0 || dot(v_face_normal, light_position - v_world) <= 0.0) {
        mask = 0.0;
        return;
    }
    mask = textureProj(shadow_map, v_stq.xyw).r;  // (s q, t q, q) -> texture at (s, t)
}
