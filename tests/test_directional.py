"""Homogeneous and directional lights in ``fit_shadow``, and the orthographic Frustum."""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import shadowmath as sm

BOX = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (4, 6)], dtype=float)


def _ndc(M: np.ndarray, pts: np.ndarray) -> np.ndarray:
    clip = np.c_[pts, np.ones(len(pts))] @ np.asarray(M).T
    return clip[:, :3] / clip[:, 3:]


def _direction(seed: int) -> np.ndarray:
    v = np.random.default_rng(seed).normal(size=3)
    return v / np.linalg.norm(v)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), size=st.sampled_from([(64, 64), (100, 50), (257, 31)]))
def test_directional_fit_is_orthographic_and_touches_the_margins(
    seed: int, size: tuple[int, int]
) -> None:
    rng = np.random.default_rng(seed)
    verts = rng.normal(size=(20, 3)) * rng.uniform(0.1, 10, 3) + rng.normal(size=3) * 50
    toward = _direction(seed) * rng.uniform(0.01, 100)
    s = sm.fit_shadow(np.r_[toward, 0.0], verts, size)
    assert bool(s.frustum.orthographic)
    np.testing.assert_array_equal(s.blocker_to_clip[3], [0, 0, 0, 1])  # affine
    np.testing.assert_allclose(s.frame.z_axis, -toward / np.linalg.norm(toward), atol=1e-15)
    ndc = _ndc(s.blocker_to_clip, verts)
    mx, my = sm.border_margin(size)
    tol = 1e-12
    # Every vertex inside the margins, some vertex on each of the four sides.
    assert np.all(np.abs(ndc[:, 0]) <= mx + tol) and np.all(np.abs(ndc[:, 1]) <= my + tol)
    for axis, m in ((0, mx), (1, my)):
        assert abs(ndc[:, axis].max() - m) < tol and abs(ndc[:, axis].min() + m) < tol
    # Inside the depth range, every vertex in front of the frame's origin.
    assert np.all(np.abs(ndc[:, 2]) < 1)
    z = (verts - s.frame.origin) @ s.frame.z_axis
    assert np.all(z > 0)
    # The left-handed frame of the point lights: X x Y = -Z.
    f = s.frame
    np.testing.assert_allclose(np.cross(f.x_axis, f.y_axis), -f.z_axis, atol=1e-15)


def test_homogeneous_point_light_is_the_point_light() -> None:
    a = sm.fit_shadow(np.array([0.5, -0.2, 0.1]), BOX, 128)
    b = sm.fit_shadow(np.array([1.0, -0.4, 0.2, 2.0]), BOX, 128)
    np.testing.assert_allclose(b.blocker_to_clip, a.blocker_to_clip, rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(b.world_to_texture, a.world_to_texture, rtol=1e-13, atol=1e-13)
    assert not bool(b.frustum.orthographic)


def test_mixed_batch_selects_per_entry() -> None:
    lights = np.array([[0.0, 0.0, 0.0, 1.0], [0.2, 0.3, -1.0, 0.0]])
    s = sm.fit_shadow(lights, BOX, 64)
    np.testing.assert_array_equal(s.frustum.orthographic, [False, True])
    for i in range(2):
        one = sm.fit_shadow(lights[i], BOX, 64)
        np.testing.assert_allclose(s.blocker_to_clip[i], one.blocker_to_clip, atol=1e-14)
    np.testing.assert_array_equal(s.blocker_to_clip[:, 3], [[0, 0, 1, 0], [0, 0, 0, 1]])


def test_orthographic_frustum_projection() -> None:
    fr = sm.Frustum(2.0, 1.0, 1.0, 5.0, 0.98, 0.96, 0.5, -0.25, True)  # positional, as before
    sx, sy, n, f = 0.98 / 2.0, 0.96 / 1.0, 1.0, 5.0
    expected = np.array(
        [
            [sx, 0, 0, -sx * 0.5],
            [0, sy, 0, -sy * -0.25],
            [0, 0, 2 / (f - n), -(f + n) / (f - n)],
            [0, 0, 0, 1],
        ]
    )
    np.testing.assert_allclose(sm.blocker_projection(fr), expected, rtol=1e-15)
    T = np.array([[0.5, 0, 0, 0.5], [0, 0.5, 0, 0.5], [0, 0, 0.5, 0.5], [0, 0, 0, 1]])
    np.testing.assert_allclose(sm.receiver_projection(fr), T @ expected, rtol=1e-15)
    # The perspective default is unchanged, and a boolean array selects per entry.
    persp = sm.Frustum(2.0, 1.0, 1.0, 5.0, 0.98, 0.96)
    both = sm.blocker_projection(persp._replace(orthographic=np.array([False, True])))
    np.testing.assert_allclose(both[0], sm.blocker_projection(persp), rtol=1e-15)
    np.testing.assert_allclose(
        both[1], sm.blocker_projection(fr._replace(x_offset=0.0, y_offset=0.0))
    )


def test_zero_directional_light_raises_and_poisons() -> None:
    with pytest.raises(ValueError, match="light_position: zero directional light"):
        sm.fit_shadow(np.zeros(4), BOX, 64)
    lights = jnp.asarray([[0.2, 0.3, -1.0, 0.0], [0.0, 0.0, 0.0, 0.0]])
    out = jax.jit(lambda L: sm.fit_shadow(L, jnp.asarray(BOX), 64))(lights)
    assert bool(jnp.all(jnp.isfinite(out.blocker_to_clip[0])))
    assert bool(jnp.all(jnp.isnan(out.blocker_to_clip[1])))


@pytest.mark.parametrize("light", [[0.2, 0.3, -1.0, 0.0], [0.0, 0.0, 0.0, 1.0]])
def test_jax_matches_numpy_and_gradients_are_finite(light: Any) -> None:
    ref = sm.fit_shadow(np.array(light), BOX, 64)
    got = sm.fit_shadow(jnp.asarray(light), jnp.asarray(BOX), 64)
    np.testing.assert_allclose(np.asarray(got.blocker_to_clip), ref.blocker_to_clip, atol=1e-12)

    def loss(L: Any, V: Any) -> Any:
        return jnp.sum(sm.fit_shadow(L, V, 64).world_to_texture)

    grads = jax.grad(loss, argnums=(0, 1))(jnp.asarray(light), jnp.asarray(BOX))
    assert all(bool(jnp.all(jnp.isfinite(g))) for g in grads)
