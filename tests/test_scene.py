"""ShadowScene: summaries hold their geometry, culling never drops a caster that can
shadow a lit point, the fits hold every kept caster, and bad input is refused by name.

Each culling rule is checked against geometry computed another way (the distance from a
sphere to a cone, points sampled on the culled objects' own triangles), and against the
mutation that makes it too aggressive (its bound halved), which a constructed scene
catches.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import shadowmath as sm
from shadowmath import meshes
from shadowmath._scene import _cull
from shadowmath._scene._summary import DIRECTIONS, summarize

SEEDS = st.integers(0, 2**32 - 1)


def _rotation(rng: np.random.Generator) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    return q * np.sign(np.diag(r))


def _affine(rng: np.random.Generator, spread: float = 4.0) -> np.ndarray:
    """A random affine placement: rotation, non-uniform scale, shear, translation."""
    M = np.eye(4)
    M[:3, :3] = (
        _rotation(rng)
        @ np.diag(rng.uniform(0.3, 2.0, 3))
        @ (np.eye(3) + np.triu(rng.uniform(-0.3, 0.3, (3, 3)), 1))
    )
    M[:3, 3] = rng.uniform(-spread, spread, 3)
    return M


def _geometry(rng: np.random.Generator) -> sm.Mesh:
    kind = rng.integers(0, 4)
    if kind == 0:
        return meshes.sphere(rng.uniform(0.2, 1.0), segments=int(rng.integers(6, 20)), rings=6)
    if kind == 1:
        return meshes.torus(rng.uniform(0.5, 1.0), 0.2, segments=16, sides=8)
    if kind == 2:
        return meshes.box(tuple(rng.uniform(0.1, 1.5, 3)))
    V = rng.normal(size=(int(rng.integers(4, 200)), 3)) * rng.uniform(0.1, 1.0, 3)
    F = rng.integers(0, len(V), (int(rng.integers(1, 300)), 3))
    return sm.Mesh(V, F)


def _world(mesh: sm.Mesh, M: np.ndarray) -> np.ndarray:
    V = np.asarray(mesh.vertices, dtype=np.float64)
    return (V @ M[:3, :3].T + M[:3, 3])[np.asarray(mesh.faces)]


def _samples(triangles: np.ndarray, n: int = 6) -> np.ndarray:
    """Points on each triangle: a barycentric grid of ``n`` steps per edge (corners too)."""
    i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="ij")
    keep = i + j <= n
    a, b = i[keep] / n, j[keep] / n
    w = np.stack([1 - a - b, a, b], axis=-1)  # (S, 3)
    return np.einsum("sc,tcd->tsd", w, triangles).reshape(-1, 3)


# -- summaries ------------------------------------------------------------------------
@given(SEEDS)
def test_summary_holds_its_geometry(seed: int) -> None:
    """Every direction's support of the summary is at least the geometry's triangles' (so
    the summary's convex solid holds every surface the geometry draws; a vertex no face uses
    draws nothing), and every vertex is in the sphere."""
    rng = np.random.default_rng(seed)
    mesh = _geometry(rng)
    V = np.asarray(mesh.vertices, dtype=np.float64)
    T = V[np.asarray(mesh.faces)]
    s = summarize(V, T)
    U = rng.normal(size=(200, 3))
    U = np.concatenate([U / np.linalg.norm(U, axis=1, keepdims=True), DIRECTIONS])
    tol = 1e-12 * np.max(np.abs(V))
    drawn = np.max(T.reshape(-1, 3) @ U.T, axis=0)
    assert np.all(np.max(s.triangles.reshape(-1, 3) @ U.T, axis=0) >= drawn - tol)
    assert np.all(np.linalg.norm(V - s.center, axis=1) <= s.radius)
    assert np.all(np.linalg.norm(s.triangles.reshape(-1, 3) - s.center, axis=1) <= s.radius)


def test_summary_of_a_dense_sphere_is_small_and_close() -> None:
    """A 4,000-triangle sphere: the 26-DOP's 92 triangles, its corners within the bound
    of the 26-DOP of a ball (the corner of the (1, 1, 1) face: 12.8 % out), and every
    face plane touching the sphere."""
    mesh = meshes.sphere(1.0, segments=64, rings=32)
    V = np.asarray(mesh.vertices, dtype=np.float64)
    s = summarize(V, V[np.asarray(mesh.faces)])
    assert not s.exact and len(s.triangles) <= 100
    far = np.max(np.linalg.norm(s.points, axis=1))
    assert 1.0 < far < 1.13
    small = summarize(V[:8], V[:8][None, :3])  # one triangle: its own
    assert small.exact and len(small.triangles) == 1


@given(SEEDS)
def test_world_spheres_hold_placed_vertices(seed: int) -> None:
    rng = np.random.default_rng(seed)
    mesh = _geometry(rng)
    V = np.asarray(mesh.vertices, dtype=np.float64)
    s = summarize(V, V[np.asarray(mesh.faces)])
    M = np.stack([_affine(rng) for _ in range(3)])
    c, r = _cull.world_spheres(M, np.broadcast_to(s.center, (3, 3)), np.full(3, s.radius))
    for k in range(3):
        W = V @ M[k, :3, :3].T + M[k, :3, 3]
        assert np.all(np.linalg.norm(W - c[k], axis=1) <= r[k])
    # the bound is the largest stretch, not a looser one: a pure scale is exact
    S = np.diag([3.0, 1.0, 1.0, 1.0])
    _, r1 = _cull.world_spheres(S[None], np.zeros((1, 3)), np.ones(1))
    assert r1[0] == pytest.approx(3.0, rel=1e-9)


# -- culling rules --------------------------------------------------------------------
def _cone_distance(L: np.ndarray, axis: np.ndarray, theta: float, p: np.ndarray) -> np.ndarray:
    """Euclidean distance from points ``p`` to the solid cone (apex ``L``), written from the
    angle in the plane of the axis and the point: ``|v| sin(phi - theta)`` beside the cone,
    ``|v|`` beyond its apex, 0 inside."""
    v = p - L
    d = np.linalg.norm(v, axis=-1)
    cos_phi = (v @ axis) / np.maximum(d, 1e-300) / np.linalg.norm(axis)
    phi = np.arccos(np.clip(cos_phi, -1.0, 1.0))
    beside = d * np.sin(phi - theta)
    return np.where(phi <= theta, 0.0, np.where(phi - theta >= np.pi / 2, d, beside))


@given(SEEDS)
def test_spot_cull_only_drops_spheres_outside_the_cone(seed: int) -> None:
    rng = np.random.default_rng(seed)
    L, axis = rng.normal(size=3), rng.normal(size=3)
    theta = rng.uniform(0.05, 1.5)
    c = L + rng.normal(size=(400, 3)) * 3
    r = rng.uniform(0.0, 2.0, 400)
    keep = _cull.spot_visible(L, axis, theta, c, r)
    gap = _cone_distance(L, axis, theta, c)
    assert np.all(gap[~keep] > r[~keep] * (1 - 1e-9))  # dropped: sphere misses the cone
    assert np.all(keep[gap < r * (1 - 1e-9)])  # reaching in: kept


def _clip_inside(world_to_clip: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Points that land in the map: ``|x| <= w``, ``|y| <= w`` in clip coordinates."""
    h = np.c_[points, np.ones(len(points))] @ world_to_clip.T
    return (np.abs(h[:, 0]) <= h[:, 3]) & (np.abs(h[:, 1]) <= h[:, 3])


@given(SEEDS)
def test_clip_rule_drops_nothing_a_map_draws(seed: int) -> None:
    """Points sampled on the culled objects' own triangles never land in the map's clip
    volume (a cube face with a border ring, a perspective and an orthographic map)."""
    rng = np.random.default_rng(seed)
    L = rng.normal(size=3)
    mesh = _geometry(rng)
    V = np.asarray(mesh.vertices, dtype=np.float64)
    s = summarize(V, V[np.asarray(mesh.faces)])
    M = np.stack([_affine(rng, 3.0) for _ in range(12)])
    c, r = _cull.world_spheres(M, np.broadcast_to(s.center, (12, 3)), np.full(12, s.radius))
    faces = sm.cube_face_projection(0.1, 20.0, map_size=64, border_texels=int(rng.integers(0, 4)))
    maps = np.concatenate([faces @ sm.cube_face_views(L), _maps(rng)])
    seen = _cull.clip_visible(maps, c, r)
    assert seen.shape == (len(maps), 12)
    for k in range(12):
        p = _samples(_world(mesh, M[k]), 3)
        for m in range(len(maps)):
            if not seen[m, k]:
                assert not np.any(_clip_inside(maps[m], p))
            if _clip_inside(maps[m], c[k : k + 1])[0]:
                assert seen[m, k]  # a centre in the map: kept


def _maps(rng: np.random.Generator) -> np.ndarray:
    """A perspective (a spot's fit) and an orthographic (a sun's) world-to-clip matrix."""
    box = rng.uniform(-3, 3, (8, 3))
    spot = sm.fit_shadow(sm.PointLight(np.r_[rng.uniform(-1, 1, 2), 8.0]), box, 128)
    sun = sm.fit_shadow(sm.DirectionalLight(rng.normal(size=3)), box, 128)
    return np.stack([spot.blocker_to_clip, sun.blocker_to_clip])


def test_cube_range_from_candidates_equals_every_object() -> None:
    rng = np.random.default_rng(7)
    scene = sm.ShadowScene()
    ball = scene.add_geometry(meshes.sphere(0.5, segments=12, rings=6))
    balls = np.stack([_affine(rng, 6.0) for _ in range(40)])
    balls[:, 2, 3] += 12.0  # above the torus: they hold the far end
    scene.add_objects(ball, balls)
    # a torus around the light (its centre nearer than any of its points) and a ball
    # nearer than the torus's ring: the nearest caster is the ball's
    ring = scene.add_geometry(meshes.torus(2.0, 0.3, segments=32, sides=8))
    scene.add_objects(ring, np.eye(4))
    near_ball = np.eye(4)
    near_ball[:3, 3] = [1.0, 1.0, 0.0]
    scene.add_objects(scene.add_geometry(meshes.sphere(0.3, segments=8, rings=4)), near_ball)
    light = sm.PointLight(np.array([0.0, 0.0, 0.0]))
    scene_fit = scene.fit([light], 512)[0].fit
    read = scene._triangles(scene._casts, light.position)  # the torus: its own triangles
    every = sm.cube_depth_range(light.position, read, map_size=512, border_texels=1)
    assert isinstance(scene_fit, sm.CubeDepthRange)
    assert float(scene_fit.near) == float(every.near)
    assert float(scene_fit.far) == float(every.far)
    # the ball's nearest point (D = 0.79), not the torus's 26-DOP, whose slab holds the light
    assert 0.7 < float(scene_fit.near) < 0.79


def test_the_nearest_caster_of_a_cube_map_may_end_farthest() -> None:
    """A plank from 0.8 to 8.8 units above a point light (its sphere ends far beyond a small
    ball at 2.3) and a ball 20 units away holding the far end: the near plane is the
    plank's nearest point, though its sphere ends last among the near ones."""
    scene = sm.ShadowScene()
    plank = scene.add_geometry(meshes.box((0.4, 0.4, 8.0)))
    ball = scene.add_geometry(meshes.sphere(0.3, segments=8, rings=4))
    scene.add_objects(plank, _place((0.0, 0.0, 4.8)))
    scene.add_objects(ball, np.stack([_place((-2.3, 0.0, 0.0)), _place((0.0, 20.0, 0.0))]))
    light = sm.PointLight(np.zeros(3))
    scene_fit = scene.fit([light], 512)[0].fit
    every = sm.cube_depth_range(light.position, sm.Triangles(scene._world), map_size=512,
                                border_texels=1)  # fmt: skip
    assert isinstance(scene_fit, sm.CubeDepthRange)
    assert 0.7 < float(scene_fit.near) == float(every.near) < 0.8  # the plank's end: D = 0.8
    assert float(scene_fit.far) == float(every.far)


# -- whole scenes ---------------------------------------------------------------------
def _random_scene(rng: np.random.Generator, n: int = 10) -> tuple[sm.ShadowScene, list]:
    """A scene of ``n`` placed geometries over a floor; returns it and (mesh, M) per object."""
    scene = sm.ShadowScene()
    floor_mesh = meshes.grid((30.0, 30.0))
    floor = scene.add_geometry(floor_mesh)
    scene.add_objects(floor, casts=False, static=True)
    objects: list = [(floor_mesh, np.eye(4))]
    for _ in range(n):
        mesh = _geometry(rng)
        M = _affine(rng, 5.0)
        M[2, 3] = abs(M[2, 3]) + 2.0
        scene.add_objects(scene.add_geometry(mesh), M)
        objects.append((mesh, M))
    return scene, objects


def _inside_map(setup: sm.ShadowSetup, points: np.ndarray) -> np.ndarray:
    """Texture coordinates of world points: (s, t, r) all in [0, 1] (and q > 0)."""
    h = np.c_[points, np.ones(len(points))] @ np.asarray(setup.world_to_texture).T
    q = h[:, 3]
    stq = h[:, :3] / q[:, None]
    tol = 1e-9
    return (q > 0) & np.all((stq >= -tol) & (stq <= 1 + tol), axis=1)


@given(SEEDS)
@settings(max_examples=10, deadline=None)
def test_spot_fit_holds_every_caster_in_its_cone(seed: int) -> None:
    """Every point of every caster (its own triangles, sampled) inside the cone lies in the
    map, and every object left out of the draw list has no point in the cone."""
    rng = np.random.default_rng(seed)
    scene, objects = _random_scene(rng)
    L = np.r_[rng.uniform(-3, 3, 2), rng.uniform(8, 12)]
    axis = np.r_[rng.uniform(-0.4, 0.4, 2), -1.0]
    theta = float(rng.uniform(0.2, 0.8))
    result = scene.fit([sm.SpotLight(L, axis, np.float64(theta))], 1024)[0]
    drawn = set(result.draws[0].tolist())
    for k, (mesh, M) in enumerate(objects):
        if k == 0:
            continue  # the floor casts nothing
        p = _samples(_world(mesh, M), 4)
        in_cone = _cone_distance(L, axis, theta, p) == 0
        if k not in drawn:
            assert not np.any(in_cone)
        elif result.fit is not None:
            assert np.all(_inside_map(result.fit, p[in_cone]))


@given(SEEDS)
@settings(max_examples=10, deadline=None)
def test_sun_fit_equals_the_fit_of_every_summary(seed: int) -> None:
    """The sun's fit from candidate objects is the fit of every caster's summary (the
    others lie inside its box), and holds every caster's own vertices."""
    rng = np.random.default_rng(seed)
    scene, objects = _random_scene(rng)
    sun = sm.DirectionalLight(np.r_[rng.uniform(-0.6, 0.6, 2), 1.0])
    result = scene.fit([sun], 1024)[0]
    assert result.fit is not None
    casts = scene._casts[scene._owner]
    every = sm.fit_shadow(sun, sm.Triangles(scene._world[casts]), 1024,
                          receivers=sm.Triangles(scene._world))  # fmt: skip
    for a, b in zip(result.fit.frustum, every.frustum, strict=True):
        assert float(a) == pytest.approx(float(b), rel=1e-9, abs=1e-9)
    assert np.allclose(result.fit.world_to_texture, every.world_to_texture, atol=1e-9)
    assert int(result.fit.casters_used) == int(every.casters_used) == int(casts.sum())
    for mesh, M in objects[1:]:
        assert np.all(_inside_map(result.fit, _world(mesh, M).reshape(-1, 3)))
    assert result.draws[0].tolist() == list(range(1, len(objects)))


@pytest.mark.parametrize("direction", [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
def test_a_sun_along_an_axis_fits_boxes_whose_faces_it_sees_edge_on(direction: list[float]) -> None:
    """A sun straight along an axis over axis-aligned boxes (half their faces edge-on to
    it): fitted as every caster's summary, like any other sun."""
    scene = sm.ShadowScene()
    cube = scene.add_geometry(meshes.box((1.0, 1.0, 1.0)))
    placed = np.stack([np.eye(4)] * 2)
    placed[:, :3, 3] = [[0.3, -0.2, 1.5], [-1.0, 0.5, 0.7]]
    scene.add_objects(cube, placed)
    sun = sm.DirectionalLight(np.array(direction))
    result = scene.fit([sun], 512)[0]
    assert result.skipped == "" and result.fit is not None
    every = sm.fit_shadow(
        sun, sm.Triangles(scene._world), 512, receivers=sm.Triangles(scene._world)
    )
    assert np.allclose(result.fit.world_to_texture, every.world_to_texture, atol=1e-9)


def test_a_ramp_under_the_caster_is_held_when_a_deeper_receiver_lies_aside() -> None:
    """An overhead sun, one box above a ramp (a 4 x 4 tile tilted 45 degrees, its high side
    above the box's base) and a deeper plate far to the side (outside the map): the
    plate reaches deepest, so it alone is the first receiver candidate, but only points
    inside the map's sides count; the ramp, which straddles the first fit's far plane,
    must be refitted in: every point of it the map covers lies in its depth range."""
    scene = sm.ShadowScene()
    cube = scene.add_geometry(meshes.box((1.0, 1.0, 1.0)))
    tile = scene.add_geometry(meshes.grid((4.0, 4.0)))
    scene.add_objects(cube, _place((0.0, 0.0, 1.7)))  # z from 1.2 to 2.2
    c = s = np.sqrt(0.5)
    ramp = _place((0.0, 0.0, 0.0))
    ramp[:3, :3] = [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]  # z = -x, from -1.41 to 1.41
    scene.add_objects(tile, ramp, casts=False)
    scene.add_objects(tile, _place((-40.0, 0.0, -3.0)), casts=False)
    sun = sm.DirectionalLight(np.array([0.1, 0.05, 1.0]))
    result = scene.fit([sun], 256)[0]
    assert result.fit is not None
    u = np.linspace(-2.0, 2.0, 81)
    flat = np.stack(np.meshgrid(u, u, [0.0], indexing="ij"), axis=-1).reshape(-1, 3)
    points = flat @ ramp[:3, :3].T
    h = np.c_[points, np.ones(len(points))] @ np.asarray(result.fit.world_to_texture).T
    covered = np.all((h[:, :2] >= 0) & (h[:, :2] <= h[:, 3:]), axis=1)
    assert covered.sum() > 10 and np.all(_inside_map(result.fit, points[covered]))
    every = sm.fit_shadow(sun, sm.Triangles(scene._world[scene._casts[scene._owner]]), 256,
                          receivers=sm.Triangles(scene._world))  # fmt: skip
    assert np.allclose(result.fit.world_to_texture, every.world_to_texture, atol=1e-9)


def _place(t: tuple[float, float, float]) -> np.ndarray:
    M = np.eye(4)
    M[:3, 3] = t
    return M


def test_cascade_draws_leave_out_only_what_cannot_shadow_the_slice() -> None:
    """Objects left out of a cascade's draw list project wholly outside its map's window or
    beyond its far plane (so they shadow nothing it covers)."""
    rng = np.random.default_rng(3)
    scene, objects = _random_scene(rng, 30)
    view = np.eye(4)
    view[:3, 3] = [0.0, 0.0, -40.0]  # looking down -z at the floor from 40 above
    n, f = 1.0, 80.0
    P = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0],
                  [0, 0, -(f + n) / (f - n), -2 * f * n / (f - n)], [0, 0, -1, 0]])  # fmt: skip
    sun = sm.DirectionalLight(np.array([0.3, 0.2, 1.0]))
    result = scene.fit_cascades(sun, view, P, 512, count=4)
    c = result.cascades
    assert len(result.draws) == 4
    left_out = 0
    for i, drawn in enumerate(result.draws):
        for k, (mesh, M) in enumerate(objects):
            if k == 0 or k in set(drawn.tolist()):
                continue
            left_out += 1
            h = np.c_[_world(mesh, M).reshape(-1, 3), np.ones(3 * len(mesh.faces))]
            clip = h @ np.asarray(c.world_to_clip[i]).T
            ndc = clip[:, :3] / clip[:, 3:]
            outside = (np.abs(ndc[:, 0]) > 1) | (np.abs(ndc[:, 1]) > 1) | (ndc[:, 2] > 1)
            assert np.all(outside)
    assert left_out > 0  # the rule did cull something here


def test_a_halved_bound_would_drop_a_caster() -> None:
    """The constructed cases that the rules' bounds are not loose: a ball grazing the
    cone and a cube face, each kept, and dropped with its radius halved."""
    L, axis, theta = np.zeros(3), np.array([0.0, 0.0, 1.0]), 0.3
    # a ball of radius 1 whose nearest point is 0.5 inside the cone's side
    d = 10.0
    c = d * np.array([np.sin(theta + 0.12), 0.0, np.cos(theta + 0.12)])
    gap = _cone_distance(L, axis, theta, c[None])[0]
    r = gap + 0.5
    assert _cull.spot_visible(L, axis, theta, c[None], np.array([r]))[0]
    assert not _cull.spot_visible(L, axis, theta, c[None], np.array([r / 2]))[0]
    # a ball beside the +X cube face (no ring), its sphere reaching 0.4 r into it
    face = (sm.cube_face_projection(0.1, 50.0, map_size=64) @ sm.cube_face_views(L))[0]
    c = np.array([[2.0, 2.0 + 0.6 * np.sqrt(2.0), 0.0]])
    assert _cull.clip_visible(face, c, np.array([1.0]))[0]
    assert not _cull.clip_visible(face, c, np.array([0.5]))[0]


@pytest.mark.parametrize("side", range(4))
def test_clip_rule_keeps_a_sphere_reaching_in_by_part_of_its_radius(side: int) -> None:
    """An orthographic map's window ``[-2, 3] x [-1, 4]`` (a cascade's): a sphere reaching
    0.4 of its radius into each side is kept; moved out by more than its radius, dropped."""
    lo, hi = np.array([-2.0, -1.0]), np.array([3.0, 4.0])
    ortho = np.eye(4)
    ortho[:2, :2] = np.diag(2 / (hi - lo))
    ortho[:2, 3] = -(hi + lo) / (hi - lo)
    ortho[2, 2] = -0.1
    edge = [np.array([lo[0] - 0.6, 1.0, 0.0]), np.array([hi[0] + 0.6, 1.0, 0.0]),
            np.array([0.0, lo[1] - 0.6, 0.0]), np.array([0.0, hi[1] + 0.6, 0.0])][side]  # fmt: skip
    out = [np.array([-1.6, 0, 0]), np.array([1.6, 0, 0]), np.array([0, -1.6, 0]),
           np.array([0, 1.6, 0])][side]  # fmt: skip
    keep = _cull.clip_visible(ortho, np.stack([edge, edge + out]), np.ones(2))
    assert keep.tolist() == [True, False]


def test_scene_moves_only_what_changed_and_refuses_bad_input() -> None:
    scene = sm.ShadowScene()
    box = scene.add_geometry(meshes.box())
    ids = scene.add_objects(box, np.stack([np.eye(4)] * 3))
    floor = scene.add_objects(scene.add_geometry(meshes.grid((5.0, 5.0))), static=True)
    assert ids.tolist() == [0, 1, 2] and floor.tolist() == [3]
    M = scene.transforms
    M[1, 0, 3] = 2.0
    scene.set_transforms(M)
    assert scene.moved.tolist() == [1]
    assert scene.bounds()[1, 0] == pytest.approx(2.5)
    scene.set_transforms(M)
    assert scene.moved.tolist() == []
    row_major = M.copy()
    row_major[0] = np.eye(4)
    row_major[0, 3, :3] = [1.0, 2.0, 3.0]  # translation in the bottom row
    with pytest.raises(ValueError, match=r"transforms\[0\]: its last row"):
        scene.set_transforms(row_major)
    frozen = M.copy()
    frozen[3, 1, 3] = 1.0
    with pytest.raises(ValueError, match=r"transforms\[3\].*static=True"):
        scene.set_transforms(frozen)
    with pytest.raises(ValueError, match=r"transforms: expected shape \(4, 4, 4\)"):
        scene.set_transforms(M[:2])
    bad = M.copy()
    bad[2, 0, 0] = np.nan
    with pytest.raises(ValueError, match=r"transforms\[2\]: contains non-finite"):
        scene.set_transforms(bad)
    with pytest.raises(ValueError, match="geometry: no geometry 9"):
        scene.add_objects(9)
    with pytest.raises(ValueError, match="geometry: contains non-finite"):
        scene.add_geometry(np.array([[0.0, 0.0, np.inf]]))
    with pytest.raises(ValueError, match=r"geometry\.faces: indices must lie in"):
        scene.add_geometry(sm.Mesh(np.zeros((3, 3)), np.array([[0, 1, 5]])))
    with pytest.raises(ValueError, match=r"lights\[1\]: expected an sm.PointLight"):
        scene.fit([sm.PointLight(np.array([0.0, 0.0, 5.0])), (0.0, 0.0, 5.0, 1.0)], 256)
    with pytest.raises(ValueError, match=r"lights\[0\].position: expected shape \(3,\)"):
        scene.fit([sm.PointLight(np.zeros((2, 3)))], 256)
    with pytest.raises(ValueError, match="static: expected a bool"):
        scene.add_objects(box, static=1)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="the scene has no objects"):
        sm.ShadowScene().fit([sm.PointLight(np.zeros(3))], 256)


def test_lights_out_of_reach_are_skipped_with_empty_draws() -> None:
    scene = sm.ShadowScene()
    box = scene.add_geometry(meshes.box())
    lift = np.eye(4)
    lift[2, 3] = 3.0
    scene.add_objects(box, lift)
    away = sm.SpotLight(np.array([0.0, 0.0, 10.0]), np.array([0.0, 0.0, 1.0]), np.float64(0.4))
    at_box = sm.SpotLight(np.array([0.0, 0.0, 10.0]), np.array([0.0, 0.0, -1.0]), np.float64(0.4))
    inside = sm.PointLight(np.array([0.0, 0.0, 3.0]))
    away_fit, box_fit, inside_fit = scene.fit([away, at_box, inside], 256)
    assert away_fit.fit is None and away_fit.skipped and away_fit.draws[0].size == 0
    assert box_fit.skipped == "" and box_fit.draws[0].tolist() == [0]
    assert isinstance(box_fit.fit, sm.ShadowSetup) and int(box_fit.fit.casters_used) > 0
    # a point light inside the box: every face sees it, and its depth range stays exact
    assert inside_fit.skipped == "" and all(d.tolist() == [0] for d in inside_fit.draws)


def test_the_scenes_page_program_runs() -> None:
    """docs/scenes.md's per-frame loop, as printed, runs and its assertions hold."""
    from pathlib import Path

    page = (Path(__file__).resolve().parent.parent / "docs" / "scenes.md").read_text()
    blocks = page.split("```python\n")[1:]
    assert blocks, "docs/scenes.md shows no program"
    for block in blocks:
        exec(compile(block.split("```")[0], "docs/scenes.md", "exec"), {})


def _atlas_scene() -> tuple[sm.ShadowScene, list, np.ndarray]:
    scene = sm.ShadowScene()
    box = scene.add_geometry(meshes.box((1.0, 1.0, 1.0)))
    places = np.tile(np.eye(4), (6, 1, 1))
    places[:, :3, 3] = [[0, 0, 1], [1.5, 0, 1], [8, 0, 1], [8, 1.5, 1], [-8, 0, 1], [-8, 2, 1]]
    scene.add_objects(box, places)
    scene.add_objects(scene.add_geometry(meshes.grid((30.0, 30.0))), casts=False, static=True)
    lights = [
        sm.SpotLight(np.array([0.0, 0.0, 8.0]), np.array([0.0, 0.0, -1.0]), np.float64(0.3)),
        sm.PointLight(np.array([8.0, 0.5, 4.0])),
        sm.DirectionalLight(np.array([0.1, 0.2, 1.0])),
    ]
    return scene, lights, places


def test_scene_atlas_draws_per_tile_and_holds_the_casters() -> None:
    scene, lights, places = _atlas_scene()
    atlas = sm.allocate_atlas([0.5, 0.25, 0.5], atlas_size=2048, cube=[False, True, False])
    result = scene.fit_atlas(lights, atlas)
    assert len(result.draws) == atlas.tile_light.shape[0] == 8
    spot_tile = int(atlas.light_tiles[0, 0])
    assert result.draws[spot_tile].tolist() == [0, 1]  # the boxes under the spot
    sun_tile = int(atlas.light_tiles[2, 0])
    assert result.draws[sun_tile].tolist() == list(range(6))
    for face in range(6):  # the point light at (8, 0.5, 4) above boxes 2 and 3: -Z sees them
        drawn = result.draws[int(atlas.light_tiles[1, face])].tolist()
        assert ({2, 3} <= set(drawn)) == (face == 5)
    # every corner of a drawn box lands inside its tile (s, t within the tile's clamp)
    corners = np.asarray(meshes.box((1.0, 1.0, 1.0)).vertices, dtype=np.float64)
    for tile in (spot_tile, sun_tile):
        for k in result.draws[tile]:
            p = corners + places[k, :3, 3]
            h = np.c_[p, np.ones(len(p))] @ np.asarray(result.fit.world_to_texture[tile]).T
            st = h[:, :2] / h[:, 3:]
            lo, hi = atlas.tile_clamp[tile, :2], atlas.tile_clamp[tile, 2:]
            assert np.all((st >= lo - 1e-9) & (st <= hi + 1e-9))
    assert result.moved.tolist() == list(range(7))  # everything is new at the first fit


def test_atlas_redraw_learns_the_objects() -> None:
    scene, lights, _ = _atlas_scene()
    atlas = sm.allocate_atlas([0.5, 0.25, 0.5], atlas_size=2048, cube=[False, True, False])
    first = scene.fit_atlas(lights, atlas)
    again = scene.fit_atlas(lights, atlas)  # nothing moved, nothing changed
    redraw = sm.atlas_redraw(again.fit, first.fit, draws=again.draws,
                             previous_draws=first.draws, moved=again.moved)  # fmt: skip
    assert again.moved.tolist() == [] and not redraw.any()
    # box 1 turns in place by 90 degrees about z: the same solid, so the same fits
    M = scene.transforms
    M[1, :3, :3] = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # 90 deg
    scene.set_transforms(M)
    third = scene.fit_atlas(lights, atlas)
    plain = sm.atlas_redraw(third.fit, again.fit)
    assert not plain.any()  # the matrices alone see nothing
    redraw = sm.atlas_redraw(third.fit, again.fit, draws=third.draws,
                             previous_draws=again.draws, moved=third.moved)  # fmt: skip
    spot_tile, sun_tile = int(atlas.light_tiles[0, 0]), int(atlas.light_tiles[2, 0])
    assert third.moved.tolist() == [1]
    assert redraw[spot_tile] and redraw[sun_tile]  # both draw box 1
    # exactly the tiles that draw box 1 (the spot, the sun, the cube's -X face)
    assert redraw.tolist() == [1 in d.tolist() for d in third.draws]
    assert redraw[int(atlas.light_tiles[1, 1])] and redraw.sum() == 3
    with pytest.raises(ValueError, match="give all three"):
        sm.atlas_redraw(third.fit, again.fit, draws=third.draws)
    with pytest.raises(ValueError, match=r"draws: expected one draw list per tile \(8\)"):
        sm.atlas_redraw(third.fit, again.fit, draws=third.draws[:3],
                        previous_draws=again.draws, moved=[])  # fmt: skip


def _mixed_lights(rng: np.random.Generator) -> list:
    return [
        sm.SpotLight(
            np.r_[rng.uniform(-3, 3, 2), 11.0],
            np.r_[rng.uniform(-0.3, 0.3, 2), -1.0],
            np.float64(rng.uniform(0.3, 0.7)),
        ),
        sm.DirectionalLight(np.r_[rng.uniform(-0.5, 0.5, 2), 1.0]),
        sm.PointLight(np.r_[rng.uniform(-3, 3, 2), 12.0]),
    ]


@pytest.mark.parametrize("seed", [1, 2])
def test_fit_summaries_is_the_scenes_fit_on_arrays(seed: int) -> None:
    """NumPy: the masked array form gives the fits and draw lists of ShadowScene.fit."""
    rng = np.random.default_rng(seed)
    scene, _ = _random_scene(rng)
    summaries = scene.summaries()
    lights = _mixed_lights(rng)
    for light, direct in zip(lights, scene.fit(lights, 512), strict=True):
        masked = sm.fit_summaries(light, summaries, 512)
        assert direct.fit is not None
        for a, b in zip(_leaves(masked.fit), _leaves(direct.fit), strict=True):
            assert np.allclose(a, b, rtol=1e-9, atol=1e-9)
        for m, drawn in enumerate(direct.draws):
            assert np.flatnonzero(masked.draws[m]).tolist() == drawn.tolist()


def _leaves(tree: object) -> list[np.ndarray]:
    import jax

    return [np.asarray(x, dtype=np.float64) for x in jax.tree_util.tree_leaves(tree)]


def test_fit_summaries_under_jit_and_vmap() -> None:
    """A batch of spot lights (and of suns) fitted in one jitted, vmapped call equals the
    NumPy fits light by light; the gradient of a map's size by the light's position is
    finite."""
    import jax
    import jax.numpy as jnp

    rng = np.random.default_rng(5)
    scene, _ = _random_scene(rng)
    summaries = scene.summaries()
    S = sm.SceneSummaries(*(jnp.asarray(a) for a in summaries))
    spec = sm.ShadowMapSpec(512)
    n = 4
    spots = sm.SpotLight(
        np.c_[rng.uniform(-3, 3, (n, 2)), np.full(n, 11.0)],
        np.c_[rng.uniform(-0.3, 0.3, (n, 2)), -np.ones(n)],
        rng.uniform(0.3, 0.7, n),
    )
    batched = jax.jit(jax.vmap(lambda L: sm.fit_summaries(L, S, spec)))(
        sm.SpotLight(*(jnp.asarray(a) for a in spots))
    )
    for i in range(n):
        one = sm.SpotLight(*(np.asarray(a[i]) for a in spots))
        ref = sm.fit_summaries(one, summaries, spec)
        got = jax.tree_util.tree_map(lambda x, i=i: x[i], batched)
        for a, b in zip(_leaves(got.fit), _leaves(ref.fit), strict=True):
            assert np.allclose(a, b, rtol=1e-8, atol=1e-8)
        assert np.array_equal(np.asarray(got.draws), ref.draws)

    def size(position: jax.Array) -> jax.Array:
        light = sm.SpotLight(position, jnp.asarray(spots.direction[0]), jnp.asarray(spots.angle[0]))
        f = sm.fit_summaries(light, S, spec).fit.frustum
        return f.rx_max * f.ry_max

    g = jax.jit(jax.grad(size))(jnp.asarray(spots.position[0]))
    assert np.all(np.isfinite(np.asarray(g))) and np.any(np.asarray(g) != 0)


def _camera(eye: np.ndarray, target: np.ndarray) -> np.ndarray:
    """An OpenGL world-to-clip matrix: a 60-degree perspective looking from ``eye`` at
    ``target`` (gluLookAt, gluPerspective)."""
    f = (target - eye) / np.linalg.norm(target - eye)
    r = np.cross(f, [0.0, 1.0, 0.0])
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    view = np.eye(4)
    view[:3, :3] = np.stack([r, u, -f])
    view[:3, 3] = -view[:3, :3] @ eye
    k, n, far = 1 / np.tan(np.radians(30.0)), 0.5, 100.0
    a, b = -(far + n) / (far - n), -2 * far * n / (far - n)
    proj = np.array([[k, 0, 0, 0], [0, k, 0, 0], [0, 0, a, b], [0, 0, -1, 0]])
    return proj @ view


@given(SEEDS)
@settings(max_examples=10, deadline=None)
def test_a_camera_skips_the_maps_no_visible_receiver_reaches(seed: int) -> None:
    """With a camera, a map whose list is emptied has no receiver point that the camera
    sees (sampled on the receivers' own triangles, inside the camera's clip volume) in
    its clip volume; the lists it keeps are those without a camera; and a camera that
    sees no receiver skips every face."""
    rng = np.random.default_rng(seed)
    scene, objects = _random_scene(rng)
    point = sm.PointLight(np.r_[rng.uniform(-3, 3, 2), rng.uniform(6, 10)])
    camera = _camera(np.r_[rng.uniform(-4, 4, 2), 25.0], np.zeros(3))
    (plain,) = scene.fit([point], 512)
    (looked,) = scene.fit([point], 512, camera=camera)
    assert plain.fit is not None
    P = sm.cube_face_projection(plain.fit.near, plain.fit.far, map_size=512, border_texels=1)
    faces = P @ sm.cube_face_views(point.position)
    seen = [_samples(_world(mesh, M), 3) for mesh, M in objects]
    seen = np.concatenate([p[_clip_inside(camera, p)] for p in seen])
    for face in range(6):
        if len(looked.draws[face]):
            assert looked.draws[face].tolist() == plain.draws[face].tolist()
        elif len(plain.draws[face]):  # emptied by the camera: no pixel samples it
            assert not np.any(_clip_inside(faces[face], seen))
    away = _camera(np.array([0.0, 0.1, 40.0]), np.array([0.0, 0.0, 80.0]))  # at the sky
    (skipped,) = scene.fit([point], 512, camera=away)
    assert all(len(d) == 0 for d in skipped.draws) and any(len(d) for d in plain.draws)
    with pytest.raises(ValueError, match=r"camera: expected a \(4, 4\)"):
        scene.fit([point], 512, camera=np.eye(3))


@given(SEEDS)
def test_light_intervals_hold_every_corner_and_reach_a_box(seed: int) -> None:
    """A sun's candidate and inside tests read each object's light-coordinate interval: it
    holds every corner of the object's summary (a random rigid frame), and for a box whose
    faces are the frame's planes it is the box itself (no looser than the sphere or box)."""
    rng = np.random.default_rng(seed)
    scene, _ = _random_scene(rng, 6)
    frame = np.eye(4)
    frame[:3, :3], frame[:3, 3] = _rotation(rng), rng.normal(size=3)
    lo, hi = _cull.light_intervals(frame, scene._center, scene._radius, scene._bounds)
    p = scene._world @ frame[:3, :3].T + frame[:3, 3]
    for k in range(len(scene._M)):
        corners = p[scene._owner == k].reshape(-1, 3)
        tol = 1e-9 * (1 + np.max(np.abs(corners)))
        assert np.all(corners >= lo[k] - tol) and np.all(corners <= hi[k] + tol)
    box = sm.ShadowScene()
    place = np.eye(4)
    place[:3, 3] = [2.0, -1.0, 4.0]
    box.add_objects(box.add_geometry(meshes.box((1.0, 0.5, 0.3))), place)
    lo, hi = _cull.light_intervals(np.eye(4), box._center, box._radius, box._bounds)
    assert np.allclose(lo[0], [1.5, -1.25, 3.85]) and np.allclose(hi[0], [2.5, -0.75, 4.15])
