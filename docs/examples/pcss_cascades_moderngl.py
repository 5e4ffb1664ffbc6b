"""PCSS cascades with moderngl: a box on a floor under a sun of angular radius 3 degrees,
three cascades fitted to the camera, tiles of one depth atlas.

Run ``python docs/examples/pcss_cascades_moderngl.py`` (the shaders are read from this
folder; the map pass's shaders are pcss_moderngl.py's).
"""

from typing import NamedTuple

import moderngl
import numpy as np
from pcss_moderngl import MAP_FRAGMENT, MAP_VERTEX, lookup_pass
from pcss_scene import CASCADES_PROJECTION, CASCADES_VIEW, TRIANGLES, Vector, normals, shader

import shadowmath as sm

MAX_CASCADES = 4
ANGLE = float(np.radians(3.0))  # the sun's angular radius

LOOKUP_VERTEX = """#version 330
uniform mat4 camera;  // world to the camera's clip space
in vec3 position;
in vec3 normal;
out vec3 v_world;
out vec3 v_normal;
void main() {
    v_world = position;
    v_normal = normal;
    gl_Position = camera * vec4(position, 1.0);
}
"""
LOOKUP_FRAGMENT = (
    "#version 330\n"
    + shader("pcss.glsl")
    + """
const int MAX_CASCADES = 4;
uniform sampler2D shadow_map;  // the atlas: cascade i in tile i
uniform vec3 sun;              // toward the sun
uniform vec4 view_z;           // -view[2]: the view depth d = dot(view_z, (p, 1))
uniform int count;
uniform float splits[MAX_CASCADES + 1];          // cascades.splits
uniform mat4 world_to_texture[MAX_CASCADES];     // cascades.world_to_texture
uniform ivec4 tiles[MAX_CASCADES];               // cascades.viewports as (x0, y0, x1, y1)
uniform vec2 K[MAX_CASCADES];                    // pcss_parameters(cascades) per cascade
uniform float d_near[MAX_CASCADES];
uniform float bias;
in vec3 v_world;
in vec3 v_normal;
out vec4 color;  // rgb the shaded colour, a the lit fraction
void main() {
    float diffuse = max(dot(normalize(v_normal), normalize(sun)), 0.0);
    float d = dot(view_z, vec4(v_world, 1.0));
    float lit = 0.0;  // faces turned from the sun are unlit: no lookup
    if (diffuse > 0.0) {
        lit = 1.0;  // beyond the last cascade: no shadow
        for (int i = 0; i < count; ++i) {
            if (d >= splits[i] && d < splits[i + 1]) {
                vec3 str = (world_to_texture[i] * vec4(v_world, 1.0)).xyz;  // w = 1: a sun
                lit = pcss(shadow_map, tiles[i], str, K[i], d_near[i], bias,
                           pcss_angle(gl_FragCoord.xy));
            }
        }
    }
    color = vec4(vec3(0.15 + 0.85 * diffuse * lit), lit);
}
"""
)


class Picture(NamedTuple):
    color: np.ndarray  # (H, W, 3) the shaded picture, row 0 at the bottom
    lit: np.ndarray  # (H, W) the lit fraction PCSS found (0 off the lit surfaces)
    cascades: sm.Cascades
    parameters: sm.PcssParameters


def padded(values: np.ndarray, shape: int | tuple[int, ...], dtype: str = "f4") -> bytes:
    """``values`` as the first rows of a zero array of ``shape``, as bytes."""
    out = np.zeros(shape, dtype)
    out[: len(values)] = values
    return out.tobytes()


def render(
    ctx: moderngl.Context,
    view: np.ndarray,
    projection: np.ndarray,
    *,
    sun: Vector = (-1.5, 1.0, 1.0),
    angle: float = ANGLE,
    map_size: int = 512,
    size: int = 128,
) -> Picture:
    """The scene through the camera ``projection @ view``, shadowed by PCSS cascades."""
    bounds = np.array([TRIANGLES.min(axis=0), TRIANGLES.max(axis=0)])
    cascades = sm.fit_cascades(sun, view, projection, bounds, map_size, count=3, layout="atlas")
    # Each box widened by tan(angle) (f - n): every blocker of a receiver's search is in
    # its cascade's tile.
    cascades = sm.widen_cascades(cascades, angular_radius=angle)
    pcss = sm.pcss_parameters(cascades, angular_radius=angle)  # K (3, 2), near depth (3,)
    n = len(cascades.viewports)
    x, y, w, h = np.asarray(cascades.viewports).T
    tiles = np.stack([x, y, x + w - 1, y + h - 1], axis=1)
    bias = float(
        sm.slope_scaled_bias(
            cascades.world_to_texture[0],
            TRIANGLES[0],
            [0, 0, 1],
            map_size=map_size,
            slope_factor=0.0,
        )
    )
    vertices = TRIANGLES.astype("f4")
    data = np.hstack([vertices, normals(TRIANGLES)]).astype("f4")

    # Pass 1, the maps: cascade i into tile i of one depth texture, the faces turned from
    # the sun (culled by the sign of det(world_to_clip[i]), as pcss_moderngl.py's).
    shadow_map = ctx.depth_texture(cascades.texture_size)
    shadow_map.filter = (moderngl.NEAREST, moderngl.NEAREST)
    shadow_map.repeat_x = shadow_map.repeat_y = False
    shadow_map.compare_func = ""  # plain depths: moderngl's default compares
    map_fbo = ctx.framebuffer(depth_attachment=shadow_map)
    map_prog = ctx.program(vertex_shader=MAP_VERTEX, fragment_shader=MAP_FRAGMENT)
    map_vao = ctx.vertex_array(map_prog, [(ctx.buffer(vertices), "3f", "position")])
    map_fbo.use()
    map_fbo.clear(depth=1.0)
    ctx.enable(moderngl.DEPTH_TEST | moderngl.CULL_FACE)
    for i in range(n):
        light_clip = np.asarray(cascades.world_to_clip[i])
        map_fbo.viewport = tuple(int(v) for v in cascades.viewports[i])
        map_prog["light_clip"].write(light_clip.T.astype("f4").tobytes())
        ctx.cull_face = "front" if np.linalg.det(light_clip) < 0 else "back"
        map_vao.render()
    ctx.disable(moderngl.CULL_FACE)

    # Pass 2, the lookup: every surface from the camera, in the cascade of its view depth.
    prog = ctx.program(vertex_shader=LOOKUP_VERTEX, fragment_shader=LOOKUP_FRAGMENT)
    prog["camera"].write((projection @ view).T.astype("f4").tobytes())
    prog["sun"].value = tuple(sun)
    prog["view_z"].value = tuple(-view[2])
    prog["count"].value = n
    prog["splits"].write(padded(cascades.splits, MAX_CASCADES + 1))
    matrices = np.asarray(cascades.world_to_texture).transpose(0, 2, 1)  # column-major
    prog["world_to_texture"].write(padded(matrices, (MAX_CASCADES, 4, 4)))
    prog["tiles"].write(padded(tiles, (MAX_CASCADES, 4), "i4"))
    prog["K"].write(padded(pcss.texels_per_depth, (MAX_CASCADES, 2)))
    prog["d_near"].write(padded(pcss.near_depth, MAX_CASCADES))
    prog["bias"].value = bias
    prog["shadow_map"].value = 0
    shadow_map.use(location=0)
    pixels = lookup_pass(ctx, prog, data, size)
    return Picture(pixels[..., :3].copy(), pixels[..., 3].copy(), cascades, pcss)


if __name__ == "__main__":
    context = moderngl.create_standalone_context(backend="egl")
    picture = render(context, CASCADES_VIEW, CASCADES_PROJECTION, size=256)
    print(f"splits {picture.cascades.splits}, lit fraction {picture.lit.mean():.3f}")
