#version 330
// The lit pass: ambient plus Lambert diffuse from every light, no shadows yet.
// Also writes the visible surface's world position (w = body id + 1, 0 = background)
// and unit face normal, the per-pixel record the shadow passes and the tests use.
const int MAX_LIGHTS = 8;
uniform int light_count;
uniform vec4 light[MAX_LIGHTS];  // (x, y, z, 1) a point, (x, y, z, 0) toward a direction
uniform vec3 light_color[MAX_LIGHTS];
uniform vec3 albedo;
uniform float ambient;
uniform float body_id;

in vec3 v_world;
in vec3 v_normal;
flat in vec3 v_face_normal;
in vec4 v_stq;

layout(location = 0) out vec4 color;
layout(location = 1) out vec4 position;
layout(location = 2) out vec4 face_normal;

void main() {
    vec3 n = normalize(v_normal);
    vec3 lit = vec3(ambient);
    for (int i = 0; i < light_count; ++i) {
        lit += light_color[i] * max(dot(n, normalize(light[i].xyz - light[i].w * v_world)), 0.0);
    }
    color = vec4(albedo * lit, 1.0);
    position = vec4(v_world, body_id + 1.0);
    face_normal = vec4(normalize(v_face_normal), 0.0);
}
