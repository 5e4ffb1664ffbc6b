#version 330
// Heckbert and Herf's accumulation (glAccum(GL_ACCUM, 1 / count)), with ADD blending:
// add one light sample's hard shadow on the receiver, weighted, into the blocked fraction.
uniform sampler2D coverage;  // 1 where a blocker hides this sample from the texel
uniform float weight;        // 1 / count

out float blocked;

void main() {
    blocked = weight * texelFetch(coverage, ivec2(gl_FragCoord.xy), 0).r;
}
