"""Stable directional maps take their size from the blocker's minimal enclosing sphere.

So the size depends on the shape only: not on how its faces are tessellated, not on
points inside it, not on how it is turned about its centre. The reference for the
sphere is a brute force independent of Welzl's algorithm: the smallest of the spheres
through 2, 3 or 4 of the points (diameter, circumcircle, circumsphere) that hold them all.
"""

from __future__ import annotations

import contextlib
import itertools
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import shadowmath as sm
from shadowmath._backends import _kernels

W = 256
PATHS = {
    "compiled": contextlib.nullcontext,
    "python loop": _kernels.disabled,
    "array path": _kernels.array_path,
}
SUN = sm.DirectionalLight(np.array([0.3, 1.0, -0.2]))


def _radius(s: sm.ShadowSetup) -> float:
    """The sphere's radius from the stable map's half-width ``h (1 - 1 / (m W)) = r``."""
    m = float(s.frustum.margin_x)
    return float(s.frustum.half_width) * (1 - 1 / (m * W))


def _sphere(points: np.ndarray) -> tuple[np.ndarray, float]:
    """Centre and radius of the sphere through 2 to 4 points (the smallest such)."""
    p0, d = points[0], points[1:] - points[0]
    G = d @ d.T
    lam = np.linalg.lstsq(G, 0.5 * np.diag(G), rcond=None)[0]
    c = p0 + lam @ d
    return c, float(np.linalg.norm(c - p0))


def _brute_force(points: np.ndarray) -> float:
    best = np.inf
    for k in (2, 3, 4):
        for idx in itertools.combinations(range(len(points)), k):
            c, r = _sphere(points[list(idx)])
            if r < best and np.all(np.linalg.norm(points - c, axis=1) <= r * (1 + 1e-9)):
                best = r
    return best


def _box_surface(half: np.ndarray, n: int) -> np.ndarray:
    """A box's surface sampled on an ``n^3`` grid (its 8 corners among the points)."""
    g = np.linspace(-1, 1, n)
    grid = np.array(list(itertools.product(g, g, g)))
    return grid[np.abs(grid).max(axis=1) == 1] * half


@pytest.mark.parametrize("path", PATHS)
@pytest.mark.parametrize("seed", range(5))
def test_the_radius_is_the_minimal_enclosing_spheres(path: str, seed: int) -> None:
    rng = np.random.default_rng(seed)
    points = rng.normal(size=(9, 3)) * rng.uniform(0.5, 3, 3) + rng.normal(size=3) * 10
    with PATHS[path]():
        s = sm.fit_shadow(SUN, points, W, stable=True)
    np.testing.assert_allclose(_radius(s), _brute_force(points), rtol=1e-9)


@pytest.mark.parametrize("path", PATHS)
def test_the_size_depends_on_the_shape_only(path: str) -> None:
    half = np.array([2.0, 1.0, 0.5])
    rng = np.random.default_rng(7)
    corners = _box_surface(half, 2)  # 8 vertices
    fine = _box_surface(half, 9)  # 386 vertices on the faces
    inner = np.r_[corners, rng.uniform(-1, 1, (500, 3)) * half]  # and 500 inside
    shuffled = fine[rng.permutation(len(fine))]
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    sizes = []
    with PATHS[path]():
        for v in (corners, fine, inner, shuffled, corners @ q.T + 5.0, fine @ q.T - 3.0):
            sizes.append(float(sm.fit_shadow(SUN, v, W, stable=True).frustum.half_width))
    np.testing.assert_allclose(sizes, sizes[0], rtol=1e-12)
    np.testing.assert_allclose(_radius_of(sizes[0]), np.linalg.norm(half), rtol=1e-12)
    tight = sm.fit_shadow(SUN, corners, W)
    assert sizes[0] > float(tight.frustum.half_width)  # the price of stability


def _radius_of(half_width: float) -> float:
    return half_width * (1 - 1 / (sm.border_margin(W)[0] * W))


def test_jax_value_and_gradient_follow_the_support_points() -> None:
    rng = np.random.default_rng(3)
    points = rng.normal(size=(12, 3))

    def half(v: Any) -> Any:
        return sm.fit_shadow(
            sm.DirectionalLight(jnp.asarray(SUN.direction)), v, W, stable=True
        ).frustum.half_width

    value = jax.jit(half)(jnp.asarray(points))
    np.testing.assert_allclose(
        value, sm.fit_shadow(SUN, points, W, stable=True).frustum.half_width, rtol=1e-12
    )
    g = np.asarray(jax.grad(half)(jnp.asarray(points)))
    h = 1e-6
    fd = np.zeros_like(g)
    for idx in np.ndindex(*points.shape):
        e = np.zeros(points.shape)
        e[idx] = h
        fd[idx] = (half(jnp.asarray(points + e)) - half(jnp.asarray(points - e))) / (2 * h)
    np.testing.assert_allclose(g, fd, atol=1e-6)
    assert 2 <= np.count_nonzero(np.abs(g).sum(axis=1)) <= 4  # only the support points move it
    batch = np.stack([points, points * 2.0])
    vm = jax.vmap(half)(jnp.asarray(batch))
    np.testing.assert_allclose(vm, [value, 2 * value], rtol=1e-12)


@pytest.mark.parametrize("path", PATHS)
@pytest.mark.parametrize("seed", range(4))
def test_four_support_points(path: str, seed: int) -> None:
    # A regular tetrahedron's minimal sphere passes through all four corners (its
    # circumsphere, radius a sqrt(6) / 4): every level of Welzl's algorithm is needed.
    rng = np.random.default_rng(seed)
    a = 2.0 * np.sqrt(2.0)  # corners (+-1, +-1, +-1) with an even number of minus signs
    tet = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], dtype=float)
    inside = rng.uniform(-0.3, 0.3, (40, 3))
    points = np.r_[tet, inside][rng.permutation(44)]
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    with PATHS[path]():
        s = sm.fit_shadow(SUN, points @ q.T + rng.normal(size=3), W, stable=True)
    np.testing.assert_allclose(_radius(s), a * np.sqrt(6) / 4, rtol=1e-12)


#: Found by the fuzz (tests/test_fuzz.py): a repeated vertex, far from the origin.
DUPLICATE = np.array([
    [0.5988462126346276, 0.03972210748165899, -0.2924567509650886],
    [0.5988462126346276, 0.03972210748165899, -0.2924567509650886],
    [-0.7819084623568421, -0.2571922406188707, 0.00814218051834351],
    [-0.2756029052993704, 1.2940638143982073, 1.0067243153057943],
    [-2.7111624789659685, -1.8890132459676727, -0.17477209205516195],
    [-0.42219041157635356, 0.2136429974986111, 0.21732193102256359],
])  # fmt: skip


@pytest.mark.parametrize("path", PATHS)
@pytest.mark.parametrize("offset", [1e3, 1e4, 1e6])
def test_a_repeated_vertex_far_from_the_origin_changes_nothing(path: str, offset: float) -> None:
    # A vertex repeated (or within rounding of another) must not become a second
    # support point: the sphere through two equal points is ill-posed.
    radius = _brute_force(np.unique(DUPLICATE, axis=0))
    light = sm.DirectionalLight(np.random.default_rng(0).normal(size=3))
    rng = np.random.default_rng(1)
    with PATHS[path]():
        for v in (DUPLICATE, DUPLICATE[::-1], DUPLICATE[rng.permutation(6)]):
            s = sm.fit_shadow(light, v + [0.0, offset, 0.0], W, stable=True)
            np.testing.assert_allclose(_radius(s), radius, rtol=1e-6)


def test_the_batched_support_finds_each_entrys_minimal_sphere(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # Without Numba a batch's supports come from the support-set iteration over every
    # entry at once (_math/_ball_support.py): the sphere through them is, per entry, the
    # brute force's (random clouds, coplanar and cospherical sets, a box's 8 corners on
    # one sphere, repeated points, 20 points on a sphere: supports of 4 that grow), and
    # it holds every point. Welzl's loop, its fallback, must not be needed.
    from shadowmath._math import _ball_support
    from shadowmath._math._specialize import formulas

    monkeypatch.setattr(_ball_support, "scalar_formulas", None)
    monkeypatch.setattr(_ball_support, "LOOPED", 1)
    rng = np.random.default_rng(11)
    on_sphere = rng.normal(size=(6, 20, 3))
    batches = [
        rng.normal(size=(12, 7, 3)) * rng.uniform(0.5, 3, (12, 1, 3)) + rng.normal(size=(12, 1, 3)),
        np.concatenate([rng.normal(size=(6, 7, 2)), np.full((6, 7, 1), 3.0)], axis=-1),
        np.repeat(_box_surface(np.array([2.0, 1.0, 0.5]), 2)[None, ::-1], 3, axis=0),
        np.repeat(rng.normal(size=(6, 3, 3)), 3, axis=1) + 1e4,
        on_sphere / np.linalg.norm(on_sphere, axis=-1, keepdims=True),
    ]  # fmt: skip
    sizes = set()
    for sets in batches:
        rows = _ball_support.support_arrays(sets)
        q = sets[np.arange(len(sets))[:, None], rows[:, :4]]
        cx, cy, cz, r2 = formulas(np).sphere_through(
            tuple(q[:, j // 3, j % 3] for j in range(12)), rows[:, 4]
        )
        expected = [_brute_force(np.unique(s, axis=0)) for s in sets]
        np.testing.assert_allclose(np.sqrt(r2), expected, rtol=1e-9)
        centres = np.stack([cx, cy, cz], axis=-1)[:, None]
        far = np.linalg.norm(sets - centres, axis=-1).max(axis=1)
        np.testing.assert_allclose(far, np.sqrt(r2), rtol=1e-9)
        sizes |= set(rows[:, 4].tolist())
    assert sizes == {2, 3, 4}
