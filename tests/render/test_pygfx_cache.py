"""fit_scene_shadows' cache (a ShadowScene kept per pygfx scene): invalidation, instances
culled one by one, and agreement with the per-frame path that fits every triangle
(``_fit_gathered``). Nothing is drawn: these need pygfx, not a wgpu adapter."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import shadowmath as sm

from .test_pygfx import gfx  # noqa: F401  (the fixture, used by name)


def lit_scene(gfx: Any, meshes: list[Any]) -> tuple[Any, list[Any]]:  # noqa: F811
    """A 20 x 20 floor that receives, ``meshes``, and a sun, two spots and a point light."""
    scene = gfx.Scene()
    floor = gfx.Mesh(gfx.plane_geometry(20, 20), gfx.MeshPhongMaterial())
    floor.receive_shadow = True
    scene.add(floor, *meshes)
    sun = gfx.DirectionalLight(cast_shadow=True)
    sun.local.position = (2.0, -1.0, 6.0)
    spots = [gfx.SpotLight(cast_shadow=True, angle=a) for a in (0.6, 0.35)]
    spots[0].local.position = (0.5, -0.5, 7.0)
    spots[1].local.position = (-3.0, 2.0, 5.0)
    spots[1].target.local.position = (-2.0, 1.0, 0.0)
    lamp = gfx.PointLight(cast_shadow=True)
    lamp.local.position = (1.0, 1.5, 3.5)
    scene.add(sun, sun.target, *[x for s in spots for x in (s, s.target)], lamp)
    return scene, [sun, *spots, lamp]


def caster(gfx: Any, geometry: Any, position: tuple[float, ...], turn: float = 0.0) -> Any:  # noqa: F811
    mesh = gfx.Mesh(geometry, gfx.MeshPhongMaterial())
    mesh.cast_shadow = mesh.receive_shadow = True
    mesh.local.position = position
    mesh.local.euler_z = turn
    return mesh


def fields(fit: Any) -> list[np.ndarray]:
    """Every float field of a ShadowSetup or CubeDepthRange, flattened."""
    out = []
    for value in fit:
        parts = value if isinstance(value, tuple) else (value,)
        for part in parts:
            a = np.asarray(part)
            if np.issubdtype(a.dtype, np.floating):
                out.append(a.ravel())
    return out


def assert_holds(gfx: Any, report: Any, casters: np.ndarray) -> None:  # noqa: F811
    """Every caster vertex a light reaches lies in its fitted map: in a spot light's cone
    (the lit points' segments to the light stay in it), anywhere for a sun; inside the
    window and the depth range (WebGPU's ``0 <= z <= 1``); for a point light, every
    caster's depth ``max |p - L|`` in ``[near, far]``."""
    fit = report.fit
    assert report.skipped == "" and fit is not None
    if isinstance(fit, sm.CubeDepthRange):
        D = np.max(np.abs(casters - np.asarray(report.light.world.position)), axis=1)
        assert float(fit.near) <= D.min() and D.max() <= float(fit.far)
        return
    clip = np.c_[casters, np.ones(len(casters))] @ np.asarray(fit.blocker_to_clip).T
    if isinstance(report.light, gfx.SpotLight):
        axis = np.asarray(report.light.target.world.position) - report.light.world.position
        rel = casters - np.asarray(report.light.world.position)
        cos = rel @ axis / np.linalg.norm(rel, axis=1) / np.linalg.norm(axis)
        clip = clip[cos > np.cos(float(report.light.angle))]
        assert len(clip) > 0
    ndc = clip[:, :3] / clip[:, 3:]
    tol = 1e-6
    assert np.all(np.abs(ndc[:, :2]) <= 1 + tol), report.light
    assert np.all((ndc[:, 2] >= -tol) & (ndc[:, 2] <= 1 + tol)), report.light


def test_boxes_fit_as_every_triangle(gfx):  # noqa: F811
    """Boxes' summaries are their own 12 triangles: the sun's fit and the point light's
    depth range equal the per-frame path's to 1e-9 relative (plain boxes, one under a
    turned group, and an instanced one), frame after frame as they move, and the sun
    draws every caster. A spot's map holds every caster vertex in its cone; it may be
    smaller than the per-frame path's, which also keeps casters in the corners of the
    square pyramid around the cone (they shadow no lit point: the culling drops them)."""
    from shadowmath.integrations.pygfx import _fit_gathered, fit_scene_shadows, gather_scene

    geometry = gfx.box_geometry(1.0, 0.8, 0.6)
    boxes = [caster(gfx, geometry, (x, y, 0.8), t) for x, y, t in
             ((0.0, 0.0, 0.3), (2.0, 1.0, 1.1), (-2.0, 1.5, 0.0))]  # fmt: skip
    group = gfx.Group()
    group.local.euler_x = 0.4
    group.add(caster(gfx, gfx.box_geometry(0.5, 0.5, 1.5), (1.0, -2.0, 1.2)))
    many = gfx.InstancedMesh(geometry, gfx.MeshPhongMaterial(), 3)
    many.cast_shadow = True
    for k in range(3):
        m = np.eye(4)
        m[:3, 3] = (-1.0 + k, -1.5, 0.5 + 0.3 * k)
        many.set_matrix_at(k, m)
    scene, _ = lit_scene(gfx, [*boxes, group, many])
    for frame in range(3):
        boxes[0].local.position = (0.3 * frame, 0.0, 0.8)
        group.local.euler_z = 0.2 * frame
        cached, old = fit_scene_shadows(scene), _fit_gathered(scene)
        assert [r.skipped for r in cached] == [""] * 4 == [r.skipped for r in old]
        casters = gather_scene(scene).casters.vertices
        for new, ref in zip(cached, old, strict=True):
            assert type(new.fit) is type(ref.fit)
            assert_holds(gfx, new, casters)
            if isinstance(new.light, gfx.SpotLight):
                continue
            for a, b in zip(fields(new.fit), fields(ref.fit), strict=True):
                scale = max(float(np.max(np.abs(b), initial=0.0)), 1.0)
                np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-9 * scale)
        assert len(cached[0].draws[0]) == len(boxes) + 1 + 3  # the sun draws every caster


def test_the_fitted_maps_hold_every_caster(gfx):  # noqa: F811
    """Spheres and torus knots (summarized by their 26-DOP): every caster vertex in a spot
    light's cone projects inside its fitted map (and depth range), and every caster vertex
    lies in the sun's; the point light's range holds every caster's depth."""
    from shadowmath.integrations.pygfx import fit_scene_shadows, gather_scene

    ball, knot = gfx.sphere_geometry(0.5, 32, 16), gfx.torus_knot_geometry(0.6, 0.2)
    meshes = [caster(gfx, g, (x, y, 1.0), t) for g, x, y, t in
              ((ball, 0.0, 0.0, 0.0), (knot, 1.5, 1.0, 0.5), (knot, -2.5, 1.5, 1.0),
               (ball, -1.5, -1.0, 0.0))]  # fmt: skip
    scene, _ = lit_scene(gfx, meshes)
    casters = gather_scene(scene).casters.vertices
    for report in fit_scene_shadows(scene):
        assert_holds(gfx, report, casters)


def test_editing_positions_refits(gfx):  # noqa: F811
    """The summaries are cached by geometry data version: an unchanged scene is not
    rebuilt; editing a geometry's positions (and telling pygfx, update_full) changes the
    next fit, equal again to the per-frame path's; an edit without telling pygfx is
    caught by the values' fingerprint; replacing the buffer likewise."""
    from shadowmath.integrations.pygfx import _CACHE, _fit_gathered, fit_scene_shadows

    box = caster(gfx, gfx.box_geometry(1.0, 1.0, 1.0), (0.0, 0.0, 1.0))
    scene, _ = lit_scene(gfx, [box])
    first = fit_scene_shadows(scene)
    state = _CACHE[scene]
    rebuilds = state.rebuilds
    box.local.position = (0.2, 0.0, 1.0)  # a move: new matrices, no rebuild
    fit_scene_shadows(scene)
    assert state.rebuilds == rebuilds

    def check(before: list[Any]) -> list[Any]:
        after = fit_scene_shadows(scene)
        assert state.rebuilds > rebuilds
        sun_before, sun_after = before[0].fit.frustum, after[0].fit.frustum
        assert float(sun_after.half_width) > 1.2 * float(sun_before.half_width)
        old = _fit_gathered(scene)
        for new, ref in zip(after, old, strict=True):
            for a, b in zip(fields(new.fit), fields(ref.fit), strict=True):
                np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-9)
        return after

    positions = box.geometry.positions
    positions.data[:] *= 1.5
    positions.update_full()
    grown = check(first)
    rebuilds = state.rebuilds
    positions.data[:] *= 1.5  # pygfx is not told: the fingerprint changed
    again = check(grown)
    rebuilds = state.rebuilds
    box.geometry.positions = gfx.Buffer(np.asarray(positions.data) * 1.5)
    check(again)
    assert len(state.summaries) == 2  # the floor's and the box's latest


def test_instances_are_culled_one_by_one(gfx):  # noqa: F811
    """An InstancedMesh is one object per instance: a narrow spot over instance 0 draws
    that instance alone, the sun draws all four; moving instance 3 under the spot
    (set_matrix_at, no rebuild) puts it in the spot's list at the next call; the point
    light's cube faces list the instances on their side."""
    from shadowmath.integrations.pygfx import _CACHE, fit_scene_shadows

    many = gfx.InstancedMesh(gfx.box_geometry(0.5, 0.5, 0.5), gfx.MeshPhongMaterial(), 4)
    many.cast_shadow = True
    for k in range(4):
        m = np.eye(4)
        m[:3, 3] = (8.0 * k, 0.0, 0.5)
        many.set_matrix_at(k, m)
    scene = gfx.Scene()
    spot = gfx.SpotLight(cast_shadow=True, angle=0.2)
    spot.local.position = (0.0, 0.0, 5.0)
    spot.target.local.position = (0.0, 0.0, 0.0)
    sun = gfx.DirectionalLight(cast_shadow=True)
    sun.local.position = (1.0, 1.0, 5.0)
    lamp = gfx.PointLight(cast_shadow=True)
    lamp.local.position = (12.0, 0.0, 0.5)  # between instances 1 and 2
    scene.add(many, spot, spot.target, sun, sun.target, lamp)
    reports = {type(r.light).__name__: r for r in fit_scene_shadows(scene)}
    assert reports["SpotLight"].draws == (((many, 0),),)
    assert reports["DirectionalLight"].draws == (tuple((many, k) for k in range(4)),)
    faces = reports["PointLight"].draws  # +X, -X, +Y, -Y, +Z, -Z
    assert faces[0] == ((many, 2), (many, 3)) and faces[1] == ((many, 0), (many, 1))
    assert faces[2] == faces[3] == faces[4] == faces[5] == ()
    rebuilds = _CACHE[scene].rebuilds
    m = np.eye(4)
    m[:3, 3] = (0.3, 0.0, 1.5)
    many.set_matrix_at(3, m)
    spot_report = fit_scene_shadows(scene)[0]
    assert spot_report.draws == (((many, 0), (many, 3)),)
    assert _CACHE[scene].rebuilds == rebuilds


def test_flags_and_visibility_rebuild_the_cache(gfx):  # noqa: F811
    """Hiding a caster, clearing its cast_shadow, or adding a mesh rebuilds the cache: the
    draw lists follow at the next call."""
    from shadowmath.integrations.pygfx import fit_scene_shadows

    geometry = gfx.box_geometry(1.0, 1.0, 1.0)
    a, b = caster(gfx, geometry, (0.0, 0.0, 1.0)), caster(gfx, geometry, (3.0, 0.0, 1.0))
    scene, _ = lit_scene(gfx, [a, b])

    def sun_draws() -> set[Any]:
        return {mesh for mesh, _ in fit_scene_shadows(scene)[0].draws[0]}

    assert sun_draws() == {a, b}
    b.visible = False
    assert sun_draws() == {a}
    b.visible, a.cast_shadow = True, False
    assert sun_draws() == {b}
    c = caster(gfx, geometry, (-3.0, 0.0, 1.0))
    scene.add(c)
    assert sun_draws() == {b, c}
    a.cast_shadow = b.cast_shadow = c.cast_shadow = False
    reports = fit_scene_shadows(scene)
    assert [r.skipped for r in reports] == ["the scene has no visible mesh with cast_shadow"] * 4
    with pytest.raises(ValueError, match="pcf_radius"):
        fit_scene_shadows(scene, pcf_radius=-1)
