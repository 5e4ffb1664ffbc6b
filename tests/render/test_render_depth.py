"""Williams' shadow z-buffer (method="depth") against the ray caster: every body casts and
receives, so the torus shadows itself and the floor, the box the floor at its contact edges.
Pictures may differ only in a band of BAND pixels around the edges of the shadow and of the
lit region (the terminator), and nowhere off it: no acne at the default bias."""

from __future__ import annotations

import numpy as np
import pytest

from shadowmath import fit_shadow
from shadowmath.meshes import box, grid
from shadowmath.render import Body, Light, render_scene

from .depth_scenes import SCENES, SIZE, DepthScene, _camera, compare, homogeneous, ray_cast
from .scenes import place, rotation, world_mesh

CASES = [(256, 0), (512, 1), (1024, 2)]  # (map size, PCF radius)
MAX_ALL = 0.01  # edges included, at most 1 % of the visible pixels differ


def render(scene, **kwargs):
    *receivers, blocker = scene.bodies
    return render_scene(
        receivers, [blocker], [scene.light], scene.world_to_clip, image_size=SIZE,
        method="depth", **kwargs,
    )  # fmt: skip


@pytest.mark.parametrize(("map_size", "pcf"), CASES)
@pytest.mark.parametrize("name", list(SCENES))
def test_depth_map_agrees_with_ray_caster(gl, name, map_size, pcf):
    scene = SCENES[name]
    frame = render(scene, map_size=map_size, pcf_radius=pcf, ctx=gl)
    truth = ray_cast(frame.body, frame.position, frame.normal, scene)
    count = compare(frame.shadow[..., 0] > 0.5, truth)
    print(f"{name} map {map_size} pcf {pcf}: {count}")
    assert count.shadowed > 600, "the scene must show a sizeable shadow to test anything"
    if name == "torus":
        assert (truth.shadow & (frame.body == 1)).sum() > 30, "the torus must shadow itself"
    assert count.differ_off_band == 0, count
    assert count.differ <= MAX_ALL * truth.on.sum(), count


def test_depth_bias_is_what_prevents_acne(gl):
    """Without the polygon offset, lit surfaces shadow themselves (the test can see acne)."""
    scene = SCENES["torus"]
    frame = render(scene, map_size=512, depth_bias=(0.0, 0.0), ctx=gl)
    truth = ray_cast(frame.body, frame.position, frame.normal, scene)
    assert compare(frame.shadow[..., 0] > 0.5, truth).acne > 100


def test_depth_frame_records_one_map_per_light(gl):
    scene = SCENES["box"]
    frame = render(scene, map_size=(128, 64), ctx=gl)
    assert len(frame.setups[0]) == 1 and len(frame.shadow_maps[0]) == 1
    depth = frame.shadow_maps[0][0]
    assert depth.shape == (64, 128)
    # the floor fills the map inside the far plane, the box is nearer than the floor
    assert depth.min() > 0.0 and depth.max() < 1.0
    assert depth.max() - depth.min() > 0.3


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [({"pcf_radius": -1}, "pcf_radius"), ({"depth_bias": (1.0, float("nan"))}, "depth_bias")],
)
def test_depth_bad_options(gl, kwargs, match):
    with pytest.raises(ValueError, match=match):
        render(SCENES["box"], ctx=gl, **kwargs)


# ---- a large floor of two triangles: receivers as surfaces -------------------------------

GROUND = Body(*grid((60.0, 60.0), segments=(1, 1)), color=(0.7, 0.8, 0.9))  # two triangles
TOWER = Body(*box((0.8, 0.8, 4.0)), to_world=place(rotation((0, 0, 1), 20), (0, 0, 2.0)))
GROUND_LIGHTS = {
    "grazing sun": Light(direction=(1.0, 0.35, 0.22)),
    "high sun": Light(direction=(0.25, -0.2, 1.0)),
    "low point": Light((5.0, 2.0, 4.5)),
    "high point": Light((-1.5, 1.0, 9.0)),
}


@pytest.mark.parametrize("light", list(GROUND_LIGHTS))
def test_a_floor_of_two_large_triangles_keeps_every_shadow(gl, light):
    # The floor's four corners all lie outside the map: as points they count for nothing
    # and the depth range ends behind the tower, losing its shadow on the floor.
    scene = DepthScene(
        [GROUND, TOWER], 1, GROUND_LIGHTS[light], _camera((-6.0, -9.0, 6.0), (-4.0, -1.0, 0.0))
    )
    frame = render(scene, map_size=512, pcf_radius=1, ctx=gl)
    truth = ray_cast(frame.body, frame.position, frame.normal, scene)
    count = compare(frame.shadow[..., 0] > 0.5, truth)
    print(f"{light}: {count}")
    assert count.shadowed > 100, "the tower must cast a sizeable shadow on the floor"
    lost = count.differ_off_band - count.acne  # in shadow, drawn lit, off the band
    assert lost == 0, count
    # Acne (the bias's business, not the depth range's): at most a few pixels under the
    # grazing sun, whose floor has the steepest depth slope.
    assert count.acne <= 0.01 * count.shadowed, count
    # The test can fail: with the corners as points, shadowed floor pixels fall beyond far.
    vertices, triangles = world_mesh(GROUND)
    corners = vertices[triangles].reshape(-1, 3)
    casters = world_mesh(TOWER)[0]
    as_points = fit_shadow(homogeneous(scene.light), casters, 512, receivers=corners)
    on_floor = truth.shadow & (frame.body == 0)
    p = frame.position[on_floor].astype(np.float64)
    tex = np.c_[p, np.ones(len(p))] @ np.asarray(as_points.world_to_texture).T
    assert (tex[:, 2] / tex[:, 3] > 1).sum() > 0.2 * on_floor.sum()
