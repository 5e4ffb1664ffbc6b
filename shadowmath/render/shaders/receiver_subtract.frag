#version 330
// Pass 4, per light (FUNC_REVERSE_SUBTRACT blending: destination minus this): remove
// the light's diffuse contribution where its combined mask says the receiver is in
// shadow. The mask is the MAX of all the light's blockers, so overlapping shadows of
// one light subtract once; each light subtracts only what it added.
uniform sampler2D mask;
uniform sampler2D surface;
uniform float body_id;
uniform vec4 light;  // (x, y, z, 1) a point light, (x, y, z, 0) a directional one
uniform vec3 light_color;
uniform vec3 albedo;

in vec3 v_world;
in vec3 v_normal;
flat in vec3 v_face_normal;
in vec4 v_stq;

out vec4 color;

void main() {
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    if (texelFetch(surface, pixel, 0).w != body_id + 1.0) discard;
    vec3 n = normalize(v_normal);
    float diffuse = max(dot(n, normalize(light.xyz - light.w * v_world)), 0.0);
    color = vec4(albedo * light_color * diffuse * texelFetch(mask, pixel, 0).r, 0.0);
}
