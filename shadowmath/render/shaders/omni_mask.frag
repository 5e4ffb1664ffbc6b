#version 330
// Omnidirectional point light, pass 2 (into the light's shadow mask, MAX blending): look
// the visible point up in the light's cube depth map with the hardware's samplerCubeShadow
// along r = p - light. The map's six faces were drawn with cube_face_projection @
// cube_face_views[i] and a polygon offset (the bias), so the stored value is a window
// depth: compare the point's own window depth on the face samplerCube selects, computed
// from D = max(|r_x|, |r_y|, |r_z|), the distance along that face's axis (not |r|).
// No shadow outside the depth range (lit by this map) nor on faces turned from the light.
#include "mask_pass.glsl"

uniform samplerCubeShadow cube_map;  // compare_func <=: 1.0 where depth <= stored (lit)
uniform vec3 light_position;
uniform float near;
uniform float far;

void main() {
    if (!visible()) discard;
    vec3 r = v_world - light_position;
    float D = max(abs(r.x), max(abs(r.y), abs(r.z)));
    if (dot(v_face_normal, -r) <= 0.0 || D <= near || D >= far) {
        mask = 0.0;
        return;
    }
    float depth = far * (D - near) / ((far - near) * D);  // cube_face_depth's window depth
    mask = 1.0 - texture(cube_map, vec4(r, depth));
}
