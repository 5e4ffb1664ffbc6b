"""A whole animated pygfx scene, fitted by one call a frame (fit_scene_shadows), against
the ray caster; and the user's lights, untouched.

Three lights (a sun, a spot, a point light) and four meshes: a floor, a box, a torus
under a moving group, and a second box, each placed by its own world matrix. Every
frame the lights and meshes move as an application would move them (the sun's
``local.position``, the spot's position and target, the lamp's position, the meshes'
matrices), ``fit_scene_shadows(scene)`` fits every light, and pygfx draws. After every
frame each light's settings are exactly those the application set (position, target,
angle, distance, decay, penumbra, intensity, colour) and the direction pygfx lit with
is the one from the application's position to its target. At every frame one light
(sun, spot and point in turn) is drawn alone, shadows on and off, and compared with the
ray caster (shadowmath.groundtruth) exactly as in test_pygfx.py: no shadow pixel lost
outside the edge band.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
import pytest

import shadowmath as sm
from shadowmath.meshes import box, grid, torus

from .scenes import place, rotation
from .test_pygfx import (  # noqa: F401  (the fixtures, used by name)
    SIZE,
    Body,
    Count,
    Picture,
    Scene,
    _gl_current_after_pygfx,
    compare,
    draw,
    flat_mesh,
    gfx,
    ground_truth,
    pygfx_canvas,
)

FRAMES = 9
KINDS = ("directional", "spot", "point")


class Part(NamedTuple):
    mesh: sm.Mesh  # local vertices and triangles (the mesh builders' Mesh)
    cast: bool


PARTS = {
    "floor": Part(grid((12.0, 12.0), segments=(2, 2)), cast=False),
    "box": Part(box((1.2, 1.2, 1.2)), cast=True),
    "torus": Part(torus(0.8, 0.28, segments=24, sides=12), cast=True),
    "post": Part(box((0.4, 0.4, 1.6)), cast=True),
}


def local_matrices(t: float) -> dict[str, np.ndarray]:
    """Each mesh's local matrix at time ``t`` in [0, 1), and the torus' group's."""
    return {
        "floor": place(),
        "box": place(rotation((0, 0, 1), 20 + 30 * t), (-1.5 + t, -0.5, 0.6)),
        "torus": place(rotation((1.0, 0.5, 0.0), 70 + 30 * t), (1.2, 1.0, 1.4)),
        "post": place(rotation((0, 1, 0), 10 * t), (0.5, -2.0, 0.8), scale=1.0 + 0.3 * t),
        "group": place(rotation((0, 0, 1), 40 * t), (0.3 * t, 0.0, 0.0)),
    }


def placements(t: float) -> dict[str, np.ndarray]:
    """Each mesh's world matrix (the torus': its group's times its own)."""
    m = local_matrices(t)
    return {name: m["group"] @ m[name] if name == "torus" else m[name] for name in PARTS}


class Lights(NamedTuple):
    sun: np.ndarray  # the sun's local.position (its target stays at the origin)
    spot: np.ndarray  # the spot's position
    spot_target: np.ndarray
    lamp: np.ndarray  # the point light's position


def lights(t: float) -> Lights:
    a = 2 * np.pi * t
    return Lights(
        sun=np.array([3.0 * np.cos(a), -1.5 + 2 * t, 3.5]),
        spot=np.array([-3.0 + 2 * t, -2.5, 4.0 - t]),
        spot_target=np.array([-0.5 + t, 0.0, 0.5]),
        lamp=np.array([1.0 - 2 * t, 1.5 * np.sin(a), 3.0]),
    )


def build(gfx: Any) -> tuple[Any, dict[str, Any], dict[str, Any], Any]:  # noqa: F811 (the fixtures)
    """(scene, meshes, lights, torus group): flat-shaded grey meshes as test_pygfx's."""
    scene, group = gfx.Scene(), gfx.Group()
    meshes = {}
    for name, part in PARTS.items():
        mesh = flat_mesh(part.mesh.vertices, part.mesh.faces, cast=part.cast)
        meshes[name] = mesh
        (group if name == "torus" else scene).add(mesh)
    sun = gfx.DirectionalLight(intensity=8.0, cast_shadow=True)
    spot = gfx.SpotLight(intensity=8.0, cast_shadow=True, angle=0.75, penumbra=0.0)
    lamp = gfx.PointLight(intensity=8.0, cast_shadow=True, distance=0.0)
    scene.add(group, sun, sun.target, spot, spot.target, lamp)
    return scene, meshes, {"directional": sun, "spot": spot, "point": lamp}, group


def animate(t: float, meshes: dict[str, Any], lit: dict[str, Any], group: Any) -> None:
    """What an application does each frame: move its meshes and lights."""
    m = local_matrices(t)
    group.local.matrix = m["group"]
    for name, mesh in meshes.items():
        mesh.local.matrix = m[name]
    at = lights(t)
    lit["directional"].local.position = at.sun
    lit["spot"].local.position = at.spot
    lit["spot"].target.local.position = at.spot_target
    lit["point"].local.position = at.lamp


def user_state(light: Any) -> dict[str, Any]:
    """Everything the application set on a light (what the integration must not touch)."""
    state = {
        "position": light.local.position.tolist(),
        "world position": light.world.position.tolist(),
        "intensity": light.intensity,
        "color": light.color.hex,
        "cast_shadow": light.cast_shadow,
    }
    if hasattr(light, "target"):
        state["target"] = light.target.local.position.tolist()
    for name in ("angle", "penumbra", "distance", "decay"):
        if hasattr(light, name):
            state[name] = getattr(light, name)
    return state


def truth_scene(t: float, kind: str) -> Scene:
    """The frame's scene as the application set it, for the ray caster: world vertices
    from the matrices above, the lights from the values above (not read from pygfx)."""
    m, at = placements(t), lights(t)
    bodies = []
    for name, part in PARTS.items():
        v = part.mesh.vertices @ m[name][:3, :3].T + m[name][:3, 3]
        bodies.append(Body(v, part.mesh.faces, part.cast))
    eye, target = (3.0, -6.5, 6.0), (0.0, 0.0, 0.5)
    if kind == "directional":  # toward the light: from the target (the origin) to the sun
        return Scene(bodies, kind, at.sun, np.zeros(3), 0.0, eye, target)
    if kind == "spot":
        return Scene(bodies, kind, at.spot, at.spot_target, 0.75, eye, target)
    return Scene(bodies, kind, at.lamp, np.zeros(3), 0.0, eye, target)


def alone(canvas_renderer: Any, scene: Any, camera: Any, light: Any, lit: dict) -> Picture:
    """``light`` drawn alone (the others hidden), shadows on and off."""
    for other in lit.values():
        other.visible = other is light
    shaded = draw(canvas_renderer, scene, camera)
    light.cast_shadow = False
    bare = draw(canvas_renderer, scene, camera)
    light.cast_shadow = True
    for other in lit.values():
        other.visible = True
    return Picture(shaded < 0.5 * bare, bare > 0.01, light, camera, float(bare.max()))


def test_animated_scene_keeps_the_users_lights_and_its_shadows(gfx, pygfx_canvas):  # noqa: F811 (the fixtures)
    from shadowmath.integrations.pygfx import fit_scene_shadows

    scene, meshes, lit, group = build(gfx)
    camera = gfx.PerspectiveCamera(45, SIZE[0] / SIZE[1])
    camera.local.position = truth_scene(0.0, "point").eye
    camera.world.reference_up = (0, 0, 1)
    camera.look_at(truth_scene(0.0, "point").target)
    counts: list[tuple[int, str, Count]] = []
    for frame in range(FRAMES):
        t = frame / FRAMES
        animate(t, meshes, lit, group)
        before = {kind: user_state(light) for kind, light in lit.items()}
        reports = fit_scene_shadows(scene)
        assert [r.skipped for r in reports] == ["", "", ""], reports
        assert {id(r.light) for r in reports} == {id(light) for light in lit.values()}
        draw(pygfx_canvas, scene, camera)  # all three lights, as the application draws
        for kind, light in lit.items():
            assert user_state(light) == before[kind], (frame, kind)
            if kind != "point":  # pygfx lit along the application's position -> target
                d = light.target.world.position - light.world.position
                lit_along = light.uniform_buffer.data["direction"][:3]
                assert np.allclose(lit_along, d / np.linalg.norm(d), atol=1e-6), (frame, kind)
        kind = KINDS[frame % 3]
        picture = alone(pygfx_canvas, scene, camera, lit[kind], lit)
        truth = ground_truth(truth_scene(t, kind), camera)
        count = compare(picture, truth)
        counts.append((frame, kind, count))
        print(f"frame {frame}, {kind}: {count}, peak {picture.peak:.2f}")
        assert picture.peak < 0.95, "the unshadowed picture must not clip"
        assert count.shadowed > 300, (frame, kind, count)
        assert count.unreached <= 0.005 * (truth.reached & truth.on).sum(), (frame, kind, count)
        assert count.lost == 0, (frame, kind, count)
        assert count.acne <= 0.005 * count.shadowed, (frame, kind, count)


def test_gather_scene_places_every_mesh_and_instance(gfx):  # noqa: F811 (the fixtures)
    """gather_scene against the matrices as set: nested groups, an instanced mesh, and
    the flags (a hidden parent hides its children from the shadows too)."""
    from shadowmath.integrations.pygfx import gather_scene

    scene, meshes, lit, group = build(gfx)
    animate(0.4, meshes, lit, group)
    m = placements(0.4)
    quad = grid((1.0, 1.0))
    instanced = gfx.InstancedMesh(
        gfx.Geometry(
            positions=quad.vertices.astype(np.float32), indices=quad.faces.astype(np.int32)
        ),
        gfx.MeshBasicMaterial(),
        2,
    )
    instanced.cast_shadow = True
    shift = place(rotation((1, 0, 0), 90), (0, 0, 5))
    instanced.set_matrix_at(1, shift)
    instanced.local.matrix = m["post"]
    hidden = gfx.Group()
    hidden.visible = False
    ghost = gfx.Mesh(instanced.geometry, gfx.MeshBasicMaterial())
    ghost.cast_shadow = True
    hidden.add(ghost)
    scene.add(instanced, hidden)
    surfaces = gather_scene(scene)

    def corners(mesh: sm.Mesh, matrix: np.ndarray) -> np.ndarray:
        return (mesh.vertices @ matrix[:3, :3].T + matrix[:3, 3])[mesh.faces]

    casters = [corners(PARTS[n].mesh, m[n]) for n in ("box", "post", "torus")]  # scene order
    casters += [corners(quad, m["post"]), corners(quad, m["post"] @ shift)]
    got = surfaces.casters.vertices[surfaces.casters.faces]
    assert np.allclose(got, np.concatenate(casters), atol=1e-5)  # float32 positions
    receivers = [corners(PARTS[n].mesh, m[n]) for n in ("floor", "box", "post", "torus")]
    got = surfaces.receivers.vertices[surfaces.receivers.faces]
    assert np.allclose(got, np.concatenate(receivers), atol=1e-5)


def test_a_light_with_nothing_to_shadow_is_skipped_and_reported(gfx):  # noqa: F811 (the fixtures)
    """A spot light on a caster's corner cannot be fitted (the near plane would be rounding
    noise): it is reported and given back to pygfx's own shadow camera; the sun and the
    lamp beside it are fitted. (A spot inside a box is fitted: to the faces in its cone.)"""
    from shadowmath.integrations.pygfx import fit_scene_shadows

    scene, meshes, lit, group = build(gfx)
    animate(0.0, meshes, lit, group)
    box = meshes["box"]
    lit["spot"].local.position = box.world.position  # inside the box
    inside = {type(r.light).__name__: r for r in fit_scene_shadows(scene)}["SpotLight"]
    assert inside.skipped == "" and int(inside.fit.casters_used) > 0
    corner = box.world.matrix @ np.r_[box.geometry.positions.data[0], 1.0]
    lit["spot"].local.position = corner[:3] / corner[3]  # on the box's corner
    reports = {type(r.light).__name__: r for r in fit_scene_shadows(scene)}
    assert reports["SpotLight"].fit is None
    assert "not strictly in front of the light" in reports["SpotLight"].skipped
    assert reports["DirectionalLight"].skipped == "" and reports["PointLight"].skipped == ""
    fresh = gfx.SpotLight(angle=0.75)
    fresh.local.position = lit["spot"].local.position
    fresh.target.local.position = lit["spot"].target.local.position
    for light in (lit["spot"], fresh):
        light.shadow._gfx_update_uniform_buffer(light)
    assert np.allclose(lit["spot"].shadow.camera.camera_matrix, fresh.shadow.camera.camera_matrix)
    for mesh in meshes.values():  # nothing casts: every light reported, none raises
        mesh.cast_shadow = False
    reports = fit_scene_shadows(scene)
    assert [r.skipped for r in reports] == ["the scene has no visible mesh with cast_shadow"] * 3
    with pytest.raises(ValueError, match=r"pcf_radius: expected an integer >= 0, got 1\.5"):
        fit_scene_shadows(scene, pcf_radius=1.5)
    meshes["floor"].geometry.positions.data[0] = np.nan
    with pytest.raises(ValueError, match=r"meshes\[0\].vertices: contains non-finite"):
        fit_scene_shadows(scene)


def test_a_headlight_is_fitted_along_the_camera(gfx):  # noqa: F811 (the fixtures)
    """A sun parented to the viewing camera (pygfx lights along the camera's view, not
    toward its target): its shadow camera looks the way pygfx lights."""
    from shadowmath.integrations.pygfx import fit_scene_shadows

    scene, meshes, lit, group = build(gfx)
    animate(0.3, meshes, lit, group)
    for light in lit.values():
        light.cast_shadow = False
    camera = gfx.PerspectiveCamera(45)
    camera.local.position = (2.0, -6.0, 7.0)
    camera.look_at((1.0, 2.0, 0.0))  # not at the light's target, the origin
    headlight = gfx.DirectionalLight(cast_shadow=True)
    camera.add(headlight)
    scene.add(camera)
    (report,) = fit_scene_shadows(scene)
    assert report.light is headlight and report.skipped == ""
    headlight._gfx_update_uniform_buffer()
    headlight.shadow._gfx_update_uniform_buffer(headlight)
    lit_along = headlight.uniform_buffer.data["direction"][:3]
    assert np.allclose(lit_along, camera.world.forward, atol=1e-6)
    assert np.allclose(headlight.shadow.camera.world.forward, lit_along, atol=1e-6)
