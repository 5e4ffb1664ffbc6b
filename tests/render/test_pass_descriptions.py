"""The pass descriptions that the moderngl and WebGPU passes both read: their packed
layouts agree with what the shaders declare and index."""

from __future__ import annotations

import numpy as np

import shadowmath as sm
from shadowmath.meshes import box, grid
from shadowmath.render import Body, Light, look_at, perspective
from shadowmath.render._atlas_pass import describe_atlas
from shadowmath.render._cascade_pass import FRAME_DTYPE, cascade_options, describe_cascades
from shadowmath.render._context import program, shader_source
from shadowmath.render._shader_constants import SHADER_CONSTANTS


def _bodies() -> list[Body]:
    cube = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 1], [0, 0, 0, 1.0]])
    return [Body(*grid((20.0, 20.0), segments=(1, 1))), Body(*box((2.0, 2.0, 2.0)), to_world=cube)]


def test_the_cascades_block_is_the_glsl_std140_block(gl):
    """``cascades.frag``'s ``Frame`` block, laid out by the driver (std140), has the size
    of :data:`FRAME_DTYPE`: a field added to one and not the other, or a member whose
    std140 alignment differs from the dtype's offsets, changes it."""
    block = program(gl, "surface.vert", "cascades.frag")["Frame"]
    assert block.size == FRAME_DTYPE.itemsize


def test_the_cascades_block_holds_the_fit():
    """Each cascade's record holds its matrix column-major, its split interval and band."""
    view = look_at([0, -12, 3], [0, 0, 1], [0, 0, 1])
    options = cascade_options(layout="atlas", pcf_radius=1, depth_bias=None, normal_offset=1.0)
    keywords = {"scene_bounds": None, "map_size": 256, "count": 3, "splits": None}
    for api in ("opengl", "webgpu"):
        described = describe_cascades(_bodies(), Light(direction=(1, 1, 2)), view,
                                      perspective(50.0, 1.0, 0.5, 60.0), options=options,
                                      fit_options=keywords, api=api)  # fmt: skip
        fit, frame = described.fit, described.frame
        cascades = frame["cascades"]
        assert int(frame["count"]) == 3 and len(frame.tobytes()) == FRAME_DTYPE.itemsize
        for i in range(3):
            column_major = np.frombuffer(sm.column_major_bytes(fit.world_to_texture[i]), np.float32)
            assert np.array_equal(cascades["world_to_texture"][i].ravel(), column_major)
            assert cascades["near"][i] == np.float32(fit.splits[i])
            assert cascades["far"][i] == np.float32(fit.splits[i + 1])
            assert np.array_equal(cascades["viewport"][i], fit.viewports[i])
            assert cascades["band_end"][i] == np.float32(fit.band_end[i])
        assert set(cascades[3:].tobytes()) == {0}  # zero past count


def test_the_atlas_tables_hold_what_the_shaders_index():
    """The tiles' rows 0..3 are ``world_to_texture`` column-major, row 4 the tile's rect;
    a light's face ``f`` tile stands at row ``4 + f // 4``, component ``f % 4`` (both
    shaders' indexing), ``-1`` where the light has no such face."""
    lights = [sm.PointLight(np.array([3.0, 0.0, 4.0])), sm.DirectionalLight(np.array([1, 1, 2.0]))]
    described = describe_atlas(
        _bodies(), lights, look_at([0, -12, 8], [0, 0, 0], [0, 0, 1]),
        perspective(50.0, 1.0, 0.5, 50.0), casters=[False, True], colors=None, coverage=None,
        atlas_size=512, budget=1.0, previous=None, pcf_radius=1, depth_bias=None,
        normal_offset=0.5,
    )  # fmt: skip
    atlas, fit = described.atlas, described.fit
    for t in range(len(atlas.tile_rect)):
        assert np.array_equal(described.tiles[t, :4].T, fit.world_to_texture[t].astype(np.float32))
        assert np.array_equal(described.tiles[t, 4, :3], atlas.tile_rect[t])
    for light in range(len(lights)):
        for face in range(6):
            stored = described.lights[light, 4 + face // 4, face % 4]
            assert stored == atlas.light_tiles[light, face]
    assert described.lights[0, 3, 0] == 1.0 and described.lights[1, 3, 0] == 0.0  # cube


def test_both_languages_take_the_same_constants():
    """Every shared constant reaches the GLSL and the WGSL PCSS code with one value."""
    glsl, wgsl = shader_source("pcss_mask.frag"), shader_source("pcss_scene.wgsl")
    for name, value in SHADER_CONSTANTS.items():
        text = str(value) if isinstance(value, int) else repr(float(value))
        assert f" {name} = {text};" in glsl
        assert f"{name}: " in wgsl and f" = {text};" in wgsl
        assert glsl.count(f" {name} = ") == 1  # included once
