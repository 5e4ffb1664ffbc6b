"""Blinn's planar projection: the properties that define a shadow onto a plane."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from shadowmath import planar_projection

from .conftest import rtol_for

coords = st.floats(-10, 10, allow_nan=False, width=32)
unit_ish = arrays(np.float64, 3, elements=st.floats(-1, 1, width=32)).filter(
    lambda n: 0.5 < np.linalg.norm(n) < 2
)


@st.composite
def scenes(draw: st.DrawFn, *, directional: bool = False) -> tuple[np.ndarray, ...]:
    """A plane, a light at least 1 unit off it (or not grazing it), points between them."""
    n = draw(unit_ish)
    d = draw(coords)
    plane = np.append(n, d)
    n_hat = n / np.linalg.norm(n)
    foot = -d * n / (n @ n)  # the point of the plane nearest the origin
    if directional:
        tangent = draw(arrays(np.float64, 3, elements=st.floats(-1, 1, width=32)))
        tangent -= (tangent @ n_hat) * n_hat
        toward = n_hat * draw(st.sampled_from([1.0, -1.0]))
        light = np.append(toward + tangent, 0.0)  # at least 45 degrees off grazing
        points = foot + draw(arrays(np.float64, (5, 3), elements=coords))
        return plane, light, points
    height = draw(st.floats(1, 10)) * draw(st.sampled_from([1.0, -1.0]))
    light_xyz = foot + draw(arrays(np.float64, 3, elements=coords)) * 0.5
    light_xyz = light_xyz + (height - (light_xyz - foot) @ n_hat) * n_hat
    t = draw(arrays(np.float64, 5, elements=st.floats(0.05, 0.95)))
    on_plane = foot + draw(arrays(np.float64, (5, 3), elements=coords))
    on_plane -= ((on_plane - foot) @ n_hat)[:, None] * n_hat
    points = on_plane + t[:, None] * (light_xyz - on_plane)  # strictly between
    return plane, np.append(light_xyz, 1.0), points


def homog(p: np.ndarray) -> np.ndarray:
    return np.concatenate([p, np.ones((*p.shape[:-1], 1))], axis=-1)


def project(M: Any, points: np.ndarray) -> np.ndarray:
    return np.einsum("ij,nj->ni", np.asarray(M, dtype=np.float64), homog(points))


@given(scenes())
def test_points_land_on_the_plane(to: Any, dtype: Any, scene: tuple[np.ndarray, ...]) -> None:
    plane, light, points = scene
    M = planar_projection(to(plane), to(light))
    assert M.dtype == dtype
    q = project(M, points)
    residual = q @ plane
    scale = np.linalg.norm(plane) * np.linalg.norm(q, axis=-1)
    np.testing.assert_array_less(np.abs(residual), 20 * rtol_for(dtype) * scale)


@given(scenes())
def test_shadow_lies_on_the_ray_from_the_light(to: Any, dtype: Any, scene: Any) -> None:
    plane, light, points = scene
    q = project(planar_projection(to(plane), to(light)), points)
    shadow = q[:, :3] / q[:, 3:]
    # light, point and shadow are collinear, the point between light and shadow
    a, b = points - light[:3], shadow - light[:3]
    cross = np.cross(a, b)
    tol = 50 * rtol_for(dtype) * np.linalg.norm(a, axis=-1) * np.linalg.norm(b, axis=-1)
    np.testing.assert_array_less(np.linalg.norm(cross, axis=-1), tol)
    assert np.all(np.einsum("ij,ij->i", a, b) > 0)
    assert np.all(np.linalg.norm(b, axis=-1) >= np.linalg.norm(a, axis=-1) * (1 - 1e-3))


@given(scenes(directional=True))
def test_directional_shadow_moves_along_the_light_direction(
    to: Any, dtype: Any, scene: Any
) -> None:
    plane, light, points = scene
    M = planar_projection(to(plane), to(light))
    q = project(M, points)
    shadow = q[:, :3] / q[:, 3:]
    # On the plane to rounding: of the terms of n.s + d, and of the projected point itself
    # (M p carries a few ulps of |M| |p|, which lands on the shadow).
    eps = float(np.finfo(dtype).eps)
    size = np.linalg.norm(shadow, axis=-1) + np.linalg.norm(points, axis=-1)
    terms = np.linalg.norm(plane[:3]) * size + abs(plane[3])
    # Below float32's normal range an ulp is absolute (the smallest subnormal), not relative.
    tiny = float(np.finfo(dtype).smallest_subnormal)
    assert np.all(np.abs(shadow @ plane[:3] + plane[3]) <= 64 * (eps * terms + tiny))
    offset = points - shadow
    cross = np.cross(offset, light[:3])
    tol = 100 * rtol_for(dtype) * (1 + np.linalg.norm(offset, axis=-1)) * np.linalg.norm(light)
    np.testing.assert_array_less(np.linalg.norm(cross, axis=-1), tol)


@given(scenes(), st.booleans())
def test_w_is_positive_between_light_and_plane_for_either_plane_sign(
    to: Any, dtype: Any, scene: Any, flip: bool
) -> None:
    plane, light, points = scene
    plane = -plane if flip else plane
    q = project(planar_projection(to(plane), to(light)), points)
    assert np.all(q[:, 3] > 0)


@given(scenes())
def test_anti_shadow_points_beyond_the_light_get_negative_w(scene: Any) -> None:
    plane, light, points = scene
    beyond = light[:3] + 2.0 * (light[:3] - points)  # same side of the plane, past the light
    q = project(planar_projection(plane, light), beyond)
    assert np.all(q[:, 3] < 0)


@given(scenes())
def test_light_is_the_null_vector_and_M_is_a_projection(to: Any, dtype: Any, scene: Any) -> None:
    plane, light, _ = scene
    M = np.asarray(planar_projection(to(plane), to(light)), dtype=np.float64)
    k = abs(plane @ light)
    scale = k * np.abs(M).max()
    np.testing.assert_allclose(M @ light, 0, atol=20 * rtol_for(dtype) * scale)
    np.testing.assert_allclose(M @ M, k * M, atol=20 * rtol_for(dtype) * scale * 4)
    assert np.linalg.matrix_rank(np.asarray(M, np.float64), tol=1e-3 * np.abs(M).max()) == 3


@given(scenes(), arrays(np.float64, (4, 3), elements=coords))
def test_points_on_the_plane_stay_fixed(scene: Any, offsets: np.ndarray) -> None:
    plane, light, _ = scene
    n = plane[:3]
    on_plane = offsets - ((offsets @ n + plane[3]) / (n @ n))[:, None] * n
    q = project(planar_projection(plane, light), on_plane)
    # Fixed to rounding: a few ulps of the coordinates involved (the point's and the light's).
    size = np.abs(on_plane).max() + np.abs(light[:3]).max()
    np.testing.assert_allclose(q[:, :3] / q[:, 3:], on_plane, rtol=0, atol=64 * 2.0**-52 * size)
    np.testing.assert_allclose(q[:, 3], abs(plane @ light), rtol=1e-9)


@given(scenes(), st.floats(0.1, 10), st.booleans())
def test_invariant_to_plane_sign_and_homogeneous_light_scale(
    scene: Any, k: float, negate: bool
) -> None:
    plane, light, _ = scene
    M = planar_projection(plane, light)
    scaled = -k * light if negate else k * light
    np.testing.assert_allclose(planar_projection(-2 * plane, light), 2 * M, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(planar_projection(plane, scaled), k * M, rtol=1e-9, atol=1e-9)


def test_floor_shadow_by_hand() -> None:
    # light at height 4 above the floor y = 0; a point at height 1 is 3/4 of the way down,
    # so its shadow is 4/3 as far from the light's foot.
    M = planar_projection([0, 1, 0, 0], [1, 4, 2, 1])
    q = M @ np.array([1 + 3.0, 1.0, 2 - 1.5, 1.0])
    np.testing.assert_allclose(q[:3] / q[3], [1 + 4.0, 0.0, 2 - 2.0])


@pytest.mark.parametrize(
    ("plane_shape", "light_shape"), [((4,), (4,)), ((3, 1, 4), (2, 4)), ((1, 4), (5, 1, 4))]
)
def test_batch_broadcasting_equals_a_loop(plane_shape: tuple[int, ...], light_shape: Any) -> None:
    rng = np.random.default_rng(1)
    planes = rng.normal(size=plane_shape)
    lights = rng.normal(size=light_shape) + np.array([0, 0, 0, 3.0])
    M = planar_projection(planes, lights)
    shape = np.broadcast_shapes(plane_shape[:-1], light_shape[:-1])
    assert M.shape == (*shape, 4, 4)
    pb = np.broadcast_to(planes, (*shape, 4))
    lb = np.broadcast_to(lights, (*shape, 4))
    for idx in np.ndindex(*shape):
        np.testing.assert_allclose(M[idx], planar_projection(pb[idx], lb[idx]), rtol=1e-14)
