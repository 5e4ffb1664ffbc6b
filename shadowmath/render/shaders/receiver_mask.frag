#version 330
// Pass 2 (into the light's shadow mask, MAX blending): the shadow map applied to a
// receiver as a projective texture. No shadow behind the light (q <= 0: the divide
// would mirror the map) nor on faces turned from the light (the article's back-face
// shadow elimination, N . (L - P) <= 0).
#include "mask_pass.glsl"

uniform sampler2D shadow_map;   // clamp to edge: outside the frustum reads the empty border
uniform vec3 light_position;

void main() {
    // The stencil test moderngl lacks: shade only pixels where this receiver is visible.
    if (!visible()) discard;
    float q = v_stq.w;
    if (q <= 0.0 || dot(v_face_normal, light_position - v_world) <= 0.0) {
        mask = 0.0;
        return;
    }
    mask = textureProj(shadow_map, v_stq.xyw).r;  // (s q, t q, q) -> texture at (s, t)
}
