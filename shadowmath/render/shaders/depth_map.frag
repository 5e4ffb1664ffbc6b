#version 330
// Depth only: the rasterizer writes the window depth, biased by the polygon offset.
void main() {
}
