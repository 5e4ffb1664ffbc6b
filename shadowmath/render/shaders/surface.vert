#version 330
// Every pass that draws a body (the lit pass, the shadow-mask pass, the subtractive
// pass) uses this one vertex shader, so that the passes produce bit-identical depths
// and the later ones pass the LEQUAL depth test exactly where the first one drew.
uniform mat4 world_to_clip;
uniform mat4 body_to_world;
// Receiver local coordinates to (s q, t q, r q, q): receiver_texture_matrix(setup, body_to_world).
uniform mat4 body_to_texture;

in vec3 position;
in vec3 normal;       // smooth (area-weighted) vertex normal, for lighting
in vec3 face_normal;  // the triangle's normal, for the article's back-face elimination

out vec3 v_world;
out vec3 v_normal;
flat out vec3 v_face_normal;
out vec4 v_stq;

invariant gl_Position;

void main() {
    vec4 world = body_to_world * vec4(position, 1.0);
    mat3 normal_matrix = transpose(inverse(mat3(body_to_world)));
    v_world = world.xyz / world.w;
    v_normal = normal_matrix * normal;
    v_face_normal = normal_matrix * face_normal;
    v_stq = body_to_texture * vec4(position, 1.0);
    gl_Position = world_to_clip * world;
}
