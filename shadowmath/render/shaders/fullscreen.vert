#version 330
// A quad covering the viewport (a triangle strip of four corners in NDC).
in vec2 corner;

void main() {
    gl_Position = vec4(corner, 0.0, 1.0);
}
