// What the shadow-mask shaders of surface.vert's bodies share, included after their
// #version line (shader_source): surface.vert's outputs, the mask they write, and the
// stencil test moderngl lacks: visible() is false where another body is the visible
// surface (the lit pass's record holds w = body id + 1 there), a pixel the mask shader
// discards. (moderngl expands a quoted name after the include keyword itself, even in
// a comment, from ctx.includes: so no such name is written in a comment here.)
uniform sampler2D surface;  // the lit pass's position record (w = body id + 1)
uniform float body_id;

in vec3 v_world;
in vec3 v_normal;
flat in vec3 v_face_normal;
in vec4 v_stq;

out float mask;

bool visible() {
    return texelFetch(surface, ivec2(gl_FragCoord.xy), 0).w == body_id + 1.0;
}
