#version 330
// Flat colour: 1 where the blocker covers the texel centre, the cleared 0 elsewhere.
out float coverage;

void main() {
    coverage = 1.0;
}
