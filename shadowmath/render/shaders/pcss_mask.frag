#version 330
// Percentage-closer soft shadows, pass 2 (into the light's shadow mask, MAX blending):
// the blocker search and the filter of pcss.glsl around each visible point's (s, t, r).
// The map holds the faces turned from the light (front faces culled), the surface
// nearest the receiver along each ray through a closed caster: the blocker distance is
// then zero where a caster touches the receiver, and the shadow hardens there. No shadow
// behind the light (q <= 0), outside the map or its depth range, nor on faces turned
// from the light (their diffuse term is already zero).
#include "mask_pass.glsl"
#include "pcss.glsl"

uniform sampler2D depth_map;  // window depths, nearest, clamp to edge (1 where empty)
uniform vec4 light;           // (x, y, z, 1) a point light, (x, y, z, 0) a directional one
uniform vec2 k;               // texels per unit of window depth, per axis
uniform float d_near;         // the window depth of the near plane

float pcss_depth(vec2 uv) {
    return textureLod(depth_map, uv, 0.0).r;
}

void main() {
    if (!visible()) discard;
    float q = v_stq.w;
    if (q <= 0.0 || dot(v_face_normal, light.xyz - light.w * v_world) <= 0.0) {
        mask = 0.0;
        return;
    }
    vec3 str = v_stq.xyz / q;
    if (any(lessThan(str, vec3(0.0))) || any(greaterThan(str, vec3(1.0)))) {
        mask = 0.0;
        return;
    }
    vec2 size = vec2(textureSize(depth_map, 0));
    mask = 1.0 - pcss_lit(str, size, k, d_near, 0.0, pixel_angle(gl_FragCoord.xy));
}
