"""Soft shadows: Heckbert and Herf's pyramid matrix, and stratified area-light samples.

The geometry is built independently (points on rays from the apex, on the side
planes, on the plane through the apex) and the matrix must send it where the
issue says: corners to the unit square, rays to one (x, y), sides to x, y in
{0, 1}, the base to z = 0, the apex plane to w = 0, and w > 0 in between.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import shadowmath as sm


def f64(x: Any) -> np.ndarray:
    return np.asarray(x, dtype=np.float64)


def eps_of(dtype: Any) -> float:
    return float(np.finfo(dtype).eps)


def vec3(lo: float = -1, hi: float = 1) -> st.SearchStrategy[np.ndarray]:
    return st.lists(st.floats(lo, hi), min_size=3, max_size=3).map(np.array)


class Pyramid(NamedTuple):
    apex: np.ndarray
    corner: np.ndarray
    edge_u: np.ndarray
    edge_v: np.ndarray


@st.composite
def pyramids(draw: st.DrawFn) -> Pyramid:
    """A parallelogram at scale 1e-3..1e3 (up to 100 sizes from the origin) and an apex
    off its plane by 1e-2 to 10 sizes, on either side, anywhere above or beside it."""
    scale = 10.0 ** draw(st.integers(-3, 3))
    eu = draw(vec3()) * scale * draw(st.floats(0.3, 3))
    ev = draw(vec3()) * scale * draw(st.floats(0.3, 3))
    n = np.cross(eu, ev)
    if (
        np.linalg.norm(n) < 0.3 * np.linalg.norm(eu) * np.linalg.norm(ev)
        or min(np.linalg.norm(eu), np.linalg.norm(ev)) < 0.1 * scale
    ):
        eu, ev = np.array([1.0, 0.2, 0.0]) * scale, np.array([0.3, 1.5, 0.1]) * scale
        n = np.cross(eu, ev)
    corner = draw(vec3()) * scale * draw(st.sampled_from([0.0, 1.0, 100.0]))
    height = 10.0 ** draw(st.floats(-2, 1)) * scale * draw(st.sampled_from([1.0, -1.0]))
    foot = corner + draw(st.floats(-1, 2)) * eu + draw(st.floats(-1, 2)) * ev
    apex = foot + height * n / np.linalg.norm(n)
    return Pyramid(apex, corner, eu, ev)


def in_dtype(to: Any, pyr: Pyramid) -> Pyramid:
    """The pyramid as the dtype under test holds it (so the geometry is exact for it)."""
    return Pyramid(*(f64(to(v)) for v in pyr))


def tolerance(pyr: Pyramid, dtype: Any) -> float:
    """A few ulps times the condition: coordinates' size over the pyramid's thinnest dimension."""
    a, b, eu, ev = pyr
    area = np.linalg.norm(np.cross(eu, ev))
    height = abs(np.cross(ev, eu) @ (b - a)) / area
    thinnest = min(height, area / np.linalg.norm(eu), area / np.linalg.norm(ev))
    size = np.linalg.norm(a) + np.linalg.norm(b) + np.linalg.norm(eu) + np.linalg.norm(ev)
    return 64 * eps_of(dtype) * (size / thinnest) ** 2


def apply(M: Any, p: np.ndarray) -> np.ndarray:
    """(X, Y, Z, W) of points p (..., 3), computed in float64."""
    return np.einsum("ij,...j->...i", f64(M), np.concatenate([p, np.ones((*p.shape[:-1], 1))], -1))


uv_strategy = st.lists(st.floats(-0.5, 1.5), min_size=16, max_size=16).map(
    lambda v: np.array(v).reshape(8, 2)
)


@given(pyramids())
def test_base_corners_go_to_the_unit_square_on_z_0(to: Any, dtype: Any, pyr: Pyramid) -> None:
    pyr = in_dtype(to, pyr)
    _, b, eu, ev = pyr
    M = sm.pyramid_to_unit_cube(*(to(v) for v in pyr))
    assert M.shape == (4, 4) and M.dtype == dtype
    corners = np.array([b, b + eu, b + ev, b + eu + ev])
    q = apply(M, corners)
    tol = tolerance(pyr, dtype)
    np.testing.assert_allclose(q[:, 3], 1.0, atol=tol)  # w = 1 on the base: positive
    np.testing.assert_allclose(
        q[:, :3] / q[:, 3:], [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], atol=tol
    )


@given(pyramids(), uv_strategy, st.lists(st.floats(0.01, 3), min_size=8, max_size=8))
def test_points_on_a_ray_from_the_apex_share_x_y(
    to: Any, dtype: Any, pyr: Pyramid, uv: np.ndarray, lam: list[float]
) -> None:
    pyr = in_dtype(to, pyr)
    a, b, eu, ev = pyr
    M = sm.pyramid_to_unit_cube(*(to(v) for v in pyr))
    base = b + uv[:, :1] * eu + uv[:, 1:] * ev  # on the base plane (inside or outside)
    lam_ = np.array(lam)[:, None]
    p = a + lam_ * (base - a)  # between the apex plane and the base for lam <= 1
    q = apply(M, p)
    tol = tolerance(pyr, dtype)
    np.testing.assert_allclose(q[:, :2] / q[:, 3:], uv, atol=tol * np.max(1 / lam_))
    np.testing.assert_allclose(q[:, 3], lam_[:, 0], atol=tol * np.max(lam_))  # w = lam > 0
    np.testing.assert_allclose(q[:, 2] / q[:, 3], 1 / lam_[:, 0] - 1, atol=tol / np.min(lam_) ** 2)


@given(pyramids(), st.lists(st.floats(0.0, 1.0), min_size=8, max_size=8))
def test_sides_go_to_x_0_x_1_y_0_y_1(to: Any, dtype: Any, pyr: Pyramid, v: list[float]) -> None:
    pyr = in_dtype(to, pyr)
    a, b, eu, ev = pyr
    M = sm.pyramid_to_unit_cube(*(to(x) for x in pyr))
    t = np.array(v)[:, None]
    lam = 0.1 + 0.9 * t[::-1]  # a point of each side, between apex and base
    tol = tolerance(pyr, dtype) * 10
    sides = {
        (0, 0.0): b + t * ev,  # the side through a, b, b + ev
        (0, 1.0): b + eu + t * ev,
        (1, 0.0): b + t * eu,
        (1, 1.0): b + ev + t * eu,
    }
    for (coord, value), on_base in sides.items():
        q = apply(M, a + lam * (on_base - a))
        np.testing.assert_allclose(q[:, coord] / q[:, 3], value, atol=tol)


@given(pyramids(), uv_strategy)
def test_the_plane_through_the_apex_goes_to_w_0(
    to: Any, dtype: Any, pyr: Pyramid, uv: np.ndarray
) -> None:
    pyr = in_dtype(to, pyr)
    a, _, eu, ev = pyr
    M = sm.pyramid_to_unit_cube(*(to(v) for v in pyr))
    p = a + uv[:, :1] * eu + uv[:, 1:] * ev
    q = apply(M, p)
    np.testing.assert_allclose(q[:, 3], 0.0, atol=tolerance(pyr, dtype))
    # ... where Z = 1 - W stays 1: the points go to infinity, z -> +inf.
    np.testing.assert_allclose(q[:, 2], 1.0, atol=tolerance(pyr, dtype))


@given(pyramids())
def test_the_inside_of_the_pyramid_maps_into_the_unit_box_with_positive_w(
    to: Any, dtype: Any, pyr: Pyramid
) -> None:
    pyr = in_dtype(to, pyr)
    a, b, eu, ev = pyr
    M = sm.pyramid_to_unit_cube(*(to(v) for v in pyr))
    rng = np.random.default_rng(7)
    u, v, lam = rng.uniform(size=(3, 200, 1))
    lam = 0.02 + 0.98 * lam
    q = apply(M, a + lam * (b + u * eu + v * ev - a))
    assert np.all(q[:, 3] > 0)
    x = q[:, :3] / q[:, 3:]
    tol = tolerance(pyr, dtype) * 50
    assert np.all((x[:, :2] >= -tol) & (x[:, :2] <= 1 + tol))
    assert np.all(x[:, 2] >= -tol)
    # Beyond the base (behind the receiver), z is negative: a near plane at -eps clips it.
    q = apply(M, a + 1.5 * (b + u * eu + v * ev - a))
    assert np.all(q[:, 2] / q[:, 3] < 0)


@pytest.mark.parametrize("batch", [(), (1,), (3, 1, 2)])
def test_batches_broadcast_and_match_one_at_a_time(batch: tuple[int, ...]) -> None:
    rng = np.random.default_rng(1)
    apex = rng.normal(size=(*batch, 3)) + [0, 0, 5]
    corner = rng.normal(size=(2, 3)) * 0.1 - [1, 1, 0]  # broadcasts against batch's last 2
    eu, ev = np.array([2.0, 0, 0]), np.array([0, 2.0, 0.1])
    if batch == (3, 1, 2):
        M = sm.pyramid_to_unit_cube(apex, corner, eu, ev)
        assert M.shape == (3, 1, 2, 4, 4)
        for idx in np.ndindex(*batch):
            np.testing.assert_array_equal(
                M[idx], sm.pyramid_to_unit_cube(apex[idx], corner[idx[-1]], eu, ev)
            )
    else:
        M = sm.pyramid_to_unit_cube(apex, corner[0], eu, ev)
        assert M.shape == (*batch, 4, 4)


# ------------------------------------------------------------------ samples


def light_uv(samples: np.ndarray, corner: Any, eu: Any, ev: Any) -> tuple[np.ndarray, ...]:
    """Parallelogram coordinates (u, v) and the out-of-plane residual of each sample."""
    E = np.stack([eu, ev], axis=-1)  # (3, 2)
    uv, *_ = np.linalg.lstsq(E, (samples - corner).T, rcond=None)
    residual = np.linalg.norm(samples - corner - (E @ uv).T, axis=-1)
    return uv[0], uv[1], residual


GRIDS = {1: (1, 1), 2: (1, 2), 4: (2, 2), 6: (2, 3), 7: (1, 7), 12: (3, 4), 16: (4, 4)}
GRIDS |= {18: (3, 6), 64: (8, 8), 97: (1, 97), 100: (10, 10), 120: (10, 12)}


@pytest.mark.parametrize("count", sorted(GRIDS))
def test_one_sample_in_each_cell_of_the_most_nearly_square_grid(count: int) -> None:
    rows, cols = GRIDS[count]
    corner, eu, ev = (
        np.array([1.0, -2.0, 5.0]),
        np.array([3.0, 0.5, 0.0]),
        np.array([-1.0, 2.0, 1.0]),
    )
    samples = sm.area_light_samples(corner, eu, ev, count, seed=count)
    assert samples.shape == (count, 3)
    u, v, residual = light_uv(samples, corner, eu, ev)
    tol = 1e-13
    assert np.all(residual < tol * 10)  # in the light's plane
    k = np.arange(count)
    col, row = k % cols, k // cols
    assert np.all((u >= col / cols - tol) & (u <= (col + 1) / cols + tol))
    assert np.all((v >= row / rows - tol) & (v <= (row + 1) / rows + tol))
    # The jitter is not a constant offset: positions within cells vary.
    if count > 1:
        assert np.ptp(u * cols - col) > 0 and np.ptp(v * rows - row) >= 0


@given(
    st.sampled_from([1, 2, 7, 12, 40]),  # few shapes: each new one recompiles JAX's eager ops
    st.integers(0, 2**32 - 1),
    vec3(-10, 10),
    vec3(),
    vec3(),
)
def test_samples_lie_in_the_parallelogram(
    to: Any, dtype: Any, count: int, seed: int, corner: np.ndarray, eu: np.ndarray, ev: np.ndarray
) -> None:
    if (
        np.linalg.norm(np.cross(eu, ev)) < 0.2 * np.linalg.norm(eu) * np.linalg.norm(ev)
        or min(np.linalg.norm(eu), np.linalg.norm(ev)) < 0.05
    ):
        eu, ev = np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.5, 0.5])
    corner, eu, ev = (f64(to(x)) for x in (corner, eu, ev))
    s = sm.area_light_samples(to(corner), to(eu), to(ev), count, seed=seed)
    assert s.shape == (count, 3) and s.dtype == dtype
    u, v, residual = light_uv(f64(s), corner, eu, ev)
    size = np.linalg.norm(corner) + np.linalg.norm(eu) + np.linalg.norm(ev)
    sin = np.linalg.norm(np.cross(eu, ev)) / (np.linalg.norm(eu) * np.linalg.norm(ev))
    tol = 16 * eps_of(dtype) * size / (min(np.linalg.norm(eu), np.linalg.norm(ev)) * sin)
    assert np.all(residual <= tol * size)
    assert np.all((u >= -tol) & (u <= 1 + tol) & (v >= -tol) & (v <= 1 + tol))


def test_seeds_make_samples_reproducible() -> None:
    args = ([0.0, 0, 3], [1.0, 0, 0], [0, 1.0, 0], 9)
    a = sm.area_light_samples(*args, seed=42)
    np.testing.assert_array_equal(a, sm.area_light_samples(*args, seed=42))
    np.testing.assert_array_equal(a, sm.area_light_samples(*args, seed=np.random.default_rng(42)))
    assert not np.array_equal(a, sm.area_light_samples(*args, seed=43))
    assert not np.array_equal(sm.area_light_samples(*args), sm.area_light_samples(*args))


@pytest.mark.parametrize("count", [4, 16, 64, 256, 1024])
def test_the_mean_converges_to_the_centre_as_stratification_predicts(count: int) -> None:
    """Per axis the mean's error has a standard deviation of 1 / (sqrt(12 count) * cells)."""
    rows, cols = {4: (2, 2), 16: (4, 4), 64: (8, 8), 256: (16, 16), 1024: (32, 32)}[count]
    corner, eu, ev = np.zeros(3), np.array([1.0, 0, 0]), np.array([0, 1.0, 0])
    errors = []
    for seed in range(20):
        mean = sm.area_light_samples(corner, eu, ev, count, seed=seed).mean(axis=0)
        errors.append(mean[:2] - 0.5)
    err = np.array(errors)
    sigma = np.array([1 / (np.sqrt(12 * count) * cols), 1 / (np.sqrt(12 * count) * rows)])
    assert np.all(np.abs(err) < 6 * sigma)  # stratified: far below plain Monte Carlo's
    rms = np.sqrt(np.mean(err**2, axis=0))
    assert np.all(rms > 0.3 * sigma) and np.all(rms < 2 * sigma)


def test_batched_lights() -> None:
    corner = np.zeros((2, 1, 3)) + [[[0, 0, 1.0]], [[0, 0, 2.0]]]
    eu = np.array([[1.0, 0, 0], [2.0, 0, 0], [3.0, 0, 0]])
    s = sm.area_light_samples(corner, eu, [0, 1.0, 0], 5, seed=0)
    assert s.shape == (2, 3, 5, 3)
    np.testing.assert_array_equal(s[1, :, :, 2], 2.0)
    assert np.all(s[:, 2, :, 0] <= 3.0) and np.any(s[:, 2, :, 0] > 2.0)


def test_jax_key_variant_under_jit() -> None:
    fn = jax.jit(sm.area_light_samples, static_argnums=3)
    corner, eu, ev = jnp.asarray([1.0, 0, 0]), jnp.asarray([0, 2.0, 0]), jnp.asarray([0, 0, 3.0])
    key = jax.random.key(3)
    s = fn(corner, eu, ev, 12, key=key)
    assert isinstance(s, jax.Array) and s.shape == (12, 3)
    np.testing.assert_array_equal(s, fn(corner, eu, ev, 12, key=key))
    np.testing.assert_array_equal(s, sm.area_light_samples(corner, eu, ev, 12, key=key))
    assert not np.array_equal(s, fn(corner, eu, ev, 12, key=jax.random.split(key)[0]))
    u, v, _ = light_uv(np.asarray(s), [1.0, 0, 0], [0, 2.0, 0], [0, 0, 3.0])
    k = np.arange(12)
    assert np.all(
        (u * 4 >= k % 4) & (u * 4 <= k % 4 + 1) & (v * 3 >= k // 4) & (v * 3 <= k // 4 + 1)
    )
    # NumPy inputs and the legacy uint32 keys work too.
    s2 = sm.area_light_samples([0.0, 0, 0], [1.0, 0, 0], [0, 1.0, 0], 3, key=jax.random.PRNGKey(0))
    assert isinstance(s2, jax.Array) and s2.shape == (3, 3)


def test_the_old_name_of_the_keyed_samples_still_works_and_warns() -> None:
    key, corner, eu, ev = jax.random.key(5), [1.0, 0, 0], [0, 2.0, 0], [0, 0, 3.0]
    with pytest.warns(DeprecationWarning, match=r"area_light_samples\(\.\.\., key=key\)"):
        old = sm.area_light_samples_jax(key, corner, eu, ev, 6)
    np.testing.assert_array_equal(old, sm.area_light_samples(corner, eu, ev, 6, key=key))
    assert "area_light_samples_jax" not in sm.__all__  # still an attribute, no longer listed


def test_seed_and_key_together_are_refused() -> None:
    with pytest.raises(ValueError, match="seed, key: give one of them"):
        sm.area_light_samples(
            [0.0, 0, 0], [1.0, 0, 0], [0, 1.0, 0], 3, seed=1, key=jax.random.key(0)
        )


def test_samples_are_differentiable_in_the_light() -> None:
    key = jax.random.key(0)

    def mean_x(corner: Any) -> Any:
        s = sm.area_light_samples(
            corner, jnp.asarray([2.0, 0, 0]), jnp.asarray([0, 1.0, 0]), 8, key=key
        )
        return jnp.mean(s[:, 0])

    np.testing.assert_allclose(jax.grad(mean_x)(jnp.zeros(3)), [1.0, 0, 0])


# ------------------------------------------------------------------ pyramid, JAX


def test_pyramid_jit_vmap_grad() -> None:
    apex = np.array([0.2, -0.1, 3.0])
    args = (np.array([-1.0, -1.0, 0.0]), np.array([2.0, 0.0, 0.1]), np.array([0.0, 2.0, 0.0]))
    M = sm.pyramid_to_unit_cube(apex, *args)
    np.testing.assert_allclose(
        jax.jit(sm.pyramid_to_unit_cube)(jnp.asarray(apex), *args), M, rtol=1e-14, atol=1e-15
    )
    apices = apex + np.random.default_rng(0).normal(size=(4, 3)) * 0.1
    vm = jax.vmap(sm.pyramid_to_unit_cube, in_axes=(0, None, None, None))(
        jnp.asarray(apices), *args
    )
    np.testing.assert_allclose(vm, sm.pyramid_to_unit_cube(apices, *args), rtol=1e-14, atol=1e-15)

    p = jnp.asarray([0.3, 0.4, 1.0, 1.0])

    def x_of(a: Any) -> Any:
        q = sm.pyramid_to_unit_cube(a, *args) @ p
        return q[0] / q[3]

    g = np.asarray(jax.grad(x_of)(jnp.asarray(apex)))
    h = 1e-6
    fd = [(float(x_of(apex + h * e)) - float(x_of(apex - h * e))) / (2 * h) for e in np.eye(3)]
    np.testing.assert_allclose(g, fd, rtol=1e-7, atol=1e-10)


def test_bad_values_give_nan_under_jit() -> None:
    corner, eu = jnp.asarray([0.0, 0, 0]), jnp.asarray([1.0, 0, 0])
    apex = jnp.asarray([[0.0, 0, 1], [0.5, 0.5, 0.0]])  # the second in the base plane
    M = np.asarray(jax.jit(sm.pyramid_to_unit_cube)(apex, corner, eu, jnp.asarray([0, 1.0, 0])))
    assert np.all(np.isfinite(M[0])) and np.all(np.isnan(M[1]))
    ev = jnp.asarray([[0, 1.0, 0], [2.0, 0, 0]])  # the second parallel to eu
    M = np.asarray(
        jax.vmap(sm.pyramid_to_unit_cube, in_axes=(None, None, None, 0))(apex[0], corner, eu, ev)
    )
    assert np.all(np.isfinite(M[0])) and np.all(np.isnan(M[1]))
    fn = jax.jit(sm.area_light_samples, static_argnums=3)
    s = np.asarray(fn(corner, eu, ev, 4, key=jax.random.key(0)))
    assert np.all(np.isfinite(s[0])) and np.all(np.isnan(s[1]))


# ------------------------------------------------------------------ errors

A, B, EU, EV = [0.0, 0, 2], [0.0, 0, 0], [1.0, 0, 0], [0, 1.0, 0]


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: sm.pyramid_to_unit_cube(A, B, [0.0, 0, 0], EV), "edge_u, edge_v: the parallel"),
        (lambda: sm.pyramid_to_unit_cube(A, B, EU, [3.0, 0, 0]), "parallelogram is degenerate"),
        (lambda: sm.pyramid_to_unit_cube(A, B, EU, [1.0, 1e-15, 0]), "parallelogram is degenerate"),
        (lambda: sm.pyramid_to_unit_cube([5.0, 7, 0], B, EU, EV), "apex: lies in the base plane"),
        (
            lambda: sm.pyramid_to_unit_cube([5.0, 7, 1e-15], B, EU, EV),
            "apex: lies in the base plane",
        ),
        (lambda: sm.pyramid_to_unit_cube([0, np.nan, 1], B, EU, EV), "apex: contains non-finite"),
        (lambda: sm.pyramid_to_unit_cube(A, B, EU, [0, 1.0]), r"edge_v: expected shape"),
        (lambda: sm.area_light_samples(B, EU, EV, 0), "count: must be at least 1"),
        (lambda: sm.area_light_samples(B, EU, EV, -3), "count: must be at least 1"),
        (lambda: sm.area_light_samples(B, EU, EV, 2.0), "count: expected a positive integer"),
        (lambda: sm.area_light_samples(B, EU, EV, True), "count: expected a positive integer"),
        (lambda: sm.area_light_samples(B, EU, [2.0, 0, 0], 4), "parallelogram is degenerate"),
        (lambda: sm.area_light_samples(B, [0.0, 0, 0], EV, 4), "parallelogram is degenerate"),
        (lambda: sm.area_light_samples([np.inf, 0, 0], EU, EV, 4), "corner: contains non-finite"),
        (
            lambda: sm.area_light_samples(B, EU, EU, 4, key=jax.random.key(0)),
            "parallelogram is degenerate",
        ),
        (lambda: sm.area_light_samples(B, EU, EV, 0, key=jax.random.key(0)), "count: must be"),
    ],
)
def test_bad_input_raises_a_value_error_naming_the_argument(call: Any, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        call()


def test_the_apex_threshold_is_relative_to_scale() -> None:
    """1e-9 off a parallelogram of size 1e-6 is a pyramid; 1e-13 off one of size 1e3 is not."""
    sm.pyramid_to_unit_cube([0, 0, 1e-9], [0, 0, 0], [1e-6, 0, 0], [0, 1e-6, 0])
    with pytest.raises(ValueError, match="apex: lies in the base plane"):
        sm.pyramid_to_unit_cube([0, 0, 1e-13], [0, 0, 0], [1e3, 0, 0], [0, 1e3, 0])
