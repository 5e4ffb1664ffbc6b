"""NumPy and JAX through one implementation: types, dtypes, jit, vmap, grad, mixed inputs."""

from __future__ import annotations

import subprocess
import sys
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import shadowmath as sm

rng = np.random.default_rng(11)
VERTS = rng.normal(size=(16, 3)) + [0.0, 0.0, 8.0]
LIGHT = np.array([0.5, -0.3, 0.0])
PLANE = np.array([0.0, 1.0, 0.0, 2.0])
LIGHT4 = np.array([0.3, 5.0, 0.1, 1.0])


def test_import_does_not_import_jax_or_moderngl() -> None:
    code = (
        "import sys, shadowmath, numpy as np\n"
        "shadowmath.fit_shadow([0, 0, 0], np.eye(3) + [0, 0, 5], 64)\n"
        "shadowmath.planar_projection([0, 1, 0, 0], [0, 3, 0, 1])\n"
        "assert 'jax' not in sys.modules, 'jax imported'\n"
        "assert 'moderngl' not in sys.modules, 'moderngl imported'\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def every_function(xp_array: Any) -> dict[str, Any]:
    """Run each public function on converted inputs; return their array outputs."""
    light, verts = xp_array(LIGHT), xp_array(VERTS)
    frame = sm.light_frame(light, verts)
    frustum = sm.adaptive_frustum(frame, verts, (64, 32))
    setup = sm.fit_shadow(light, verts, 64)
    return {
        "planar": sm.planar_projection(xp_array(PLANE), xp_array(LIGHT4)),
        "mdv": sm.mean_direction_vector(light, verts),
        "helper": sm.helper_axis(xp_array([0.2, -0.9, 0.1])),
        "x_axis": frame.x_axis,
        "from_direction": sm.light_frame_from_direction(light, xp_array([0, 0, 1])).y_axis,
        "world_to_light": sm.world_to_light(frame),
        "light_to_world": sm.light_to_world(frame),
        "rx_max": frustum.rx_max,
        "blocker_projection": sm.blocker_projection(frustum),
        "receiver_projection": sm.receiver_projection(frustum),
        "blocker_to_clip": setup.blocker_to_clip,
        "world_to_texture": setup.world_to_texture,
        "receiver": sm.receiver_texture_matrix(setup, xp_array(np.eye(4))),
    }


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_numpy_in_numpy_out_and_dtype_kept(dtype: Any) -> None:
    for name, out in every_function(lambda x: np.asarray(x, dtype=dtype)).items():
        assert isinstance(out, np.ndarray | np.generic), name
        assert out.dtype == dtype, name


@pytest.mark.parametrize("dtype", [jnp.float32, jnp.float64])
def test_jax_in_jax_out_and_dtype_kept(dtype: Any) -> None:
    for name, out in every_function(lambda x: jnp.asarray(x, dtype=dtype)).items():
        assert isinstance(out, jax.Array), name
        assert out.dtype == dtype, name


def test_integers_and_lists_become_float64() -> None:
    for name, out in every_function(lambda x: np.asarray(np.round(x), dtype=np.int64)).items():
        assert out.dtype == np.float64, name
    assert sm.planar_projection([0, 1, 0, 0], [0, 3, 0, 1]).dtype == np.float64


def test_float16_is_promoted_to_float32() -> None:
    out = sm.planar_projection(np.float16([0, 1, 0, 0]), np.float16([0, 3, 0, 1]))
    assert out.dtype == np.float32


def test_numpy_and_jax_agree() -> None:
    a = every_function(np.asarray)
    b = every_function(jnp.asarray)
    for name in a:
        np.testing.assert_allclose(np.asarray(b[name]), a[name], rtol=1e-13, atol=1e-14)


def test_jit_equals_numpy() -> None:
    @jax.jit
    def run(light: Any, verts: Any, plane: Any, light4: Any) -> Any:
        s = sm.fit_shadow(light, verts, (128, 64))
        return s.blocker_to_clip, s.world_to_texture, sm.planar_projection(plane, light4)

    got = run(LIGHT, VERTS, PLANE, LIGHT4)
    s = sm.fit_shadow(LIGHT, VERTS, (128, 64))
    want = (s.blocker_to_clip, s.world_to_texture, sm.planar_projection(PLANE, LIGHT4))
    for g, w in zip(got, want, strict=True):
        np.testing.assert_allclose(np.asarray(g), w, rtol=1e-12, atol=1e-13)


def test_vmap_equals_batching() -> None:
    lights = rng.normal(size=(5, 3))
    got = jax.vmap(lambda light: sm.fit_shadow(light, VERTS, 64).world_to_texture)(lights)
    want = sm.fit_shadow(lights, VERTS, 64).world_to_texture
    np.testing.assert_allclose(np.asarray(got), want, rtol=1e-12, atol=1e-13)
    planes = rng.normal(size=(5, 4)) + [0, 0, 0, 5]
    got = jax.vmap(sm.planar_projection, in_axes=(0, None))(planes, LIGHT4)
    np.testing.assert_allclose(np.asarray(got), sm.planar_projection(planes, LIGHT4), rtol=1e-12)


def test_mixed_numpy_plane_with_traced_light_under_grad() -> None:
    def shadow_x(light4: Any) -> Any:
        M = sm.planar_projection(PLANE, light4)  # NumPy plane, traced light
        p = M @ jnp.array([1.0, 1.0, 0.0, 1.0])
        return p[0] / p[3]

    g = jax.grad(shadow_x)(jnp.asarray(LIGHT4))
    # the shadow of (1, 1, 0) on y = -2 from light (lx, ly, lz): x = lx + (1 - lx) t,
    # t = (ly + 2) / (ly - 1); check d/dlx against the closed form.
    lx, ly = LIGHT4[0], LIGHT4[1]
    t = (ly + 2) / (ly - 1)
    assert np.isfinite(np.asarray(g)).all()
    np.testing.assert_allclose(float(g[0]), 1 - t, rtol=1e-10)
    dt_dly = ((ly - 1) - (ly + 2)) / (ly - 1) ** 2
    np.testing.assert_allclose(float(g[1]), (1 - lx) * dt_dly, rtol=1e-10)


def test_invalid_input_raises_eagerly_and_is_nan_under_jit() -> None:
    on_plane = np.array([0.0, -2.0, 0.0, 1.0])  # the light lies in the plane y = -2
    with pytest.raises(ValueError, match="light lies in the plane"):
        sm.planar_projection(PLANE, on_plane)
    with pytest.raises(ValueError, match="light lies in the plane"):
        sm.planar_projection(jnp.asarray(PLANE), jnp.asarray(on_plane))  # concrete JAX: eager
    out = jax.jit(sm.planar_projection)(PLANE, on_plane)
    assert np.isnan(np.asarray(out)).all()
    # a batch poisons only its bad entries
    lights = np.stack([on_plane, LIGHT4])
    out = np.asarray(jax.jit(sm.planar_projection)(PLANE, lights))
    assert np.isnan(out[0]).all()
    np.testing.assert_allclose(out[1], sm.planar_projection(PLANE, LIGHT4))
    # the light inside the blocker: a fit cannot exist
    bad = jax.jit(lambda light: sm.fit_shadow(light, VERTS, 64).blocker_to_clip)(VERTS.mean(0))
    assert np.isnan(np.asarray(bad)).all()


def test_shape_errors_name_the_argument() -> None:
    with pytest.raises(ValueError, match=r"light: expected shape \(\*batch, 4\)"):
        sm.planar_projection(PLANE, [0, 3, 0])
    with pytest.raises(ValueError, match=r"vertices: expected shape \(\*batch, N, 3\)"):
        sm.light_frame(LIGHT, [1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="batch dimensions do not broadcast"):
        sm.planar_projection(np.ones((2, 4)), np.ones((3, 4)))
    with pytest.raises(ValueError, match="map_size"):
        sm.fit_shadow(LIGHT, VERTS, 2)
    with pytest.raises(ValueError, match="empty"):
        sm.fit_shadow(LIGHT, np.zeros((0, 3)), 64)


def test_column_major_bytes_is_the_transpose_in_memory() -> None:
    M = sm.fit_shadow(LIGHT, VERTS, 64).blocker_to_clip
    raw = np.frombuffer(sm.column_major_bytes(M), dtype=np.float32)
    np.testing.assert_array_equal(raw.reshape(4, 4, order="F"), M.astype(np.float32))
    # GLSL's mat4 * vec4 sums over columns: element (row r) = sum_c raw[4 c + r] v[c]
    v = np.array([1.0, 2.0, 3.0, 1.0], np.float32)
    glsl = np.array([sum(raw[4 * c + r] * v[c] for c in range(4)) for r in range(4)])
    np.testing.assert_allclose(glsl, M.astype(np.float32) @ v, rtol=1e-5)
    batch = np.stack([M, 2 * M])
    assert sm.column_major_bytes(batch)[64:] == sm.column_major_bytes(2 * M)
    with pytest.raises(ValueError, match="non-finite"):
        sm.column_major_bytes(np.full((4, 4), np.nan))
