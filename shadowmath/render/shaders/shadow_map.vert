#version 330
// Pass 1 of Nagy's method: the blocker in its local coordinates straight to the
// shadow map's clip space (M_BlockerLocalToShadowMap). No lighting, no normals.
uniform mat4 blocker_to_clip;
in vec3 position;

void main() {
    gl_Position = blocker_to_clip * vec4(position, 1.0);
}
