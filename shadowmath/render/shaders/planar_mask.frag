#version 330
// Pass 3 into the light's shadow mask (MAX blending, so overlapping flattened
// triangles mark a pixel once), confined to the pixels where the receiver is visible:
// the stencil test of the seeds, done with the lit pass's body-id record.
uniform sampler2D surface;
uniform float body_id;

out float mask;

void main() {
    if (texelFetch(surface, ivec2(gl_FragCoord.xy), 0).w != body_id + 1.0) discard;
    mask = 1.0;
}
