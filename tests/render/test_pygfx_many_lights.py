"""Twenty lights in one pygfx scene, fitted by one call (fit_scene_shadows), each against the
ray caster.

The scene of test_render_caster_selection (a floor that only receives, four boxes and a
torus; six point lights, ten spot lights, four suns; casters behind spot lights 16 and
18, beside them, crossing the planes of 16 and 17, outside the cones of 18 and 19), and a
fifth box far outside the camera's view (behind it, inside spot 16's cone), as a pygfx
scene: one flat-shaded mesh per body, placed by its world matrix (the torus under a
turned group), ``cast_shadow`` on the boxes and the torus, ``receive_shadow`` on all,
``gfx.PointLight`` / ``gfx.SpotLight`` / ``gfx.DirectionalLight`` with their targets.
``fit_scene_shadows(scene)`` fits the twenty shadow cameras once; then every light is drawn
alone (the others hidden, as in test_pygfx_scene), shadows on and off, and compared with
the ray caster exactly as in test_pygfx: no shadow pixel lost outside the edge band.

pygfx's side, read in its 0.17 source: every light of a kind shares one texture array of
1024 x 1024 depth layers (one layer per sun and spot, six per point light: 50 here) and
one uniform array, so a scene may hold as many shadow-casting lights as the device's
``max_texture_array_layers`` and 64 KiB uniform arrays allow (WebGPU's default limits:
42 point lights, 240 spots, 256 suns); a spot light's ``angle`` is its cone's half-angle
(``cone_cos = cos(angle)``, shadow field of view ``2 angle``), as ``sm.SpotLight``'s.

The comparison can fail: with pygfx's default cameras every sun loses shadow pixels and
the point lights lose those in their +Y cube face; a spot selection that drops the box in
front of light 16 loses that box's shadow. The report's ``casters_used`` per spot lies
within bounds from geometry alone (cone_bounds).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import shadowmath as sm
from shadowmath._fits.shadow import _door, _spot_select
from shadowmath.meshes import box
from shadowmath.render import Body as RenderBody

from .scenes import place, rotation, world_mesh
from .test_pygfx import (  # noqa: F401  (the fixtures, used by name)
    SIZE,
    Body,
    Scene,
    _gl_current_after_pygfx,
    compare,
    flat_mesh,
    gfx,
    ground_truth,
    pygfx_canvas,
    visible_surface,
)
from .test_pygfx_scene import alone
from .test_render_atlas import BODIES as ATLAS_BODIES
from .test_render_atlas import CASTS as ATLAS_CASTS
from .test_render_caster_selection import ALL, losing_box

#: test_render_atlas's viewing camera.
EYE, TARGET = (7.0, -9.0, 8.0), (0.0, 0.0, 0.5)
#: The torus' parent group: its world matrix is the group's times its own.
GROUP = place(rotation((0, 0, 1), 35), (1.0, -0.5, 0.2))
#: A caster far outside the camera's view (behind it), beside no floor: every sun's and
#: point light's fit spans it too.
FAR = RenderBody(*box((1.0, 1.0, 2.0)), to_world=place(translation=(30.0, -30.0, 1.0)))
BODIES, CASTS = [*ATLAS_BODIES, FAR], [*ATLAS_CASTS, True]
#: The casters' triangles: five boxes of 12 and the torus' 24 x 12 quads.
CASTER_TRIANGLES = 5 * 12 + 24 * 12 * 2


def pygfx_light(gfx: Any, light: Any) -> Any:  # noqa: F811 (the fixture's name)
    """The pygfx light that shines as ``light`` does (pygfx's defaults: no fall-off)."""
    if isinstance(light, sm.DirectionalLight):  # from its position toward its target
        lit = gfx.DirectionalLight(intensity=8.0, cast_shadow=True)
        lit.local.position = 10.0 * light.direction / np.linalg.norm(light.direction)
    elif isinstance(light, sm.SpotLight):  # pygfx's angle: the half-angle too
        lit = gfx.SpotLight(intensity=8.0, cast_shadow=True, angle=float(light.angle))
        lit.local.position = light.position
        lit.target.local.position = light.position + light.direction
    else:
        lit = gfx.PointLight(intensity=8.0, cast_shadow=True)
        lit.local.position = light.position
    return lit


def build(gfx: Any) -> tuple[Any, list[Any]]:  # noqa: F811 (the fixture's name)
    """(scene, its twenty lights in ALL's order)."""
    scene, group = gfx.Scene(), gfx.Group()
    group.local.matrix = GROUP
    scene.add(group)
    for body, cast in zip(BODIES, CASTS, strict=True):
        mesh = flat_mesh(np.asarray(body.vertices, float), np.asarray(body.triangles), cast=cast)
        to_world = np.eye(4) if body.to_world is None else np.asarray(body.to_world)
        if body is ATLAS_BODIES[-1]:  # the torus
            mesh.local.matrix = np.linalg.inv(GROUP) @ to_world
            group.add(mesh)
        else:
            mesh.local.matrix = to_world
            scene.add(mesh)
    lights = [pygfx_light(gfx, light) for light in ALL]
    for lit in lights:
        scene.add(lit, *([lit.target] if hasattr(lit, "target") else []))
    return scene, lights


def truth_scene(light: Any) -> Scene:
    """test_pygfx's Scene of one light, for the ray caster (from ALL, not from pygfx)."""
    bodies = [Body(*world_mesh(b), c) for b, c in zip(BODIES, CASTS, strict=True)]
    if isinstance(light, sm.DirectionalLight):
        return Scene(bodies, "directional", light.direction, np.zeros(3), 0.0, EYE, TARGET)
    if isinstance(light, sm.SpotLight):
        aim = light.position + light.direction
        return Scene(bodies, "spot", light.position, aim, float(light.angle), EYE, TARGET)
    return Scene(bodies, "point", light.position, np.zeros(3), 0.0, EYE, TARGET)


def viewer() -> Any:
    import pygfx

    camera = pygfx.PerspectiveCamera(45, SIZE[0] / SIZE[1])
    camera.local.position = EYE
    camera.world.reference_up = (0, 0, 1)
    camera.look_at(TARGET)
    return camera


def drawn(canvas_renderer: Any, scene: Any, lights: list[Any], which: list[int]) -> dict:
    """Light ``i`` of ``which`` drawn alone, and the ray caster's picture of it:
    ``{i: (Picture, Truth)}`` (the camera's rays cast once, for every light)."""
    camera = viewer()
    lit = dict(enumerate(lights))
    result = {}
    surface = None
    for i in which:
        picture = alone(canvas_renderer, scene, camera, lights[i], lit)
        if surface is None:  # the camera's view size is set once drawn
            surface = visible_surface(truth_scene(ALL[i]).bodies, camera)
        result[i] = (picture, ground_truth(truth_scene(ALL[i]), camera, surface))
    return result


@pytest.fixture(scope="module")
def fitted(gfx: Any) -> tuple[Any, list[Any], list[Any]]:  # noqa: F811 (the fixture's name)
    """The scene, its lights and the reports of one fit_scene_shadows call."""
    from shadowmath.integrations.pygfx import fit_scene_shadows

    scene, lights = build(gfx)
    return scene, lights, fit_scene_shadows(scene)


def test_every_light_agrees_with_the_ray_caster(pygfx_canvas, fitted):  # noqa: F811
    scene, lights, _ = fitted
    assert len(lights) >= 20
    result = drawn(pygfx_canvas, scene, lights, list(range(len(lights))))
    for i, (picture, truth) in result.items():
        count, reached = compare(picture, truth), int((truth.reached & truth.on).sum())
        print(f"light {i} ({type(ALL[i]).__name__}): {count}, reached {reached}, "
              f"peak {picture.peak:.2f}")  # fmt: skip
        assert picture.peak < 0.95, "the unshadowed picture must not clip"
        assert reached > 150, (i, reached)  # every light lights a region
        assert count.unreached <= 0.005 * reached, (i, count)
        assert count.lost == 0, (i, count)
        assert count.acne <= 0.005 * count.shadowed, (i, count)
        # every light but 18 and 19 (their casters all behind or beside them) shadows
        assert (count.shadowed > 300) == (i < 18), (i, count)


def test_pygfx_default_cameras_lose_shadow_pixels(gfx, pygfx_canvas):  # noqa: F811
    """The comparison can fail: unfitted, a sun's shadow map is pygfx's 1000 x 1000 box
    (about a texel per world unit, blurred by its 5 x 5 filter): every sun loses shadow
    pixels. A point light's +Y cube face looks down -Z (pygfx 0.17's look_at along its
    up): every shadow pixel whose direction from the light lies in that face (its
    largest component +y) is lost, 500 and more for lights 0 and 4, which lie on the -y
    side of the bodies."""
    scene, lights = build(gfx)
    kinds = [type(light) for light in ALL]
    which = [i for i, k in enumerate(kinds) if k in (sm.PointLight, sm.DirectionalLight)]
    assert len(which) == 10
    for i, (picture, truth) in drawn(pygfx_canvas, scene, lights, which).items():
        count = compare(picture, truth)
        if kinds[i] is sm.DirectionalLight:
            print(f"light {i}, pygfx default: {count}")
            assert count.lost > 0, (i, count)
            continue
        d = np.nan_to_num(truth.points - ALL[i].position)
        up_face = (np.argmax(np.abs(d), axis=-1) == 1) & (d[..., 1] > 0)
        predicted = int((truth.on & truth.reached & ~truth.band & truth.shadow & up_face).sum())
        print(f"light {i}, pygfx default: {count}, {predicted} in the +Y face")
        assert count.lost >= predicted, (i, count, predicted)
        assert (predicted > 500) == (i in (0, 4)), (i, predicted)


def test_a_fit_that_drops_a_caster_loses_its_shadow(gfx, pygfx_canvas, fitted, monkeypatch):  # noqa: F811
    """The comparison can fail: light 16's selection with the box at (2, -2) taken out
    (test_render_caster_selection's losing_box): that box's shadow is lost off the band."""
    from shadowmath.integrations.pygfx import fit_scene_shadows

    monkeypatch.setattr(_door, "spot_selection", losing_box(_spot_select.spot_selection))
    scene, lights = build(gfx)
    reports = fit_scene_shadows(scene)
    assert int(reports[16].fit.casters_used) < int(fitted[2][16].fit.casters_used)
    ((picture, truth),) = drawn(pygfx_canvas, scene, lights, [16]).values()
    count = compare(picture, truth)
    print(f"light 16 without the box: {count}")
    assert count.lost > 100, count


# ---- the report --------------------------------------------------------------------------


def cone_bounds(light: sm.SpotLight, triangles: np.ndarray) -> tuple[int, int]:
    """Bounds on the triangles a spot keeps, from geometry alone: at least those whose
    corners all lie inside its round cone (which lies inside the square pyramid around it,
    whatever its roll), at most those not separated from the round cone of half-angle
    ``beta = atan(sqrt(2) tan a)`` (which holds the pyramid) by a plane through the light:
    its plane (every corner behind it), or one of the cone's tangent planes, normals
    ``cos(beta) w - sin(beta) Z`` for ``w`` every quarter degree around the axis ``Z``
    (the cone lies on their negative side; a triangle with every corner on the positive
    side of one misses it)."""
    axis = light.direction / np.linalg.norm(light.direction)
    off = triangles - light.position  # (M, 3, 3)
    depth = off @ axis
    cos = depth / np.linalg.norm(off, axis=-1)
    inside = np.all((depth > 0) & (cos > np.cos(float(light.angle))), axis=-1)
    x = np.cross(axis, [1.0, 0.0, 0.0] if abs(axis[0]) < 0.9 else [0.0, 1.0, 0.0])
    x /= np.linalg.norm(x)
    phi = np.radians(np.arange(0.0, 360.0, 0.25))[:, None]
    w = np.cos(phi) * x + np.sin(phi) * np.cross(axis, x)
    beta = np.arctan(np.sqrt(2.0) * np.tan(float(light.angle)))
    planes = np.concatenate([np.cos(beta) * w - np.sin(beta) * axis, -axis[None]])
    separated = np.any(np.all(off @ planes.T > 0, axis=1), axis=-1)
    return int(inside.sum()), int((~separated).sum())


def test_the_report_fits_every_light_and_selects_the_spots_casters(fitted):
    """No light skipped; suns use every caster triangle, point lights get their depth
    range, and every spot's count lies within its geometric bounds (cone_bounds): none
    for 18 (every caster behind or beside it) and 19 (every caster outside its narrow
    cone), some but not all for 16 and 17 (a box behind 16, a box crossing 17's plane).

    The counts are of the per-frame path that fits every triangle (``_fit_gathered``,
    what fit_scene_shadows did before its cache): the cached path fits the geometries'
    summaries (the torus' 26-DOP), so its ``casters_used`` counts summary triangles. Of
    the cached path: no light skipped, suns draw every caster object, and spots 18 and
    19 use none (their draw lists, from bounding spheres, may still hold a box beside
    them)."""
    from shadowmath.integrations.pygfx import _fit_gathered, fit_scene_shadows

    scene, lights, cached = fitted
    assert [r.light for r in cached] == lights
    assert [r.skipped for r in cached] == [""] * len(ALL)
    casting = {item for r in cached for d in r.draws for item in d}
    for i, (light, report) in enumerate(zip(ALL, cached, strict=True)):
        if isinstance(light, sm.DirectionalLight):
            assert set(report.draws[0]) == casting, i
        if i in (18, 19):
            assert int(report.fit.casters_used) == 0, i
    reports = _fit_gathered(scene)
    fit_scene_shadows(scene)  # the cached fits back on the lights, for the other tests
    assert [r.light for r in reports] == lights
    assert [r.skipped for r in reports] == [""] * len(ALL)
    world = [world_mesh(b) for b, c in zip(BODIES, CASTS, strict=True) if c]
    triangles = np.concatenate([v[t] for v, t in world])
    assert len(triangles) == CASTER_TRIANGLES
    for i, (light, report) in enumerate(zip(ALL, reports, strict=True)):
        if isinstance(light, sm.PointLight) and not isinstance(light, sm.SpotLight):
            assert isinstance(report.fit, sm.CubeDepthRange), i
        elif isinstance(light, sm.DirectionalLight):
            assert int(report.fit.casters_used) == CASTER_TRIANGLES, i
        else:
            low, high = cone_bounds(light, triangles)
            used = int(report.fit.casters_used)
            print(f"spot {i}: {low} <= {used} <= {high}")
            assert low <= used <= high, (i, low, used, high)
            if i in (18, 19):
                assert high == 0, i
            if i in (16, 17):
                assert low > 0 and high < CASTER_TRIANGLES, (i, low, high)
