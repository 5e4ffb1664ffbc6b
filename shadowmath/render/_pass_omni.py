"""An omnidirectional point light: a real GL cube depth map (six 90-degree faces drawn
with ``cube_face_projection @ cube_face_views[i]``) sampled with ``samplerCubeShadow``."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal

import moderngl
import numpy as np
from numpy.typing import NDArray

from shadowmath import ShadowSetup, cube_face_projection, cube_face_views

from ._context import program, set_matrix, set_uniform
from ._pass_depth import depth_bias_option, draw_depths
from ._resources import GpuScene, Prepared, PreparedLight, ShadowPass

#: The near plane as a fraction of the far plane: bodies nearer the light than this (along
#: a face's axis) are clipped from the map. Window depth keeps ``~2^-24 D^2 / near`` of
#: precision at distance ``D``: about ``1e-4 far`` at the far plane.
OMNI_NEAR_FRACTION = 1e-3

#: Relative slack of the far plane beyond the farthest body vertex.
_FAR_SLACK = 1e-3

#: ``GL_TEXTURE_CUBE_MAP_SEAMLESS`` (OpenGL 3.2, ARB_seamless_cube_map): a global
#: ``glEnable`` state, which moderngl turns on when it creates a context.
GL_TEXTURE_CUBE_MAP_SEAMLESS = 0x884F

#: The comparison filters of the cube map: one texel, or the 2x2 texels around the
#: lookup with their bilinear weights (hardware PCF).
CUBE_FILTERS = {"nearest": moderngl.NEAREST, "linear": moderngl.LINEAR}


def omni_depth_range(
    bodies: Sequence[Prepared], light_position: NDArray[np.float64]
) -> tuple[float, float]:
    """``(near, far)`` of the cube faces: ``far`` just beyond the farthest body vertex along
    any face axis (``max |r_i|``), ``near = OMNI_NEAR_FRACTION * far``."""
    r = np.concatenate([b.world_vertices() for b in bodies]) - light_position
    far = float(np.abs(r).max()) * (1 + _FAR_SLACK)
    if not far > 0:
        raise ValueError("omni: every body vertex lies at the light")
    return OMNI_NEAR_FRACTION * far, far


def face_to_clip(
    light_position: NDArray[np.float64],
    near: float,
    far: float,
    map_size: int,
    border_texels: int = 0,
) -> NDArray[np.float64]:
    """``(6, 4, 4)`` world to each face's OpenGL clip space, faces ``+X, -X, +Y, -Y, +Z, -Z``
    (the index of ``GL_TEXTURE_CUBE_MAP_POSITIVE_X + i``), with a border ring of
    ``border_texels`` (:func:`shadowmath.cube_face_projection`)."""
    views = np.asarray(cube_face_views(light_position), dtype=np.float64)
    proj = cube_face_projection(near, far, map_size=map_size, border_texels=border_texels)
    proj = np.asarray(proj, dtype=np.float64)
    return np.asarray(proj @ views, dtype=np.float64)


def cube_map_side(name: str, map_size: tuple[int, int]) -> int:
    """The side of a square cube face: a cube map's faces are square."""
    if map_size[0] != map_size[1]:
        raise ValueError(f"{name}: cube map faces are square, got {map_size[0]}x{map_size[1]}")
    return map_size[0]


def draw_cube_faces(
    scene: GpuScene,
    world_to_clip: NDArray[np.float64],
    side: int,
    bias: tuple[float, float],
    *,
    back_faces: bool = False,
) -> NDArray[np.float32]:
    """``(6, side, side)`` float32 window depths of every body drawn through each face's
    ``world_to_clip[i]`` with ``glPolygonOffset(*bias)`` (:func:`draw_depths`, with its
    ``back_faces``); row 0 is ``t = 0`` (NDC ``y = -1``), 1 where nothing was drawn."""
    gl = scene.ctx
    face_tex = gl.depth_texture((side, side))
    fbo = gl.framebuffer(depth_attachment=face_tex)
    faces = np.empty((6, side, side), dtype=np.float32)
    try:
        for i in range(6):
            draw_depths(scene, fbo, world_to_clip[i], bias, back_faces=back_faces)
            data = np.frombuffer(face_tex.read(alignment=1), dtype=np.float32)
            faces[i] = data.reshape(side, side)
    finally:
        fbo.release()
        face_tex.release()
    return faces


def draw_cube_depth(
    scene: GpuScene,
    world_to_clip: NDArray[np.float64],
    side: int,
    bias: tuple[float, float],
    texel_filter: int = moderngl.NEAREST,
) -> tuple[moderngl.TextureCube, NDArray[np.float32]]:
    """Every body's depth into the six faces, with ``glPolygonOffset(*bias)``.

    moderngl 5 cannot attach a cube face to a framebuffer, so each face is drawn
    into a 2D depth texture of the same format and copied into face ``i`` of a
    depth cube texture (``TextureCube.write(i, ...)``, i.e.
    ``GL_TEXTURE_CUBE_MAP_POSITIVE_X + i``) unchanged: the face's first row in
    memory is window row 0, NDC ``y = -1``, which the cube-map table reads as
    ``t = 0``. The cube texture compares with ``<=`` (``samplerCubeShadow``),
    filtered with ``texel_filter`` (``moderngl.NEAREST`` or ``LINEAR``, for
    magnification and minification), and is released with the scene.

    Returns:
        the cube texture, and ``(6, side, side)`` float32 window depths (row 0 is ``t = 0``;
        1 where nothing was drawn).
    """
    gl = scene.ctx
    faces = draw_cube_faces(scene, world_to_clip, side, bias)
    cube: moderngl.TextureCube = scene.keep(gl.depth_texture_cube((side, side)))
    for i in range(6):
        cube.write(i, faces[i].tobytes(), alignment=1)
    cube.filter = (texel_filter, texel_filter)
    cube.compare_func = "<="
    return cube, faces


def draw_world_bodies(scene: GpuScene, prog: moderngl.Program) -> None:
    """Every body into the bound mask target through ``prog``, with its ``body_to_world``
    and record (:meth:`bind_record`): a mask pass that looks the light's maps up from
    the world position."""
    for i, (body, mesh) in enumerate(zip(scene.bodies, scene.meshes, strict=True)):
        set_matrix(prog, "body_to_world", body.to_world)
        scene.bind_record(prog, i)
        mesh.render(prog)


def cube_filter_option(name: str, value: object) -> int:
    """A pass's cube-map filter option, checked: ``"nearest"`` or ``"linear"``."""
    if not isinstance(value, str) or value not in CUBE_FILTERS:
        raise ValueError(f"{name}: expected 'nearest' or 'linear', got {value!r}")
    return CUBE_FILTERS[value]


class OmniPass(ShadowPass):
    """``method="omni"``: a point light that shines in every direction, through a cube map.

    Every body casts and receives. The six faces hold the window depth of every
    body drawn with ``cube_face_projection(near, far, map_size) @ cube_face_views(light)[i]``
    and ``glPolygonOffset(*bias)`` (default :func:`depth_bias` ``(0)``); the mask pass
    compares each visible point's window depth (from ``max |r_i|``, ``r = p - light``)
    with ``texture(samplerCubeShadow, vec4(r, depth))``. No :class:`ShadowSetup`
    (``setups[l]`` is empty); ``shadow_maps[l]`` are the six faces' depths.

    ``filter`` is the comparison filter: ``"nearest"`` (the default) compares with one
    texel of the selected face; ``"linear"`` compares with the 2x2 texels around the
    lookup and blends the results (hardware PCF). ``seamless`` enables or disables
    ``GL_TEXTURE_CUBE_MAP_SEAMLESS`` while the mask is drawn (and enables it after, as
    moderngl leaves it when it creates a context). With ``"linear"`` near a face edge,
    seamless filtering takes the texels beyond the edge from the neighbouring face,
    non-seamless filtering stays on the selected face. The neighbour's texels hold
    depths along *its* axis, which can be smaller than the receiver's depth along the
    selected face's axis, so seamless ``"linear"`` puts acne speckles along the seams
    unless the bias covers the difference (``docs/cube-maps.md``, "Sampling the cube
    map"). ``"nearest"`` never leaves the selected face, seamless or not.
    """

    def __init__(
        self,
        bias: tuple[float, float] | None = None,
        *,
        filter: Literal["nearest", "linear"] = "nearest",
        seamless: bool = True,
    ) -> None:
        self.bias = depth_bias_option(bias, 0)
        self.filter = cube_filter_option("filter", filter)
        if not isinstance(seamless, bool):
            raise ValueError(f"seamless: expected a bool, got {seamless!r}")
        self.seamless = seamless

    def check_light(self, light: PreparedLight, map_size: tuple[int, int]) -> None:
        cube_map_side("map_size", map_size)

    def draw_mask(
        self, scene: GpuScene, light: PreparedLight, setups: tuple[ShadowSetup, ...]
    ) -> tuple[NDArray[np.float32], ...]:
        side = cube_map_side("map_size", scene.map_size)
        near, far = omni_depth_range(scene.bodies, light.position)
        cube, faces = draw_cube_depth(
            scene, face_to_clip(light.position, near, far, side), side, self.bias, self.filter
        )
        prog = program(scene.ctx, "surface.vert", "omni_mask.frag")
        set_matrix(prog, "world_to_clip", scene.world_to_clip)
        set_uniform(prog, "cube_map", 0)
        set_uniform(prog, "light_position", tuple(light.position))
        set_uniform(prog, "near", near)
        set_uniform(prog, "far", far)
        scene.bind_mask()
        cube.use(location=0)
        gl = scene.ctx
        if self.seamless:
            gl.enable_direct(GL_TEXTURE_CUBE_MAP_SEAMLESS)
        else:
            gl.disable_direct(GL_TEXTURE_CUBE_MAP_SEAMLESS)
        try:
            draw_world_bodies(scene, prog)
        finally:
            gl.enable_direct(GL_TEXTURE_CUBE_MAP_SEAMLESS)
        return tuple(faces)
