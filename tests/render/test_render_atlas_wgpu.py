"""The sixteen lights of test_render_atlas through one shadow atlas on WebGPU
(render_atlas_wgpu: fit_atlas with api="webgpu", shaders/atlas.wgsl) against the ray caster.

The same scene, lights and camera as the OpenGL tests: for each light, its shadow mask may
differ from the ray caster only in the band of BAND pixels around the edges of its shadow,
of the region it reaches and of the bodies, for box kernels of radius 0, 1 and 2. The test
can fail: with a budget too small for every light, the dropped lights' shadows are lost;
without the pipeline's depth bias and the normal offset the casters shadow themselves.
OpenGL (render_atlas) and WebGPU agree pixel for pixel off the band, and each WebGPU tile
holds OpenGL's map upside down.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from .test_render_atlas import (
    ATLAS,
    BODIES,
    CASTS,
    LIGHTS,
    PROJECTION,
    SIZE,
    VIEW,
    counts,
    render,
    truth,
)


def render_wgpu(lights: Any = LIGHTS, **kwargs: Any) -> Any:
    """``render_atlas_wgpu`` of the scene (imported here: wgpu is an optional extra)."""
    from shadowmath.render.webgpu import render_atlas_wgpu

    kwargs.setdefault("atlas_size", ATLAS)
    kwargs.setdefault("casters", CASTS)
    return render_atlas_wgpu(BODIES, lights, VIEW, PROJECTION, image_size=SIZE, **kwargs)


@pytest.mark.parametrize("pcf_radius", [0, 1, 2])
def test_every_light_agrees_with_the_ray_caster(wgpu_device, pcf_radius):
    frame = render_wgpu(pcf_radius=pcf_radius)
    assert len(frame.atlas.tile_light) == 6 * 6 + 10
    assert (frame.atlas.light_size > 0).all()
    for i, count in enumerate(counts(frame)):
        print(f"{frame.adapter}, light {i} ({type(LIGHTS[i]).__name__}): {count}")
        assert count.shadowed > 300, f"light {i} must cast a sizeable shadow to test anything"
        assert count.differ_off_band == 0, (i, count)


def test_a_budget_that_drops_lights_loses_their_shadows(wgpu_device):
    """The test can fail: at 1 % of a 1024² atlas the last six lights (spots and suns) are
    dropped; their shadows are lost off the band while the ten kept lights' hold."""
    frame = render_wgpu(atlas_size=1024, budget=0.01)
    dropped = np.flatnonzero(frame.atlas.light_size == 0)
    assert dropped.tolist() == list(range(10, 16))
    result = counts(frame)
    for i in dropped:
        assert result[i].differ == result[i].shadowed, (i, result[i])  # every one lost
        assert result[i].differ_off_band > 0, (i, result[i])
        assert not frame.shadow[i].any()


def test_without_bias_the_casters_shadow_themselves(wgpu_device):
    """The test can fail: with no polygon offset in the pipeline and no normal offset, the
    casters' lit faces compare with their own depths and shadow themselves (acne) off the
    band, for every light."""
    frame = render_wgpu(pcf_radius=1, depth_bias=(0.0, 0.0), normal_offset=0.0)
    acne = [count.acne for count in counts(frame)]
    print(f"{frame.adapter}: acne per light {acne}")
    assert min(acne) > 0
    assert sum(acne) > 1000


def test_webgpu_agrees_with_opengl(gl, wgpu_device):
    """The same pixels show the same points and shadows in both APIs, light by light. Each
    WebGPU 2D tile is OpenGL's upside down (t = 0 is the first row in memory in both: the
    top of the light's view in WebGPU, its bottom in OpenGL); a cube face's tile is the same
    image (fit_atlas flips a face's clip y in WebGPU, keeping the cube map's layout), but
    for texels whose centre lies on an edge (the rasterizers' tie rules)."""
    web, ogl = render_wgpu(pcf_radius=1), render(gl, pcf_radius=1)
    assert np.array_equal(web.body, ogl.body)
    np.testing.assert_allclose(web.position, ogl.position, atol=1e-3)
    assert np.array_equal(web.atlas.tile_rect, ogl.atlas.tile_rect)
    for i, light in enumerate(LIGHTS):
        band = truth(web, light).band
        assert (((web.shadow[i] > 0.5) != (ogl.shadow[i] > 0.5)) & ~band).sum() == 0, i
    flipped = np.ones_like(web.shadow_map)
    for (x, y, n), light in zip(web.atlas.tile_rect, web.atlas.tile_light, strict=True):
        tile = web.shadow_map[y : y + n, x : x + n]
        flipped[y : y + n, x : x + n] = tile if web.atlas.light_cube[light] else tile[::-1]
    error = np.abs(flipped - ogl.shadow_map)
    print(f"{web.adapter}: {int((error > 1e-4).sum())} of {error.size} depth texels differ")
    assert (error > 1e-4).sum() <= 0.001 * error.size
    assert float(np.abs(web.shadow_map - ogl.shadow_map).max()) > 0.1  # a real flip


def test_each_tile_holds_its_own_map(wgpu_device):
    """Every 2D tile and some face of every cube light was drawn, and every texel outside the
    tiles stayed empty (1.0): the viewports and scissor rects keep each light in its tile."""
    frame = render_wgpu(pcf_radius=2, atlas_size=2048)
    depth, atlas = frame.shadow_map, frame.atlas
    covered = np.zeros(depth.shape, dtype=bool)
    drawn = np.zeros(len(LIGHTS), dtype=bool)
    for t, (x, y, n) in enumerate(atlas.tile_rect):
        covered[y : y + n, x : x + n] = True
        drawn[atlas.tile_light[t]] |= depth[y : y + n, x : x + n].min() < 1.0
    assert drawn.all()
    assert (depth[~covered] == 1.0).all()


def test_errors_name_the_argument(wgpu_device):
    with pytest.raises(ValueError, match="casters"):
        render_wgpu(casters=[False] * 6)
    with pytest.raises(ValueError, match=r"lights\[1\]: .*expected an sm.PointLight"):
        render_wgpu([LIGHTS[0], (1.0, 2.0, 3.0)])
