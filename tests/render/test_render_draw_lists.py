"""The reference renderer as a client of sm.ShadowScene: each map drawn from its draw list.

``scene_fit="draw_lists"`` builds a ShadowScene of the bodies (one object each) and draws
into each atlas tile (render_atlas, render_atlas_wgpu) or cascade (render_cascades,
render_cascades_wgpu) only the bodies of its list; ``scene_fit="every_caster"`` draws every
caster into every map with the same scene fit, so the two differ in their draw lists only.

Over three frames of an animated scene (boxes sliding and turning, a torus rolling, a point
light moving; a 16 x 16 floor that receives) lit in one atlas by two point lights (cube
maps), two spots and a sun, and seen through a sun's three cascades:

* the shadow masks drawn from the draw lists equal those drawn with every caster in every
  map, 0 pixels differing, on OpenGL and WebGPU, while the lists cull (some tile's and some
  cascade's list is shorter than the casters). A culled body's sphere lies outside its
  map's clip volume, so its fragments would all be clipped: the maps are equal texel for
  texel, and so is every lookup;
* the draw-list pictures agree with the ray caster off the edge band for every light kind;
* the test can fail: with a culling rule's bound halved (the sphere's radius, monkeypatched
  into ``shadowmath._scene._cull``), the lists drop casters whose shadows are in view and
  the pictures differ.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np
import pytest

import shadowmath as sm
import shadowmath._scene._cull as cull
from shadowmath.meshes import box, grid, torus
from shadowmath.render import Body, Light, look_at, perspective, render_atlas, render_cascades

from .depth_scenes import BAND, DepthScene, compare, ray_cast
from .scenes import place, rotation
from .test_render_atlas import counts, spot

FRAMES = 3
SIZE = (160, 120)
FLOOR = Body(*grid((16.0, 16.0), segments=(1, 1)), color=(0.75, 0.78, 0.8))


def block(x: float, y: float, size: Any, turn: float = 0.0) -> Body:
    """A box of ``size`` (w, d, h) standing on the floor at ``(x, y)``, turned about z."""
    return Body(*box(size), to_world=place(rotation((0, 0, 1), turn), (x, y, size[2] / 2)),
                color=(0.85, 0.6, 0.45))  # fmt: skip


#: A beam a unit in front of the second spot (``lights()[3]``), across its axis: its sphere
#: (radius 1.5) reaches into the cone by more than half its radius, its inner end a third
#: of the way to the axis, so it casts a wide shadow inside the cone; with the radius halved
#: the spot's rule drops it.
BEAM = Body(*box((3.0, 0.2, 0.2)), to_world=place(rotation((0, 0, 1), -121.0),
            (-5.41, -1.74, 4.16)), color=(0.5, 0.5, 0.9))  # fmt: skip


def bodies(frame: int) -> list[Body]:
    """The scene at ``frame``: the floor, five boxes (three moving), a rolling torus and
    the beam."""
    s = 0.6 * frame
    return [
        FLOOR,
        block(-2.5 + s, -1.5, (1.2, 1.2, 1.5), 20.0 + 10.0 * frame),
        block(2.0, -2.0 + s, (1.0, 2.0, 1.0), -15.0),
        block(-2.0, 2.5, (0.8, 0.8, 2.5), 40.0 + 15.0 * frame),
        block(5.5 - s, 4.5, (1.0, 1.0, 1.2)),
        block(-6.0, -5.0 + s, (0.8, 0.8, 1.0)),
        Body(*torus(0.8, 0.25, segments=24, sides=12),
             to_world=place(rotation((1, 0.3, 0), 70.0 + 20.0 * frame), (0.3 * frame, 0, 1.2))),
        BEAM,
    ]  # fmt: skip


#: The atlas: the floor receives only.
CASTS = [False] + [True] * 7


def lights(frame: int) -> list[Any]:
    """Two point lights (the first moving), two spots and a sun."""
    return [
        sm.PointLight(np.array([0.5 + 0.3 * frame, 0.5, 4.5])),
        sm.PointLight(np.array([-4.0, 3.0, 3.0])),
        spot((-3, 6, 6), (-2, 2.5, 0.5), 0.4),
        spot((-5, 0, 5), (-2.5, -1.5, 0.5), 0.4),
        sm.DirectionalLight(np.array([1.0, 0.6, 2.0])),
    ]


VIEW = look_at((8, -11, 10), (0, 0, 0.5), (0, 0, 1))
PROJECTION = perspective(45.0, SIZE[0] / SIZE[1], 0.5, 60.0)
ATLAS: dict[str, Any] = {"casters": CASTS, "atlas_size": 2048, "image_size": SIZE,
                         "pcf_radius": 1}  # fmt: skip

#: The cascades: a sun behind the scene (shadows toward the camera), a camera low over the
#: floor; every body casts and receives.
SUN = Light(direction=(0.0, 1.0, 0.45))
CAMERA = look_at((0, -9, 2.0), (0, 0, 1.0), (0, 0, 1))
CAMERA_PROJECTION = perspective(50.0, SIZE[0] / SIZE[1], 0.3, 40.0)
CASCADES: dict[str, Any] = {"image_size": SIZE, "map_size": 512, "count": 3,
                            "max_distance": 20.0, "pcf_radius": 1}  # fmt: skip


def draw_atlas(api: str, frame: int, scene_fit: str) -> Any:
    if api == "opengl":
        return render_atlas(bodies(frame), lights(frame), VIEW, PROJECTION, scene_fit=scene_fit,
                            **ATLAS)  # fmt: skip
    from shadowmath.render.webgpu import render_atlas_wgpu

    return render_atlas_wgpu(bodies(frame), lights(frame), VIEW, PROJECTION,
                             scene_fit=scene_fit, **ATLAS)  # fmt: skip


def draw_cascades(api: str, frame: int, scene_fit: str) -> Any:
    if api == "opengl":
        return render_cascades(bodies(frame), SUN, CAMERA, CAMERA_PROJECTION,
                               scene_fit=scene_fit, **CASCADES)  # fmt: skip
    from shadowmath.render.webgpu import render_cascades_wgpu

    return render_cascades_wgpu(bodies(frame), SUN, CAMERA, CAMERA_PROJECTION,
                                scene_fit=scene_fit, **CASCADES)  # fmt: skip


@functools.cache
def rendered(kind: str, api: str, frame: int, scene_fit: str) -> Any:
    """One frame of the atlas or the cascades (shared by the tests; never under a mutation)."""
    return (draw_atlas if kind == "atlas" else draw_cascades)(api, frame, scene_fit)


@pytest.fixture(params=["opengl", "webgpu"])
def api(request: Any) -> str:
    request.getfixturevalue("gl" if request.param == "opengl" else "wgpu_device")
    return str(request.param)


def test_the_atlas_draw_lists_draw_the_same_shadows_as_every_caster(api):
    culled = 0
    for frame in range(FRAMES):
        lists = rendered("atlas", api, frame, "draw_lists")
        every = rendered("atlas", api, frame, "every_caster")
        assert np.array_equal(lists.fit.world_to_clip, every.fit.world_to_clip)  # one fit
        casters = np.flatnonzero(CASTS)
        assert all(np.array_equal(d, casters) for d in every.draws)
        assert all(set(d.tolist()) <= set(casters.tolist()) for d in lists.draws)
        culled += sum(len(casters) - len(d) for d in lists.draws)
        texels = int((lists.shadow_map != every.shadow_map).sum())
        differ = [int((lists.shadow[i] != every.shadow[i]).sum()) for i in range(5)]
        print(f"{api} frame {frame}: tiles' lists {[len(d) for d in lists.draws]}, "
              f"{texels} atlas texels differ, mask pixels differ per light {differ}")  # fmt: skip
        assert min(len(d) for d in lists.draws) < len(casters), "the lists must cull"
        assert sum(differ) == 0
    assert culled > 20


def test_the_cascades_draw_lists_draw_the_same_shadows_as_every_caster(api):
    """A culled body lies wholly outside the cascade's map (its window, border included) or
    beyond its far plane: the maps are equal texel for texel, and so are the masks."""
    for frame in range(FRAMES):
        lists = rendered("cascades", api, frame, "draw_lists")
        every = rendered("cascades", api, frame, "every_caster")
        print(f"{api} frame {frame}: cascades' lists {[d.tolist() for d in lists.draws]}")
        assert np.array_equal(lists.cascades.world_to_clip, every.cascades.world_to_clip)
        assert min(len(d) for d in lists.draws) < len(bodies(frame)), "the lists must cull"
        assert np.array_equal(lists.shadow_maps, every.shadow_maps)
        assert int((lists.shadow != every.shadow).sum()) == 0


def test_the_atlas_draw_lists_agree_with_the_ray_caster(api):
    """Each light kind (point lights' cube maps, spots, a sun) of the draw-list atlas against
    the ray caster, off the edge band, every frame."""
    shadowed = np.zeros(5, dtype=int)
    for frame in range(FRAMES):
        result = counts(rendered("atlas", api, frame, "draw_lists"), lights(frame),
                        bodies(frame), CASTS)  # fmt: skip
        for i, count in enumerate(result):
            print(f"{api} frame {frame} light {i}: {count}")
            assert count.differ_off_band == 0, (frame, i, count)
            shadowed[i] += count.shadowed
    assert (shadowed > 300).all(), f"every light must cast a sizeable shadow: {shadowed}"


def test_the_cascades_draw_lists_agree_with_the_ray_caster(api):
    for frame in range(FRAMES):
        picture = rendered("cascades", api, frame, "draw_lists")
        scene = DepthScene(bodies(frame), len(bodies(frame)) - 1, SUN, CAMERA_PROJECTION @ CAMERA)
        truth = ray_cast(picture.body, picture.position, picture.normal, scene)
        border = np.ones(truth.on.shape, dtype=bool)  # an edge just outside the picture
        border[BAND:-BAND, BAND:-BAND] = False
        count = compare(picture.shadow > 0.5, truth._replace(band=truth.band | border))
        used = np.unique(picture.cascade[picture.body >= 0])
        print(f"{api} frame {frame}: {count}, cascades used {used}")
        assert len(used) == 3, "the view must span every cascade"
        assert count.shadowed > 1000
        assert count.differ_off_band == 0, (frame, count)


def _halved(rule: Any) -> Any:
    """``rule`` of :mod:`shadowmath._scene._cull` with every sphere's radius halved (its
    last argument): too aggressive, it drops spheres that reach into the map."""

    def mutant(*args: Any, **kwargs: Any) -> Any:
        return rule(*args[:-1], args[-1] / 2, **kwargs)

    return mutant


@pytest.mark.parametrize(
    ("rule", "kind", "which"),
    [("clip_visible", "atlas", [0, 1]), ("clip_visible", "cascades", None)],
)  # fmt: skip
def test_a_culling_rule_too_aggressive_changes_the_pictures(gl, monkeypatch, rule, kind, which):
    """The test can fail: with the rule's radius halved the draw lists lose casters whose
    shadows are in view, and the draw-list pictures differ from the every-caster ones (both
    drawn under the mutation: the same fit; these rules make only the lists)."""
    monkeypatch.setattr(cull, rule, _halved(getattr(cull, rule)))
    draw = draw_atlas if kind == "atlas" else draw_cascades
    differ = []
    for frame in range(FRAMES):
        lists, every = draw("opengl", frame, "draw_lists"), draw("opengl", frame, "every_caster")
        mask = lists.shadow != every.shadow
        differ.append(int(mask.sum()) if which is None else int(mask[which].sum()))
    print(f"{rule} with its radius halved: {differ} pixels differ per frame")
    assert sum(differ) > 100


def test_a_spot_rule_too_aggressive_loses_the_beams_shadow(gl, monkeypatch):
    """The test can fail: spot_visible decides what a spot's fit reads (the draw lists come
    from the fitted map's clip volume). With its radius halved the second spot's fit no
    longer reads the beam, its map's near plane passes behind the beam, and the beam's
    shadow in the cone is lost: the picture disagrees with the ray caster off the band
    (drawing from the lists or every caster alike: the same map)."""
    monkeypatch.setattr(cull, "spot_visible", _halved(cull.spot_visible))
    lost, same = [], []
    for frame in range(FRAMES):
        lists = draw_atlas("opengl", frame, "draw_lists")
        every = draw_atlas("opengl", frame, "every_caster")
        count = counts(lists, lights(frame), bodies(frame), CASTS)[3]
        lost.append(count.differ_off_band)
        same.append(int((lists.shadow[3] != every.shadow[3]).sum()))
    print(f"spot_visible with its radius halved: {lost} pixels off the band differ from "
          f"the ray caster per frame; {same} from the every-caster picture")  # fmt: skip
    assert same == [0] * FRAMES
    assert min(lost) > 30


def test_pcss_tiles_draw_the_same_from_the_draw_lists(gl):
    """With ``light_size`` (PCSS: the atlas allocated again with the search's border and the
    scene fitted again) the tiles of the point lights and spots drawn from their lists give
    the same masks as every caster."""
    frames = [render_atlas(bodies(1), lights(1)[:4], VIEW, PROJECTION, scene_fit=scene_fit,
                           light_size=[0.2, 0.2, 0.1, 0.1], **ATLAS)
              for scene_fit in ("draw_lists", "every_caster")]  # fmt: skip
    lists, every = frames
    assert lists.atlas.light_border.min() > sm.pcf_border_texels(1)  # allocated again
    assert sum(len(d) for d in lists.draws) < sum(len(d) for d in every.draws)
    assert int((lists.shadow != every.shadow).sum()) == 0


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"scene_fit": "lists"}, "scene_fit: expected None"),
        ({"scene_fit": "draw_lists", "scene_bounds": [[-9, -9, 0], [9, 9, 9]]}, "scene_bounds"),
        ({"scene_fit": "draw_lists", "warp": "lispsm"}, "no warp"),
        ({"scene_fit": "draw_lists", "light_size": 0.01}, "only stable cascades"),
    ],
)
def test_the_cascades_refuse_what_the_draw_lists_do_not_cover(gl, kwargs, match):
    with pytest.raises(ValueError, match=match):
        render_cascades(bodies(0), SUN, CAMERA, CAMERA_PROJECTION, **{**CASCADES, **kwargs})


def test_the_atlas_refuses_an_unknown_scene_fit(gl):
    with pytest.raises(ValueError, match="scene_fit: expected None"):
        render_atlas(bodies(0), lights(0), VIEW, PROJECTION, scene_fit="lists", **ATLAS)
