"""The depth-map scenes on a second real graphics API: WebGPU (wgpu over Vulkan), with
WebGPU's conventions (clip depth 0..w, texture origin top-left) from api_convention. The
picture must agree with the ray caster as the OpenGL one does, and with the OpenGL one."""

from __future__ import annotations

import numpy as np
import pytest

from shadowmath.render import render_scene

from .depth_scenes import SCENES, SIZE, compare, ray_cast
from .rasterization import same_bodies_but_on_edges

CASES = [(256, 0), (512, 1)]  # (map size, PCF radius)
MAX_ALL = 0.01


@pytest.mark.parametrize(("map_size", "pcf"), CASES)
@pytest.mark.parametrize("name", list(SCENES))
def test_wgpu_depth_map_agrees_with_ray_caster_and_opengl(gl, wgpu_device, name, map_size, pcf):
    from shadowmath.render.webgpu import render_depth_wgpu

    scene = SCENES[name]
    *receivers, blocker = scene.bodies
    args = (receivers, [blocker])
    kwargs = {"image_size": SIZE, "map_size": map_size, "pcf_radius": pcf}
    web = render_depth_wgpu(*args, scene.light, scene.world_to_clip, **kwargs)
    ogl = render_scene(*args, [scene.light], scene.world_to_clip, method="depth", ctx=gl, **kwargs)
    truth = ray_cast(web.body, web.position, web.normal, scene)
    count = compare(web.shadow > 0.5, truth)
    # The same pixels show the same bodies at the same points in both APIs.
    same = same_bodies_but_on_edges(web.body, ogl.body)
    np.testing.assert_allclose(web.position[same], ogl.position[same], atol=1e-4)
    differ = int(((web.shadow > 0.5) != (ogl.shadow[..., 0] > 0.5)).sum())
    # WebGPU's map: row 0 is t = 0, the top of the light's view; OpenGL's row 0 is the bottom.
    # A texel whose centre lies exactly on an edge may go either way (the rasterizers' tie
    # rules meet a flipped y), nothing more.
    depth_error = np.abs(web.depth_map[::-1] - ogl.shadow_maps[0][0])
    texels = int((depth_error > 1e-4).sum())
    print(f"{web.adapter}: {name} map {map_size} pcf {pcf}: {count}, {differ} pixels differ "
          f"from OpenGL, {texels} depth texels differ by > 1e-4, the others within "
          f"{np.median(depth_error):.1e} (median)")  # fmt: skip
    assert count.shadowed > 600
    assert count.differ_off_band == 0, count
    assert count.differ <= MAX_ALL * truth.on.sum(), count
    assert differ <= 0.001 * truth.on.sum()
    assert texels <= 0.001 * depth_error.size
    assert float(np.abs(web.depth_map - ogl.shadow_maps[0][0]).max()) > 0.1  # a real flip


def test_wgpu_reports_an_adapter(wgpu_device):
    from shadowmath.render.webgpu import adapter_description

    description = adapter_description()
    print(f"WebGPU adapter: {description}")
    assert description
