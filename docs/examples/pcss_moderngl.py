"""PCSS with moderngl: a box on a floor under a point light of radius 0.25.

Run ``python docs/examples/pcss_moderngl.py`` (the shaders are read from this folder).
"""

from typing import NamedTuple

import moderngl
import numpy as np
from pcss_scene import CASTER, TRIANGLES, Vector, look_at, normals, perspective, shader

import shadowmath as sm

MAP_VERTEX = """#version 330
uniform mat4 light_clip;  // world to the light's clip space
in vec3 position;
void main() { gl_Position = light_clip * vec4(position, 1.0); }
"""
MAP_FRAGMENT = "#version 330\nvoid main() {}\n"

LOOKUP_VERTEX = """#version 330
uniform mat4 camera;            // world to the camera's clip space
uniform mat4 world_to_texture;  // fit.world_to_texture
in vec3 position;
in vec3 normal;
out vec3 v_world;
out vec3 v_normal;
out vec4 v_strq;
void main() {
    v_world = position;
    v_normal = normal;
    v_strq = world_to_texture * vec4(position, 1.0);
    gl_Position = camera * vec4(position, 1.0);
}
"""
LOOKUP_FRAGMENT = (
    "#version 330\n"
    + shader("pcss.glsl")
    + """
uniform sampler2D shadow_map;
uniform vec3 light;  // the light's position
uniform vec2 K;
uniform float d_near;
uniform float bias;
in vec3 v_world;
in vec3 v_normal;
in vec4 v_strq;
out vec4 color;  // rgb the shaded colour, a the lit fraction
void main() {
    vec3 to_light = normalize(light - v_world);
    float diffuse = max(dot(normalize(v_normal), to_light), 0.0);
    float lit = 0.0;  // faces turned from the light are unlit: no lookup
    if (diffuse > 0.0) {
        ivec2 size = textureSize(shadow_map, 0);
        vec3 str = v_strq.xyz / v_strq.w;
        lit = pcss(shadow_map, ivec4(0, 0, size - 1), str, K, d_near, bias,
                   pcss_angle(gl_FragCoord.xy));
    }
    color = vec4(vec3(0.15 + 0.85 * diffuse * lit), lit);
}
"""
)


class Picture(NamedTuple):
    color: np.ndarray  # (H, W, 3) the shaded picture, row 0 at the bottom
    lit: np.ndarray  # (H, W) the lit fraction PCSS found (0 off the lit surfaces)
    fit: sm.ShadowSetup
    parameters: sm.PcssParameters


def lookup_pass(
    ctx: moderngl.Context, prog: moderngl.Program, data: np.ndarray, size: int
) -> np.ndarray:
    """The triangles (positions and normals: ``data``) through ``prog`` into a
    ``(size, size, 4)`` float picture with a depth test; row 0 at the bottom."""
    target = ctx.texture((size, size), 4, dtype="f4")
    fbo = ctx.framebuffer([target], ctx.depth_renderbuffer((size, size)))
    vao = ctx.vertex_array(prog, [(ctx.buffer(data), "3f 3f", "position", "normal")])
    fbo.use()
    fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
    vao.render()
    return np.frombuffer(target.read(), "f4").reshape(size, size, 4)


def render(
    ctx: moderngl.Context,
    camera: np.ndarray,
    *,
    light: Vector = (-1.6, 1.4, 4.5),
    radius: float = 0.25,
    map_size: int = 512,
    size: int = 128,
    reversed_z: bool = False,
    mistake: str | None = None,
) -> Picture:
    """The scene seen through ``camera`` (world to clip), shadowed by PCSS (``reversed_z``:
    the map's depth 1 at the near plane); ``mistake`` ``"compare"`` or ``"cull"`` makes
    the docs' two mistakes (for their tests)."""
    receivers = sm.Triangles(TRIANGLES.reshape(-1, 3, 3))
    fit = sm.fit_shadow(light, CASTER, map_size, receivers=receivers, reversed_z=reversed_z)
    border = sm.pcss_border_texels(sm.pcss_parameters(fit, light_radius=radius))
    fit = sm.fit_shadow(
        light, CASTER, map_size, receivers=receivers, border_texels=border, reversed_z=reversed_z
    )
    pcss = sm.pcss_parameters(fit, light_radius=radius)
    world_to_texture = np.asarray(fit.world_to_texture)
    light_clip = np.asarray(fit.blocker_to_clip) @ np.linalg.inv(fit.blocker_to_world)
    # The bias: the map holds the faces turned from the light, so no lit point is
    # compared with its own surface: only the depths' rounding (no slope term).
    bias = float(
        sm.slope_scaled_bias(
            world_to_texture, TRIANGLES[0], [0, 0, 1], map_size=map_size, slope_factor=0.0
        )
    )
    vertices = TRIANGLES.astype("f4")
    data = np.hstack([vertices, normals(TRIANGLES)]).astype("f4")

    # Pass 1, the map: depth only, the faces turned from the light.
    shadow_map = ctx.depth_texture((map_size, map_size))
    shadow_map.filter = (moderngl.NEAREST, moderngl.NEAREST)
    shadow_map.repeat_x = shadow_map.repeat_y = False
    if mistake != "compare":
        shadow_map.compare_func = ""  # plain depths: moderngl's default compares
    map_fbo = ctx.framebuffer(depth_attachment=shadow_map)
    map_prog = ctx.program(vertex_shader=MAP_VERTEX, fragment_shader=MAP_FRAGMENT)
    map_prog["light_clip"].write(light_clip.T.astype("f4").tobytes())
    map_vao = ctx.vertex_array(map_prog, [(ctx.buffer(vertices), "3f", "position")])
    map_fbo.use()
    map_fbo.clear(depth=0.0 if reversed_z else 1.0)
    ctx.depth_func = ">" if reversed_z else "<"
    ctx.enable(moderngl.DEPTH_TEST | moderngl.CULL_FACE)
    # Cull the faces that face the light: GL's front faces (counter-clockwise on the
    # map) where det(light_clip) < 0 (as every projection that looks down -z does),
    # its back faces where det > 0. Reversed Z negates the depth row, and with it the
    # determinant but not the winding: there the other way round.
    sgn = -1.0 if reversed_z else 1.0
    ctx.cull_face = "front" if sgn * np.linalg.det(light_clip) < 0 else "back"
    if mistake == "cull":
        ctx.cull_face = "back" if ctx.cull_face == "front" else "front"
    map_vao.render()
    ctx.disable(moderngl.CULL_FACE)
    ctx.depth_func = "<"

    # Pass 2, the lookup: every surface from the camera.
    prog = ctx.program(vertex_shader=LOOKUP_VERTEX, fragment_shader=LOOKUP_FRAGMENT)
    prog["camera"].write(np.asarray(camera, "f4").T.tobytes())
    prog["world_to_texture"].write(world_to_texture.T.astype("f4").tobytes())
    prog["light"].value = tuple(light)
    prog["K"].value = tuple(pcss.texels_per_depth)
    prog["d_near"].value = float(pcss.near_depth)
    prog["bias"].value = bias
    prog["shadow_map"].value = 0
    shadow_map.use(location=0)
    pixels = lookup_pass(ctx, prog, data, size)
    return Picture(pixels[..., :3].copy(), pixels[..., 3].copy(), fit, pcss)


if __name__ == "__main__":
    context = moderngl.create_standalone_context(backend="egl")
    view = look_at((3.0, -5.0, 4.0), (-0.3, 0.0, 0.3))
    picture = render(context, perspective(45.0, 1.0, 0.5, 30.0) @ view, size=256)
    print(f"K = {picture.parameters.texels_per_depth}, lit fraction {picture.lit.mean():.3f}")
