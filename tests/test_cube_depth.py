"""sm.cube_depth_range: a point light's cube-map near/far against the faces as drawn.

The geometry, independently of the formula: every point is pushed through the six faces'
views (sm.cube_face_views, checked against the Vulkan tables in test_cube) and a face
"draws" it where it falls inside that face's window, border ring included
(|x_v|, |y_v| <= -z_v / k). Every caster drawn anywhere must lie at a view depth in
[near, far], and so must every receiver point (for far), with near and far tight to
the drawn extremes.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

import shadowmath as sm

SLACK = sm.NEAR_FAR_SLACK


def drawn_depths(light: np.ndarray, points: np.ndarray, k: float) -> np.ndarray:
    """View depths ``-z_v`` of every (face, point) pair the face's window holds."""
    V = np.asarray(sm.cube_face_views(light), dtype=np.float64)
    view = np.einsum("fij,nj->fni", V, np.c_[points, np.ones(len(points))])
    depth = -view[..., 2]
    inside = (depth > 0) & (np.abs(view[..., 0]) * k <= depth) & (np.abs(view[..., 1]) * k <= depth)
    return depth[inside]


def scene(seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A light, casters around it, and a floor of two triangles far below."""
    rng = np.random.default_rng(seed)
    light = rng.uniform(-3, 3, 3)
    casters = light + rng.uniform(-4, 4, (40, 3))
    casters = casters[np.abs(casters - light).max(axis=1) > 0.5]
    z = light[2] - 12.0
    floor = np.array(
        [[[-30, -30, z], [30, -30, z], [30, 30, z]], [[-30, -30, z], [30, 30, z], [-30, 30, z]]]
    )
    return light, casters, floor


def samples(triangles: np.ndarray, count: int = 2000) -> np.ndarray:
    """Points spread over the triangles (corners and edges included)."""
    rng = np.random.default_rng(1)
    u, v = rng.uniform(0, 1, (2, count))
    flip = u + v > 1
    u, v = np.where(flip, 1 - u, u), np.where(flip, 1 - v, v)
    t = rng.integers(0, len(triangles), count)
    A, B, C = triangles[t, 0], triangles[t, 1], triangles[t, 2]
    inner = A + u[:, None] * (B - A) + v[:, None] * (C - A)
    return np.concatenate([inner, triangles.reshape(-1, 3)])


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("border", [0, 3])
def test_every_drawn_caster_and_receiver_lies_in_the_range(seed, border):
    light, casters, floor = scene(seed)
    size = 64
    k = (size - 2 * border) / size
    near, far = sm.cube_depth_range(
        light, casters, receivers=sm.Triangles(floor), map_size=size, border_texels=border
    )
    near, far = float(near), float(far)
    cast = drawn_depths(light, casters, k)
    received = drawn_depths(light, samples(floor), k)
    assert cast.min() >= near and cast.max() <= far and received.max() <= far
    # Tight: within the slack of the drawn extremes (the ring lets a face draw a caster
    # nearer than its own face does, down to k D).
    assert near >= (1 - SLACK) * k * cast.min() * (1 - 1e-12)
    assert far <= (1 + SLACK) * max(cast.max(), received.max()) * (1 + 1e-12)
    if border == 0:  # without a ring, the nearest drawn caster is the nearest caster
        assert near == pytest.approx((1 - SLACK) * cast.min(), rel=1e-14)


def test_the_ring_needs_k():
    """A caster near a face's 45-degree edge is drawn by the neighbour's ring nearer than
    its D, down to k D: a near plane of D (without k) would clip it there."""
    light = np.zeros(3)
    casters = np.array([[1.0, 0.9, 0.0], [0.2, 0.0, -3.0]])  # D = 1 (+X), 0.9 along +Y
    size, border = 32, 4
    k = (size - 2 * border) / size
    near = float(sm.cube_depth_range(light, casters, map_size=size, border_texels=border).near)
    cast = drawn_depths(light, casters, k)
    assert cast.min() < 1.0  # the ring shows the edge caster nearer than its D
    assert near <= cast.min()
    plain = float(sm.cube_depth_range(light, casters).near)
    assert plain > cast.min()  # the same range without the ring would lose it


def test_receivers_only_push_far():
    light, casters, floor = scene(0)
    bare = sm.cube_depth_range(light, casters)
    near_floor = floor.copy()
    near_floor[..., 2] = light[2] - 0.1  # nearer the light than any caster
    tiny = near_floor.copy()
    tiny[..., :2] = light[:2] + 0.05 * np.sign(near_floor[..., :2])  # a small patch under it
    with_floor = sm.cube_depth_range(light, casters, receivers=sm.Triangles(floor))
    with_patch = sm.cube_depth_range(light, casters, receivers=sm.Triangles(tiny))
    assert float(with_floor.near) == float(bare.near) == float(with_patch.near)
    assert float(with_floor.far) > float(bare.far)  # the floor's corners reach farther
    assert float(with_patch.far) == float(bare.far)  # the patch lies inside the range


def test_receiver_kinds_agree():
    light, casters, floor = scene(2)
    vertices, faces = floor.reshape(-1, 3), np.arange(6).reshape(2, 3)
    tri = sm.cube_depth_range(light, casters, receivers=sm.Triangles(floor))
    mesh = sm.cube_depth_range(light, casters, receivers=sm.Mesh(vertices, faces))
    points = sm.cube_depth_range(light, casters, receivers=vertices)
    for other in (mesh, points):
        assert float(other.near) == float(tri.near) and float(other.far) == float(tri.far)


def test_batches_broadcast_like_singles():
    lights = np.stack([scene(s)[0] for s in range(3)])  # (3, 3)
    casters = scene(0)[1][:20]  # shared
    floors = np.stack([scene(s)[2] for s in range(3)])[:, None]  # (3, 1, 2, 3, 3): (3, 1)
    got = sm.cube_depth_range(lights[:, None], casters, receivers=sm.Triangles(floors))
    assert got.near.shape == got.far.shape == (3, 1)
    for i in range(3):
        one = sm.cube_depth_range(lights[i], casters, receivers=sm.Triangles(floors[i, 0]))
        assert float(got.near[i, 0]) == float(one.near) and float(got.far[i, 0]) == float(one.far)


def test_the_atlas_fits_its_cube_faces_with_the_same_range():
    light, casters, floor = scene(3)
    atlas = sm.allocate_atlas([0.5], atlas_size=1024, cube=[True], border_texels=2)
    fit = sm.fit_atlas(sm.PointLight(light), casters, atlas, receivers=sm.Triangles(floor))
    size = int(atlas.light_size[0])
    want = sm.cube_depth_range(
        light, casters, receivers=sm.Triangles(floor), map_size=size, border_texels=2
    )
    np.testing.assert_array_equal(fit.near, np.full(6, float(want.near)))
    np.testing.assert_array_equal(fit.far, np.full(6, float(want.far)))


def test_float32_stays_float32():
    light, casters, _ = scene(4)
    got = sm.cube_depth_range(light.astype(np.float32), casters.astype(np.float32))
    assert got.near.dtype == got.far.dtype == np.float32


ORIGIN, AWAY = [0.0, 0.0, 0.0], [0.0, 0.0, 9.0]
BAD_CALLS = {
    "casters: a caster lies at": lambda c: sm.cube_depth_range(ORIGIN, c),
    "light_position: contains non-finite": lambda c: sm.cube_depth_range([np.nan, 0, 0], c + 1),
    "light_position: expected shape": lambda c: sm.cube_depth_range([0.0, 0.0], c),
    "casters: the vertex set is empty": lambda c: sm.cube_depth_range(AWAY, c[:0]),
    "receivers= takes points": lambda c: sm.cube_depth_range(AWAY, c, receivers=c[:, :2]),
    "receivers: contains non-finite": lambda c: sm.cube_depth_range(
        AWAY, c, receivers=c + np.array([np.inf, 0, 0])
    ),
    "map_size: a border ring": lambda c: sm.cube_depth_range(AWAY, c, border_texels=2),
    "leaves no inner texel": lambda c: sm.cube_depth_range(AWAY, c, map_size=4, border_texels=2),
    "border_texels: must be >= 0": lambda c: sm.cube_depth_range(AWAY, c, border_texels=-1),
    "map_size: expected an integer": lambda c: sm.cube_depth_range(
        AWAY, c, map_size=8.0, border_texels=1
    ),
    "casters: expected shape": lambda c: sm.cube_depth_range(AWAY, sm.Triangles(c)),
    "casters.faces: indices must lie": lambda c: sm.cube_depth_range(AWAY, sm.Mesh(c, [[0, 1, 2]])),
    "batch dimensions do not broadcast": lambda c: sm.cube_depth_range(
        np.zeros((2, 3)) + 9, np.stack([c] * 3)
    ),
}


@pytest.mark.parametrize("message", list(BAD_CALLS))
def test_bad_input_is_named(message):
    casters = np.array([[0.0, 0.0, 0.0], [1.0, 2.0, 3.0]])
    with pytest.raises(ValueError, match=re.escape(message)):
        BAD_CALLS[message](casters)


def test_caster_within_rounding_of_the_light_is_refused_scale_free():
    casters = np.array([[1e6, 0.0, 0.0], [2e6, 1e6, 0.0]])
    light = casters[0] + np.array([0.0, 0.0, 1e-9])  # 1e-15 of the scene: rounding
    with pytest.raises(ValueError, match="a caster lies at the cube light's position"):
        sm.cube_depth_range(light, casters)
    near = sm.cube_depth_range(casters[0] + np.array([0.0, 0.0, 1e-3]), casters).near
    assert float(near) == pytest.approx(1e-3 * (1 - SLACK), rel=1e-6)  # 1e-9 of the scene: fine


def test_jax_jit_grad_and_nan():
    jax = pytest.importorskip("jax")  # in the dev extra: never skipped on CI
    jnp = jax.numpy
    light, casters, floor = scene(5)
    if True:  # float64: tests/conftest.py enables x64
        fn = jax.jit(lambda L, c, f: tuple(sm.cube_depth_range(L, c, receivers=sm.Triangles(f))))
        got = fn(jnp.asarray(light), jnp.asarray(casters), jnp.asarray(floor))
        want = sm.cube_depth_range(light, casters, receivers=sm.Triangles(floor))
        assert float(got[0]) == float(want.near) and float(got[1]) == float(want.far)

        # grad of near + far in the light's position against central differences
        def total(L):
            r = sm.cube_depth_range(L, jnp.asarray(casters), receivers=sm.Triangles(floor))
            return r.near + r.far

        g = np.asarray(jax.grad(total)(jnp.asarray(light)))
        h = 1e-6
        fd = [
            (float(total(jnp.asarray(light + h * e))) - float(total(jnp.asarray(light - h * e))))
            / (2 * h)
            for e in np.eye(3)
        ]
        np.testing.assert_allclose(g, fd, rtol=1e-6, atol=1e-9)
        # A caster at the light: NaN value and NaN gradient under jit, never a silent range.
        at = jnp.asarray(casters[0])
        bad = jax.jit(lambda L: sm.cube_depth_range(L, jnp.asarray(casters)).near)(at)
        assert np.isnan(float(bad))
        assert np.all(
            np.isnan(
                np.asarray(
                    jax.grad(lambda L: sm.cube_depth_range(L, jnp.asarray(casters)).near)(at)
                )
            )
        )
        # Triangle casters under jit: the same exact minimum.
        tri = jax.jit(lambda L, t: sm.cube_depth_range(L, sm.Triangles(t)).near)
        triangles = light + np.random.default_rng(7).uniform(-6, 6, (30, 3, 3))
        assert float(tri(jnp.asarray(light), jnp.asarray(triangles))) == pytest.approx(
            float(sm.cube_depth_range(light, sm.Triangles(triangles)).near), rel=1e-14
        )
        # vmap: only the bad entry is NaN
        both = jax.vmap(lambda L: sm.cube_depth_range(L, jnp.asarray(casters)).far)(
            jnp.stack([at, jnp.asarray(light)])
        )
        assert np.isnan(float(both[0])) and float(both[1]) == float(
            sm.cube_depth_range(light, casters).far
        )


def lp_min_chebyshev(triangle: np.ndarray, light: np.ndarray) -> float:
    """min over the triangle of max |p - light|, as a linear program (independent of the
    package's candidate points): minimise t over (u, v, t) with -t <= A + u e1 + v e2 - L
    <= t componentwise, u, v >= 0, u + v <= 1."""
    from scipy.optimize import linprog

    A, B, C = triangle
    a, e1, e2 = A - light, B - A, C - A
    rows, rhs = [], []
    for i in range(3):
        for sign in (1.0, -1.0):  # sign (a_i + u e1_i + v e2_i) <= t
            rows.append([sign * e1[i], sign * e2[i], -1.0])
            rhs.append(-sign * a[i])
    rows.append([1.0, 1.0, 0.0])
    rhs.append(1.0)
    res = linprog([0, 0, 1], A_ub=rows, b_ub=rhs, bounds=[(0, 1), (0, 1), (0, None)],
                  method="highs")  # fmt: skip
    assert res.status == 0
    return float(res.fun)


@pytest.mark.parametrize("seed", range(4))
def test_triangle_casters_count_their_whole_surface(seed):
    """Random triangles around the light, many passing nearer it than their corners: near
    is k (1 - s) times the linear program's minimum, exactly; points would miss it."""
    rng = np.random.default_rng(seed)
    light = rng.uniform(-1, 1, 3)
    triangles = light + rng.uniform(-6, 6, (30, 3, 3))
    want = min(lp_min_chebyshev(t, light) for t in triangles)
    got = sm.cube_depth_range(light, sm.Triangles(triangles))
    assert float(got.near) == pytest.approx((1 - SLACK) * want, rel=1e-9)
    by_corners = sm.cube_depth_range(light, triangles.reshape(-1, 3))
    assert float(by_corners.near) > float(got.near)  # the corners alone are farther
    assert float(got.far) == float(by_corners.far)  # the largest D is at a corner
    mesh = sm.Mesh(triangles.reshape(-1, 3), np.arange(90).reshape(30, 3))
    assert float(sm.cube_depth_range(light, mesh).near) == float(got.near)


def crowd(seed: int, walls: int) -> tuple[np.ndarray, np.ndarray]:
    """Three lights and 150 triangles around them: small ones (many passing nearer the
    light than their corners by a little) and ``walls`` a few units across (nearer by a
    lot)."""
    rng = np.random.default_rng(seed)
    lights = rng.uniform(-1, 1, (3, 3))
    small = rng.uniform(-4, 4, (150 - walls, 1, 3)) + rng.normal(0, 0.5, (150 - walls, 3, 3))
    big = rng.uniform(-3, 3, (walls, 1, 3)) + rng.uniform(-4, 4, (walls, 3, 3))
    return lights, np.concatenate([small, big])[rng.permutation(150)]


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("walls", [0, 30])
def test_the_nearest_of_many_triangles_is_never_skipped(seed, walls):
    """Among many triangles, with the light batched: near is k (1 - s) times the smallest
    linear-program minimum over all of them (the brute-force reference), for each light,
    batched exactly as alone; jitted JAX (which weighs every triangle) agrees to the
    coordinates' rounding."""
    lights, triangles = crowd(seed, walls)
    got = sm.cube_depth_range(lights, sm.Triangles(triangles))
    for i, light in enumerate(lights):
        want = min(lp_min_chebyshev(t, light) for t in triangles)
        assert float(got.near[i]) == pytest.approx((1 - SLACK) * want, rel=1e-9)
        assert float(got.near[i]) == float(sm.cube_depth_range(light, sm.Triangles(triangles)).near)
    jax = pytest.importorskip("jax")  # in the dev extra: never skipped on CI
    traced = jax.jit(lambda L, t: sm.cube_depth_range(L, sm.Triangles(t)).near)
    rounding = 16 * np.finfo(float).eps * np.abs(triangles).max()  # of the coordinates
    np.testing.assert_allclose(traced(lights, triangles), got.near, rtol=0, atol=rounding)


def test_a_wall_a_hair_nearer_than_every_corner_counts():
    """A wall in the plane x = 1 across the light's axis (its corners 5 away, its nearest
    point 1 + 1e-9 away, the whole wall beyond x = 1 by that hair) beside pebbles whose
    nearest corner is at 1 + 2e-9: near comes from the wall, among many triangles."""
    light = np.zeros(3)
    x = 1 + 1e-9
    wall = np.array([[x, -5, -5], [x, 5, -5], [x, 0, 5]])
    pebble = np.array([[-(1 + 2e-9), 0.2, 0.1], [-3, 2, 1], [-3, -2, 2]])
    offsets = np.random.default_rng(0).uniform(0, 3, (200, 1, 3)) * [[-1, 1, 1]]
    triangles = np.concatenate([wall[None], pebble + offsets, pebble[None]])
    got = sm.cube_depth_range(light, sm.Triangles(triangles))
    assert float(got.near) == (1 - SLACK) * x


def test_each_kind_of_nearest_point():
    """The three places the minimum can lie: a corner, an edge crossing r_i = +-r_j, a
    diagonal piercing the triangle; each against the linear program."""
    light = np.zeros(3)
    cases = {
        "corner": np.array([[1.0, 0.2, 0.1], [3, 2, 1], [3, -2, 2]]),
        "edge": np.array([[1.0, 3.0, 0.0], [1.0, -3.0, 0.5], [6.0, 0.0, 0.0]]),
        "diagonal": np.array([[3.0, 0.0, 0.0], [0.0, 3.0, 0.0], [0.0, 0.0, 3.0]]),
    }
    for name, triangle in cases.items():
        got = float(sm.cube_depth_range(light, sm.Triangles(triangle[None])).near)
        assert got == pytest.approx((1 - SLACK) * lp_min_chebyshev(triangle, light), rel=1e-12), (
            name
        )
    # the diagonal case: the plane x + y + z = 3 meets (t, t, t) at t = 1
    assert float(sm.cube_depth_range(light, sm.Triangles(cases["diagonal"][None])).near) == (
        pytest.approx(1 - SLACK, rel=1e-14)
    )


def test_the_atlas_counts_caster_triangles_near_its_cube_lights():
    """A wall beside a cube light, nearer than its corners: the atlas's faces keep it when
    the casters come as surfaces (the same near as cube_depth_range), not as points; its
    2D lights fit the same matrices either way (their projections hold the corners' hull)."""
    wall = np.array(
        [[[1.0, -5, -5], [1, 5, -5], [1, 0, 5]], [[3.0, -1, -1], [3, 1, -1], [3, 0, 2]]]
    )
    lights = [sm.PointLight(np.zeros(3)), sm.PointLight(np.array([0.0, 0.0, -20.0]))]
    atlas = sm.allocate_atlas([0.5, 0.5], atlas_size=2048, cube=[True, False], border_texels=2)
    surfaces = sm.fit_atlas(lights, sm.Triangles(wall), atlas)
    points = sm.fit_atlas(lights, wall.reshape(-1, 3), atlas)
    mesh = sm.fit_atlas(lights, sm.Mesh(wall.reshape(-1, 3), np.arange(6).reshape(2, 3)), atlas)
    size = int(atlas.light_size[0])
    want = sm.cube_depth_range(np.zeros(3), sm.Triangles(wall), map_size=size, border_texels=2)
    cube_tiles = atlas.light_tiles[0]
    np.testing.assert_array_equal(surfaces.near[cube_tiles], float(want.near))
    np.testing.assert_array_equal(mesh.near[cube_tiles], float(want.near))
    assert float(want.near) < 1.0 < float(points.near[cube_tiles[0]])  # corners: D >= 3
    flat = atlas.light_tiles[1, 0]
    np.testing.assert_array_equal(surfaces.world_to_clip[flat], points.world_to_clip[flat])
