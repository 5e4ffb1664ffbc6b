"""The sixteen lights of test_render_atlas through one shadow atlas on WebGPU
(render_atlas_wgpu: fit_atlas with api="webgpu", shaders/atlas.wgsl), beyond the tests that
test_render_atlas runs on both APIs (every light against the ray caster, a budget that
drops lights, each tile its own map): without the pipeline's depth bias and the normal
offset the casters shadow themselves; OpenGL (render_atlas) and WebGPU agree pixel for
pixel off the band, and their atlases hold the same depths (2D tiles upside down).
"""

from __future__ import annotations

import numpy as np
import pytest

from .test_render_atlas import LIGHTS, counts, render, render_wgpu, truth


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


def test_errors_name_the_argument(wgpu_device):
    with pytest.raises(ValueError, match="casters"):
        render_wgpu(casters=[False] * 6)
    with pytest.raises(ValueError, match=r"lights\[1\]: .*expected an sm.PointLight"):
        render_wgpu(lights=[LIGHTS[0], (1.0, 2.0, 3.0)])
