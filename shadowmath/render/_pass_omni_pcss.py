"""Percentage-closer soft shadows of a spherical point light through a cube depth map:
the blocker search and filter of ``pcss.glsl`` in the texture coordinates of the face
that sees each point, with the quantities of :func:`shadowmath.pcss_parameters` of the
cube's :class:`shadowmath.CubeDepthRange` (one ``K`` and ``d_near`` for every face)."""

from __future__ import annotations

import moderngl
import numpy as np
from numpy.typing import NDArray

from shadowmath import (
    CubeDepthRange,
    ShadowSetup,
    Triangles,
    cube_depth_range,
    pcss_border_texels,
    pcss_parameters,
)

from ._context import program, set_matrix, set_uniform
from ._pass_depth import depth_bias_option
from ._pass_omni import OmniPass, cube_map_side, draw_cube_faces, draw_world_bodies, face_to_clip
from ._pass_pcss import PCSS_POLYGON_OFFSET, light_size_option, pcss_uniforms
from ._resources import GpuScene, PreparedLight

#: Window coordinates ``(x, y, z)`` in ``[-1, 1]`` to texture coordinates in ``[0, 1]``.
_CLIP_TO_TEXTURE = np.array(
    [[0.5, 0, 0, 0.5], [0, 0.5, 0, 0.5], [0, 0, 0.5, 0.5], [0, 0, 0, 1]], dtype=np.float64
)


def omni_pcss_range(
    scene: GpuScene, light: PreparedLight, light_size: float, side: int
) -> tuple[CubeDepthRange, int]:
    """The cube's depth range fitted to every body's triangles (every body casts), with
    the border ring :func:`shadowmath.pcss_border_texels` asks for (at most a quarter of
    the face; the refit's ``K`` only shrinks, so the border still holds)."""
    triangles = Triangles(np.concatenate([b.world_vertices()[b.triangles] for b in scene.bodies]))
    first = cube_depth_range(light.position, triangles)
    p = pcss_parameters(first, light_radius=light_size, map_size=side)
    border = min(pcss_border_texels(p), side // 4)
    refit = cube_depth_range(light.position, triangles, map_size=side, border_texels=border)
    return refit, border


def face_array(scene: GpuScene, faces: NDArray[np.float32]) -> moderngl.TextureArray:
    """The six faces' window depths as a float texture array (layer ``i`` face ``i``),
    nearest, clamped to each face's edge: the search reads depths, not comparisons;
    released with the scene."""
    n, h, w = faces.shape
    tex: moderngl.TextureArray = scene.keep(
        scene.ctx.texture_array((w, h, n), 1, faces.tobytes(), dtype="f4")
    )
    tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
    tex.repeat_x = tex.repeat_y = False
    return tex


class OmniPcssPass(OmniPass):
    """``method="omni"`` with ``light_size > 0``: PCSS of a point light of that radius.

    :func:`shadowmath.cube_depth_range` of every body's triangles gives the faces'
    ``near`` and ``far`` (refitted with the border ring of
    :func:`shadowmath.pcss_border_texels`); each face holds the faces turned from the
    light (as ``method="pcss"``'s map), drawn with ``cube_face_projection(near, far,
    map_size, border_texels) @ cube_face_views[i]``. The mask pass picks the face of the
    point's largest component of ``r = p - light`` and runs ``pcss.glsl`` in that face's
    texture coordinates, taps clamped to the face (the border holds the widest search),
    with ``K`` and ``d_near`` of :func:`shadowmath.pcss_parameters` of the range
    (``omni_pcss_mask.frag``). ``shadow_maps[l]`` are the six faces' depths.
    """

    def __init__(self, light_size: float, bias: tuple[float, float] | None = None) -> None:
        self.light_size = light_size_option(light_size)
        self.bias = PCSS_POLYGON_OFFSET if bias is None else depth_bias_option(bias, 0)

    def draw_mask(
        self, scene: GpuScene, light: PreparedLight, setups: tuple[ShadowSetup, ...]
    ) -> tuple[NDArray[np.float32], ...]:
        side = cube_map_side("map_size", scene.map_size)
        depth_range, border = omni_pcss_range(scene, light, self.light_size, side)
        near, far = float(depth_range.near), float(depth_range.far)
        to_clip = face_to_clip(light.position, near, far, side, border)
        faces = draw_cube_faces(scene, to_clip, side, self.bias, back_faces=True)
        params = pcss_parameters(
            depth_range, light_radius=self.light_size, map_size=side, border_texels=border
        )
        uniforms = pcss_uniforms(params)
        prog = program(scene.ctx, "surface.vert", "omni_pcss_mask.frag")
        set_matrix(prog, "world_to_clip", scene.world_to_clip)
        set_matrix(prog, "face_to_texture", _CLIP_TO_TEXTURE @ to_clip)
        set_uniform(prog, "faces", 0)
        set_uniform(prog, "light_position", tuple(light.position))
        set_uniform(prog, "k", uniforms.k)
        set_uniform(prog, "d_near", uniforms.d_near)
        scene.bind_mask()
        face_array(scene, faces).use(location=0)
        draw_world_bodies(scene, prog)
        return tuple(faces)
