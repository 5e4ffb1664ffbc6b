#version 330
// Pass 3, Blinn's planar shadow: the blocker flattened onto the receiver's plane by
// planar_projection(plane, light) and seen by the camera. A point beyond the light
// gets w < 0 and is clipped by the GPU (no anti-shadow).
uniform mat4 world_to_clip;
uniform mat4 flatten;          // planar_projection(plane, light), world to world
uniform mat4 blocker_to_world;

in vec3 position;

void main() {
    gl_Position = world_to_clip * (flatten * (blocker_to_world * vec4(position, 1.0)));
}
