"""Sixteen lights through one shadow atlas (render_atlas: allocate_atlas, fit_atlas) against
the ray caster.

A 12 x 12 floor (it receives, casts nothing) with four boxes and a torus, lit by six point
lights (cube maps: six face tiles each), six spot lights and four suns; 46 tiles in one
atlas. For each light, its rendered shadow mask may differ from the ray caster only in the
band of BAND pixels around the edges of its shadow, of the region it reaches (its front
faces, a spot's cone) and of the bodies, for box kernels of radius 0, 1 and 2. The test can
fail: with a budget too small for every light, the dropped lights' shadows are lost.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import shadowmath as sm
from shadowmath.groundtruth import segment_hits_triangles
from shadowmath.meshes import box, grid, torus
from shadowmath.render import Body, look_at, perspective, render_atlas

from .depth_scenes import BAND, LIFT, Count, Truth, compare
from .scenes import edge_band, place, rotation, world_mesh

SIZE = (240, 180)
ATLAS = 4096
FLOOR = Body(*grid((12.0, 12.0), segments=(1, 1)), color=(0.75, 0.78, 0.8))


def block(x: float, y: float, w: float, d: float, h: float, turn: float) -> Body:
    return Body(*box((w, d, h)), to_world=place(rotation((0, 0, 1), turn), (x, y, h / 2)),
                color=(0.85, 0.6, 0.45))  # fmt: skip


BODIES = [
    FLOOR,
    block(-2.5, -1.5, 1.2, 1.2, 1.5, 20.0),
    block(2.0, -2.0, 1.0, 2.0, 1.0, -15.0),
    block(-2.0, 2.5, 0.8, 0.8, 2.5, 40.0),
    block(2.5, 2.0, 1.5, 1.0, 0.8, 10.0),
    Body(*torus(0.8, 0.25, segments=24, sides=12),
         to_world=place(rotation((1, 0.3, 0), 70), (0, 0, 1.2)), color=(0.9, 0.45, 0.25)),
]  # fmt: skip
CASTS = [False, True, True, True, True, True]


def spot(position: Any, target: Any, angle: float) -> sm.SpotLight:
    p = np.asarray(position, dtype=np.float64)
    return sm.SpotLight(p, np.asarray(target, dtype=np.float64) - p, np.array(angle))


POINTS = [(-4, -4, 3.5), (4, -4, 4), (4, 4, 3), (-4, 4, 4.5), (0, -5, 2.5), (0.5, 0.5, 4.5)]
LIGHTS: list[Any] = [
    *(sm.PointLight(np.asarray(p, dtype=np.float64)) for p in POINTS),
    spot((-5, 0, 5), (-2.5, -1.5, 0.5), 0.5),
    spot((5, 0, 5), (2, -2, 0.5), 0.55),
    spot((0, 5, 6), (-2, 2.5, 1), 0.5),
    spot((0, -6, 5), (0, 0, 1), 0.6),
    spot((5, 5, 5), (2.5, 2, 0.4), 0.5),
    spot((-5, -5, 6), (0, 0, 0), 0.7),
    *(sm.DirectionalLight(np.asarray(d, dtype=np.float64))
      for d in [(1, 1, 2), (-1, 0.5, 1.5), (0.3, -1, 1.2), (-0.6, -0.8, 2.5)]),
]  # fmt: skip
VIEW = look_at((7, -9, 8), (0, 0, 0.5), (0, 0, 1))
PROJECTION = perspective(45.0, SIZE[0] / SIZE[1], 0.5, 50.0)


def render(gl: Any, **kwargs: Any) -> Any:
    kwargs.setdefault("atlas_size", ATLAS)
    kwargs.setdefault("casters", CASTS)
    return render_atlas(BODIES, LIGHTS, VIEW, PROJECTION, image_size=SIZE, ctx=gl, **kwargs)


def truth(frame: Any, light: Any, bodies: Any = BODIES, casts: Any = CASTS) -> Truth:
    """The ray caster's shadow of one light on the frame's visible points: the light reaches
    a point on a face turned toward it (inside a spot's cone), and a caster blocks the
    segment to it (the ray toward a sun)."""
    on = frame.body >= 0
    p = frame.position[on].astype(np.float64)
    n = frame.normal[on].astype(np.float64)
    if isinstance(light, sm.DirectionalLight):
        target = np.append(light.direction, 0.0)
        toward = np.broadcast_to(light.direction, p.shape)
    else:
        target = np.append(light.position, 1.0)
        toward = light.position - p
    reach = np.sum(n * toward, axis=1) > 0
    if isinstance(light, sm.SpotLight):
        axis = light.direction / np.linalg.norm(light.direction)
        reach &= -(toward @ axis) >= np.cos(float(light.angle)) * np.linalg.norm(toward, axis=1)
    blocked = np.zeros(len(p), dtype=bool)
    lit = np.flatnonzero(reach)
    for body, cast in zip(bodies, casts, strict=True):
        if cast:
            blocked[lit] |= segment_hits_triangles(p[lit] + LIFT * n[lit], target,
                                                   *world_mesh(body))  # fmt: skip
    shadow = np.zeros(on.shape, dtype=bool)
    shadow[on] = blocked & reach
    dark = np.zeros(on.shape, dtype=bool)
    dark[on] = blocked | ~reach
    band = edge_band(shadow, BAND) | edge_band(dark, BAND) | edge_band(on, BAND)
    # an edge just outside the picture leaves no change of value inside it
    band[:BAND], band[-BAND:], band[:, :BAND], band[:, -BAND:] = True, True, True, True
    return Truth(on, shadow, band)


def counts(frame: Any) -> list[Count]:
    return [compare(frame.shadow[i] > 0.5, truth(frame, light)) for i, light in enumerate(LIGHTS)]


@pytest.mark.parametrize("pcf_radius", [0, 1, 2])
def test_every_light_agrees_with_the_ray_caster(gl, pcf_radius):
    frame = render(gl, pcf_radius=pcf_radius)
    assert len(frame.atlas.tile_light) == 6 * 6 + 10
    assert (frame.atlas.light_size > 0).all()
    for i, count in enumerate(counts(frame)):
        print(f"light {i} ({type(LIGHTS[i]).__name__}): {count}")
        assert count.shadowed > 300, f"light {i} must cast a sizeable shadow to test anything"
        assert count.differ_off_band == 0, (i, count)


def test_a_budget_that_drops_lights_loses_their_shadows(gl):
    """The test can fail: at 1 % of a 1024² atlas the budget keeps ten lights at the
    smallest tile (16 texels) and drops the last six (spots and suns); their shadows are
    lost off the band."""
    frame = render(gl, atlas_size=1024, budget=0.01)
    dropped = np.flatnonzero(frame.atlas.light_size == 0)
    assert dropped.tolist() == list(range(10, 16))
    result = counts(frame)
    for i in dropped:
        assert result[i].differ == result[i].shadowed, (i, result[i])  # every one lost
        assert result[i].differ_off_band > 0, (i, result[i])
        assert not frame.shadow[i].any()


def test_each_tile_holds_its_own_map(gl):
    """Every 2D tile and some face of every cube light was drawn (a depth below 1), a sun's
    tile kept its border ring of pcf_border_texels(k) texels empty (1.0; a spot's map is
    clipped to its cone, so casters outside the cone may cross its ring), and every texel
    outside the tiles stayed empty: no light drew outside its viewport."""
    frame = render(gl, pcf_radius=2, atlas_size=2048)
    depth, atlas = frame.shadow_map, frame.atlas
    covered = np.zeros(depth.shape, dtype=bool)
    drawn = np.zeros(len(LIGHTS), dtype=bool)
    b = sm.pcf_border_texels(2)
    for t, (x, y, n) in enumerate(atlas.tile_rect):
        tile = depth[y : y + n, x : x + n]
        covered[y : y + n, x : x + n] = True
        light = atlas.tile_light[t]
        drawn[light] |= tile.min() < 1.0
        if not atlas.light_cube[light]:
            assert tile.min() < 1.0, t
        if isinstance(LIGHTS[light], sm.DirectionalLight):
            ring = np.ones((n, n), dtype=bool)
            ring[b:-b, b:-b] = False
            assert (tile[ring] == 1.0).all(), t
    assert drawn.all()
    assert (depth[~covered] == 1.0).all()


def test_the_picture_is_lit_by_every_light(gl):
    """Where a light reaches and nothing shadows, the picture holds its Lambert term: the
    floor's brightness is ambient plus the sum over lights; a light's shadow darkens it."""
    colors = np.zeros((len(LIGHTS), 3))
    colors[6] = 1.0  # only the first spot lights the picture
    frame = render(gl, colors=colors, ambient=0.1, pcf_radius=0)
    floor = frame.body == 0
    reach = truth(frame, LIGHTS[6])
    lit = floor & ~reach.shadow & ~reach.band
    shadowed = floor & reach.shadow & ~reach.band
    p = frame.position[lit].astype(np.float64)
    toward = LIGHTS[6].position - p
    cos = toward[:, 2] / np.linalg.norm(toward, axis=1)  # the floor's normal is +z
    axis = LIGHTS[6].direction / np.linalg.norm(LIGHTS[6].direction)
    inside = -(toward @ axis) >= np.cos(0.5) * np.linalg.norm(toward, axis=1)
    albedo = np.asarray(FLOOR.color)
    expected = albedo * (0.1 + np.where(inside, cos, 0.0))[:, None]
    assert np.allclose(frame.color[lit], expected, atol=2e-3)
    assert shadowed.sum() > 300
    assert np.allclose(frame.color[shadowed], albedo * 0.1, atol=2e-3)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"casters": [False] * 6}, "casters"),
        ({"casters": [True]}, "casters"),
        ({"colors": np.ones((2, 3))}, "colors"),
        ({"normal_offset": -1.0}, "normal_offset"),
        ({"pcf_radius": -1}, "pcf_radius"),
        ({"atlas_size": 1000}, "atlas_size"),
        ({"budget": 0.0}, "budget"),
    ],
)
def test_errors_name_the_argument(gl, kwargs, match):
    with pytest.raises(ValueError, match=match):
        render(gl, **kwargs)


@pytest.mark.parametrize(
    ("light", "match"),
    [
        ((1.0, 2.0, 3.0), "expected an sm.PointLight"),
        (sm.PointLight(np.zeros((2, 3))), "a batch of shape"),
        (sm.DirectionalLight(np.zeros(3)), "the direction nonzero"),
        (sm.PointLight(np.array([np.nan, 1.0, 2.0])), "must be finite"),
    ],
)
def test_a_light_that_is_not_one_light_is_refused(gl, light, match):
    with pytest.raises(ValueError, match=r"lights\[1\]: .*" + match):
        render_atlas(BODIES, [LIGHTS[0], light], VIEW, PROJECTION, ctx=gl)
