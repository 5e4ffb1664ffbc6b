"""Receivers as surfaces: the depth range holds every receiver point that the map covers.

The reference here is an independent clip: each receiver triangle is clipped by
Sutherland-Hodgman against the map's four side planes in homogeneous clip space
(``-w <= x, y <= w``) of the fit's own ``blocker_to_clip``; the light-space depth
is linear over the clipped polygon, so its largest value is at one of the
polygon's corners. The fit must hold all of them (``far``) and be tight (a
receiver that sets ``far`` sets it exactly), on every path: compiled loop,
Python loop, array path and JAX.
"""

from __future__ import annotations

import contextlib
import itertools
import re
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import shadowmath as sm
from shadowmath._backends import _kernels

SLACK = sm.NEAR_FAR_SLACK
PATHS = {
    "compiled": contextlib.nullcontext,
    "python loop": _kernels.disabled,
    "array path": _kernels.array_path,
}


def _clip_polygon(poly: np.ndarray) -> np.ndarray:
    """Sutherland-Hodgman: the homogeneous polygon ``(K, 4)`` inside ``|x|, |y| <= w``."""
    planes = (np.array([-1, 0, 0, 1]), np.array([1, 0, 0, 1]))
    planes += (np.array([0, -1, 0, 1]), np.array([0, 1, 0, 1]))
    for plane in planes:
        if len(poly) == 0:
            break
        out = []
        d = poly @ plane
        for i in range(len(poly)):
            j = (i + 1) % len(poly)
            if d[i] >= 0:
                out.append(poly[i])
            if (d[i] >= 0) != (d[j] >= 0):
                t = d[i] / (d[i] - d[j])
                out.append(poly[i] + t * (poly[j] - poly[i]))
        poly = np.array(out).reshape(-1, 4)
    return poly


def _covered_depths(s: sm.ShadowSetup, tris: np.ndarray) -> np.ndarray:
    """Light-space ``z`` of every corner of every triangle's part inside the map's sides."""
    W = np.asarray(s.world_to_light)
    to_clip = np.asarray(s.blocker_to_clip)
    depths = []
    for tri in tris:
        h = np.c_[tri, np.ones(3)]
        poly = _clip_polygon(h @ to_clip.T)
        if len(poly):
            world = np.linalg.solve(to_clip, poly.T).T  # back to world, homogeneous
            world = world[:, :3] / world[:, 3:]
            depths.extend((np.c_[world, np.ones(len(world))] @ W.T)[:, 2])
    return np.array(depths)


def _casters_depths(s: sm.ShadowSetup, verts: np.ndarray) -> np.ndarray:
    return (np.c_[verts, np.ones(len(verts))] @ np.asarray(s.world_to_light).T)[:, 2]


def _scene(seed: int, directional: bool) -> tuple[Any, np.ndarray, np.ndarray]:
    """A blocker near (0, 0, 6) and 40 large random triangles around and beyond it."""
    rng = np.random.default_rng(seed)
    verts = rng.normal(size=(24, 3)) * [1.0, 0.7, 0.5] + [0.3, -0.2, 6.0]
    centres = rng.normal(size=(40, 1, 3)) * 6 + [0.0, 0.0, 12.0]
    tris = centres + rng.normal(size=(40, 3, 3)) * 8.0
    if directional:
        light: Any = sm.DirectionalLight(np.array([0.2, -0.1, -1.0]) + rng.normal(size=3) * 0.2)
    else:
        light = sm.PointLight(rng.normal(size=3) * 0.5)
    return light, verts, tris


LIGHTS = pytest.mark.parametrize("directional", [False, True], ids=["point", "directional"])


@LIGHTS
@pytest.mark.parametrize("path", PATHS)
@pytest.mark.parametrize("seed", range(6))
def test_far_holds_every_covered_receiver_point_exactly(
    directional: bool, path: str, seed: int
) -> None:
    light, verts, tris = _scene(seed, directional)
    with PATHS[path]():
        s = sm.fit_shadow(light, verts, 128, receivers=sm.Triangles(tris))
    depths = _covered_depths(s, tris)
    casters = _casters_depths(s, verts)
    far = float(s.frustum.far)
    assert len(depths) > 0
    assert depths.max() <= far * (1 + 1e-12)  # everything covered is in range...
    expected = max(depths.max(), casters.max()) * (1 + SLACK)
    np.testing.assert_allclose(far, expected, rtol=1e-9)  # ...and no more than that
    # near is the casters' own: receivers never pull it toward the light.
    plain = sm.fit_shadow(light, verts, 128)
    shift = 0.0 if not directional else float(np.asarray(s.frame.z_axis) @ (
        np.asarray(s.frame.origin) - np.asarray(plain.frame.origin)))  # fmt: skip
    np.testing.assert_allclose(
        float(s.frustum.near) + shift * (1 - SLACK),
        float(plain.frustum.near),
        rtol=1e-9,
        atol=1e-9 * far,
    )


@LIGHTS
@pytest.mark.parametrize("path", PATHS)
def test_every_edge_and_corner_order_gives_the_same_far(directional: bool, path: str) -> None:
    # One triangle reaching out of the map's side: its farthest covered point is where an
    # edge crosses the side plane. Each of its six corner orders must give the same far.
    verts = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (4, 6)], float)
    tri = np.array([[-0.2, 0.1, 7.0], [9.0, 0.3, 30.0], [0.1, -0.3, 8.0]])
    light: Any = sm.DirectionalLight(np.array([0.0, 0.0, -1.0])) if directional else [0.0, 0, 0]
    fars = []
    with PATHS[path]():
        for order in itertools.permutations(range(3)):
            s = sm.fit_shadow(light, verts, 64, receivers=sm.Triangles(tri[list(order)][None]))
            fars.append(float(s.frustum.far))
    depths = _covered_depths(s, tri[None])
    assert depths.max() < _casters_depths(s, np.array([tri[1]]))[0]  # the far corner is out
    np.testing.assert_allclose(fars, depths.max() * (1 + SLACK), rtol=1e-9)


@LIGHTS
def test_a_floor_whose_corners_are_all_outside_the_map_is_held(directional: bool) -> None:
    # The case: a floor's corners outside the map count for nothing as points.
    verts = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (4, 6)], float)
    a, b, c, d = [-50, -50, 30], [50, -50, 30], [50, 50, 30], [-50, 50, 30]
    floor = np.array([[a, b, c], [a, c, d]], float)
    light = sm.DirectionalLight(np.array([0.0, 0.0, -1.0])) if directional else [0.0, 0, 0]
    as_points = sm.fit_shadow(light, verts, 64, receivers=floor.reshape(-1, 3))
    as_triangles = sm.fit_shadow(light, verts, 64, receivers=sm.Triangles(floor))
    floor_depth = 30.0 - (0.0 if not directional else float(as_triangles.frame.origin[2]))
    assert float(as_points.frustum.far) < floor_depth  # its corners are outside the map
    np.testing.assert_allclose(float(as_triangles.frustum.far), floor_depth * (1 + SLACK))


def test_receivers_behind_a_point_light_or_before_every_caster_change_nothing() -> None:
    verts = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (4, 6)], float)
    behind = np.array([[[-9, -9, -3], [9, -9, -3], [0, 9, -3]]], float)  # z < 0
    before = np.array([[[-9, -9, 2], [9, -9, 2], [0, 9, 2]]], float)  # 0 < z < 4
    plain = sm.fit_shadow([0.0, 0, 0], verts, 64)
    for tris in (behind, before):
        s = sm.fit_shadow([0.0, 0, 0], verts, 64, receivers=sm.Triangles(tris))
        np.testing.assert_array_equal(s.blocker_to_clip, plain.blocker_to_clip)
    # A receiver before every caster gets a depth before near: lit by the recommended shader.
    s = sm.fit_shadow([0.0, 0, 0], verts, 64, receivers=sm.Triangles(before))
    tex = np.asarray(s.world_to_texture) @ [0.0, 0.0, 2.0, 1.0]
    assert tex[2] / tex[3] < 0


@pytest.mark.parametrize("path", PATHS)
def test_mesh_is_its_triangles(path: str) -> None:
    light, verts, tris = _scene(1, directional=False)
    vertices = tris.reshape(-1, 3)
    faces = np.arange(len(vertices)).reshape(-1, 3)[:, ::-1]  # the winding does not matter
    with PATHS[path]():
        a = sm.fit_shadow(light, verts, 64, receivers=sm.Triangles(tris))
        b = sm.fit_shadow(light, verts, 64, receivers=sm.Mesh(vertices, faces))
    np.testing.assert_allclose(b.blocker_to_clip, a.blocker_to_clip, rtol=1e-12)


@LIGHTS
def test_batches_and_jax_agree_with_numpy(directional: bool) -> None:
    scenes = [_scene(seed, directional) for seed in range(4)]
    light = type(scenes[0][0])(np.stack([s[0][0] for s in scenes]))
    verts = np.stack([s[1] for s in scenes])
    tris = np.stack([s[2] for s in scenes])
    batch = sm.fit_shadow(light, verts, 64, receivers=sm.Triangles(tris))
    for i, (li, vi, ti) in enumerate(scenes):
        one = sm.fit_shadow(li, vi, 64, receivers=sm.Triangles(ti))
        np.testing.assert_allclose(batch.blocker_to_clip[i], one.blocker_to_clip, rtol=1e-12)

    def far(light: Any, verts: Any, tris: Any) -> Any:
        return sm.fit_shadow(light, verts, 64, receivers=sm.Triangles(tris)).frustum.far

    args = (type(light)(jnp.asarray(light[0])), jnp.asarray(verts), jnp.asarray(tris))
    got = jax.jit(far)(*args)
    np.testing.assert_allclose(got, batch.frustum.far, rtol=1e-12)
    vmapped = jax.vmap(far)(*args)
    np.testing.assert_allclose(vmapped, batch.frustum.far, rtol=1e-12)


def test_far_is_differentiable_in_the_receivers() -> None:
    # A triangle crossing the map's side: far is set where its edge meets the side
    # plane; the derivative is that point's, checked against central differences.
    verts = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (4, 6)], float)
    tri = jnp.asarray([[[-0.5, 0.0, 7.0], [3.0, 0.5, 20.0], [-0.2, -3.0, 9.0]]])

    def far(t: Any) -> Any:
        return sm.fit_shadow(
            jnp.zeros(3), jnp.asarray(verts), 64, receivers=sm.Triangles(t)
        ).frustum.far

    g = np.asarray(jax.grad(far)(tri))
    h = 1e-6
    fd = np.zeros_like(g)
    for idx in np.ndindex(*tri.shape):
        e = np.zeros(tri.shape)
        e[idx] = h
        fd[idx] = (far(tri + e) - far(tri - e)) / (2 * h)
    assert np.abs(g).max() > 0.1  # far follows the triangle
    np.testing.assert_allclose(g, fd, atol=1e-6)


def test_non_finite_receivers_are_nan_under_jit_with_nan_derivatives() -> None:
    verts = jnp.asarray([[x, y, z] for x in (-1.0, 1.0) for y in (-1.0, 1.0) for z in (4.0, 6.0)])
    tri = jnp.asarray([[[-9.0, -9.0, 9.0], [9.0, -9.0, 9.0], [0.0, jnp.nan, 9.0]]])

    def clip(t: Any) -> Any:
        return sm.fit_shadow(jnp.zeros(3), verts, 64, receivers=sm.Triangles(t)).blocker_to_clip

    assert bool(jnp.isnan(jax.jit(clip)(tri)).any())
    assert bool(jnp.isnan(jax.grad(lambda t: clip(t).sum())(tri)).any())
    # A mesh index out of range cannot raise under jit: NaN, not a clamped vertex.
    quad = jnp.asarray([[-9.0, -9, 9], [9, -9, 9], [9, 9, 9], [-9, 9, 9]])

    def mesh_far(faces: Any) -> Any:
        return sm.fit_shadow(jnp.zeros(3), verts, 64, receivers=sm.Mesh(quad, faces)).frustum.far

    assert bool(jnp.isnan(jax.jit(mesh_far)(jnp.asarray([[0, 1, 7]]))))
    assert bool(jnp.isfinite(jax.jit(mesh_far)(jnp.asarray([[0, 1, 2]]))))


BOX = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (4, 6)], float)


_E = re.escape
_MESH = np.zeros((4, 3))


@pytest.mark.parametrize(
    ("receivers", "words"),
    [
        (np.zeros((0, 3)), _E("receivers: no receiver points (M = 0); pass receivers=None")),
        (np.zeros((5, 2)), _E("got (5, 2); receivers= takes points (*batch, N, 3), sm.Triangles")),
        (sm.Triangles(np.zeros((0, 3, 3))), _E("receivers: no receiver triangles (M = 0)")),
        (sm.Triangles(np.zeros((4, 3))), _E("receivers: expected shape (*batch, M, 3, 3), got")),
        (sm.Mesh(np.zeros((4, 2)), np.zeros((1, 3), int)), "receivers.vertices: expected shape"),
        (sm.Mesh(_MESH, np.zeros((1, 4), int)), _E("receivers.faces: expected shape (F, 3)")),
        (sm.Mesh(_MESH, np.zeros((1, 3))), _E("receivers.faces: expected integer indices")),
        (sm.Mesh(_MESH, np.array([[0, 1, 4]])), _E("receivers.faces: indices must lie in [0, 4)")),
        (sm.Mesh(_MESH, np.array([[0, -1, 2]])), _E("receivers.faces: indices must lie in [0, 4)")),
        (sm.Triangles(np.full((1, 3, 3), np.inf)), "receivers: .*non-finite"),
    ],
)  # fmt: skip
def test_receiver_messages_speak_of_receivers(receivers: Any, words: str) -> None:
    with pytest.raises((ValueError, TypeError), match=words):
        sm.fit_shadow([0.0, 0, 0], BOX, 64, receivers=receivers)


@LIGHTS
def test_the_array_paths_receiver_blocks_change_nothing(
    directional: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    # Without Numba the receivers' pass runs in blocks of receivers (NumPy temporaries of
    # at most _passes._BLOCK numbers): with blocks of one to three receivers per entry
    # the batch fits as the compiled loop does, entry by entry, points and triangles alike.
    from shadowmath._math import _passes

    scenes = [_scene(seed, directional) for seed in range(4)]
    light = type(scenes[0][0])(np.stack([s[0][0] for s in scenes]))
    verts = np.stack([s[1] for s in scenes])
    tris = np.stack([s[2] for s in scenes])
    for receivers in (sm.Triangles(tris), tris.reshape(4, -1, 3)):
        whole = sm.fit_shadow(light, verts, 64, receivers=receivers)
        for block in (4, 8, 12):
            monkeypatch.setattr(_passes, "_BLOCK", block)
            with _kernels.array_path():
                blocked = sm.fit_shadow(light, verts, 64, receivers=receivers)
            np.testing.assert_allclose(blocked.frustum.far, whole.frustum.far, rtol=1e-12)
