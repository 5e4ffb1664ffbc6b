#version 330
// Percentage-closer soft shadows of a spherical point light through a cube depth map,
// pass 2 (into the light's shadow mask, MAX blending): the face of r = p - light's
// largest component (+X, -X, +Y, -Y, +Z, -Z: layer 2 axis + (r_axis < 0)) gives the
// point's (s, t, d_R) through face_to_texture; the blocker search and filter of pcss.glsl
// run in that face's texture coordinates, taps clamped to the face (its border ring
// holds the widest search). The faces hold the faces turned from the light, as
// pcss_mask.frag's map. No shadow outside a face's depth range nor on faces turned from
// the light.
#include "mask_pass.glsl"
#include "pcss.glsl"

uniform sampler2DArray faces;    // window depths per face, nearest, clamped (1 where empty)
uniform mat4 face_to_texture[6];  // world to each face's (s, t, depth, 1), depth in [0, 1]
uniform vec3 light_position;
uniform vec2 k;                   // texels per unit of window depth (every face alike)
uniform float d_near;             // the window depth of the near plane

int face = 0;  // the layer pcss_depth reads

float pcss_depth(vec2 uv) {
    return textureLod(faces, vec3(uv, float(face)), 0.0).r;
}

void main() {
    if (!visible()) discard;
    vec3 r = v_world - light_position;
    vec3 a = abs(r);
    int axis = a.x >= a.y && a.x >= a.z ? 0 : (a.y >= a.z ? 1 : 2);
    face = 2 * axis + (r[axis] < 0.0 ? 1 : 0);
    vec4 stq = face_to_texture[face] * vec4(v_world, 1.0);
    if (stq.w <= 0.0 || dot(v_face_normal, -r) <= 0.0) {
        mask = 0.0;
        return;
    }
    vec3 str = stq.xyz / stq.w;
    if (any(lessThan(str, vec3(0.0))) || any(greaterThan(str, vec3(1.0)))) {
        mask = 0.0;
        return;
    }
    vec2 size = vec2(textureSize(faces, 0).xy);
    mask = 1.0 - pcss_lit(str, size, k, d_near, 0.0, pixel_angle(gl_FragCoord.xy));
}
