"""Twenty lights sharing every caster, some behind spot lights, beside them, crossing a spot's
plane or outside its cone: each spot's fit selects its casters (render_atlas passes them as
triangles) and every light's shadow mask agrees with the ray caster off the edge band, in
OpenGL (``render_atlas``) and WebGPU (``render_atlas_wgpu``).

The scene of ``test_render_atlas`` (a floor, four boxes, a torus; six point lights, six
spots, four suns) with four more spot lights placed among the casters:

* 16: low between the bodies, aimed at the box at (2, -2): the torus crosses its plane and
  the box at (-2.5, -1.5) lies behind it;
* 17: just above the box at (2.5, 2), aimed sideways at the tall box: that box crosses the
  light's plane, the tall box casts;
* 18: aimed out of the scene, every caster behind or beside it: the empty fit;
* 19: a narrow cone straight down beside the tall box: every caster outside the cone.

The test can fail: a selection that drops the casters of one box in front of light 16 (the
box's triangles moved behind the light) loses its shadow off the band.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import shadowmath as sm
from shadowmath._fits.atlas import _fit_2d as _atlas_2d
from shadowmath._fits.shadow import _spot_select
from shadowmath.render import render_atlas

from .depth_scenes import compare
from .scenes import world_mesh
from .test_render_atlas import (
    BODIES,
    CASTS,
    LIGHTS,
    PROJECTION,
    SCENE,
    SIZE,
    VIEW,
    renderer,
    spot,
    truth,
)  # fmt: skip

EXTRA = [
    spot((0.0, -1.0, 1.0), (3.0, -3.0, 0.0), 0.6),
    spot((2.5, 2.0, 1.3), (-2.0, 2.5, 1.0), 0.45),
    spot((-4.0, 0.0, 1.5), (-5.0, -4.0, 0.0), 0.5),
    spot((0.0, 4.5, 3.0), (0.0, 4.5, 0.0), 0.3),
]
ALL = [*LIGHTS, *EXTRA]
SHADOWING = [16, 17]  # of the extra lights, those whose casters shadow lit points
#: The twenty lights as render_atlas and render_atlas_wgpu take them.
SCENE_ALL = {**SCENE, "lights": ALL, "atlas_size": 4096}


@pytest.fixture(params=["opengl", "webgpu"])
def draw(request: Any) -> Any:
    """The scene rendered by ``render_atlas`` (OpenGL) or ``render_atlas_wgpu`` (WebGPU)."""
    return renderer(request, SCENE_ALL)


def render(gl: Any) -> Any:
    return render_atlas(BODIES, ALL, VIEW, PROJECTION, image_size=SIZE, ctx=gl,
                        atlas_size=4096, casters=CASTS)  # fmt: skip


def counts(frame: Any) -> list[Any]:
    return [compare(frame.shadow[i] > 0.5, truth(frame, light)) for i, light in enumerate(ALL)]


def test_the_scene_has_casters_behind_and_crossing_the_spots() -> None:
    """The extra spots' scenes are what the module says (checked on the casters' vertices)."""
    world = np.concatenate([world_mesh(b)[0] for b, c in zip(BODIES, CASTS, strict=True) if c])
    for i in (16, 17, 18):
        light = ALL[i]
        z = (world - light.position) @ (light.direction / np.linalg.norm(light.direction))
        assert (z < 0).any() and (z > 0).any(), i  # casters on both sides of its plane
    light = ALL[19]
    off = world - light.position
    axis = light.direction / np.linalg.norm(light.direction)
    cos = (off @ axis) / np.linalg.norm(off, axis=1)
    assert (cos < np.cos(0.3)).all()  # every caster vertex outside the narrow cone


def test_every_light_agrees_with_the_ray_caster(draw: Any) -> None:
    frame = draw()
    assert len(ALL) >= 20
    result = counts(frame)
    for i, count in enumerate(result):
        print(f"light {i} ({type(ALL[i]).__name__}): {count}")
        assert count.differ_off_band == 0, (i, count)
    for i in SHADOWING:
        assert result[i].shadowed > 300, (i, result[i])


def losing_box(real: Any) -> Any:
    """``real`` (``spot_selection``) with the box at (2, -2) taken out of light 16's
    casters (its triangles moved behind the light), for one light row ``(8,)`` (fit_shadow)
    or a batch ``(n, 8)`` (fit_atlas); world triangles (no placement)."""

    def losing(ctx: Any, light: Any, up: Any, B: Any, casters: Any, *, triangles: bool) -> Any:
        mine = np.all(np.isclose(light[..., :3], ALL[16].position), axis=-1)
        if triangles and mine.any():
            shape = np.broadcast_shapes(light.shape[:-1], casters.shape[:-3])
            casters = np.broadcast_to(casters, (*shape, *casters.shape[-3:])).copy()
            centre = casters.mean(axis=-2)
            box = np.linalg.norm(centre[..., :2] - [2.0, -2.0], axis=-1) < 1.3
            behind = (light[..., :3] - light[..., 3:6])[..., None, None, :]
            casters = np.where((box & mine[..., None])[..., None, None], behind, casters)
        return real(ctx, light, up, B, casters, triangles=triangles)

    return losing


def test_dropping_a_caster_that_shadows_a_lit_point_loses_pixels(
    gl: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Light 16's selection with the box at (2, -2) taken out (its triangles moved behind
    the light): the box is clipped out of its map and its shadow lost off the band."""
    monkeypatch.setattr(_atlas_2d, "spot_selection", losing_box(_spot_select.spot_selection))
    frame = render(gl)
    lost = compare(frame.shadow[16] > 0.5, truth(frame, ALL[16]))
    assert lost.differ_off_band > 100, lost
    others = counts(frame)
    assert all(c.differ_off_band == 0 for i, c in enumerate(others) if i != 16)


def test_the_fit_reports_no_light_as_failed() -> None:
    a = sm.allocate_atlas(np.ones(len(ALL)), atlas_size=4096, cube=[
        isinstance(light, sm.PointLight) for light in ALL])  # fmt: skip
    tris = np.concatenate(
        [v[t] for v, t in (world_mesh(b) for b, c in zip(BODIES, CASTS, strict=True) if c)]
    )
    fit = sm.fit_atlas(ALL, sm.Triangles(tris), a)
    assert fit.light_errors == (None,) * len(ALL)
