#version 330
// Williams' shadow z-buffer, pass 1: every caster (blockers and receivers alike) in its
// local coordinates straight to the light's clip space; only the depth is kept.
uniform mat4 body_to_clip;  // blocker_to_clip @ inverse(blocker_to_world) @ body_to_world
in vec3 position;

void main() {
    gl_Position = body_to_clip * vec4(position, 1.0);
}
