"""The fast core's paths agree, and its design stays fast.

``fit_shadow`` has two implementations of the same formulas (``_formulas``):
the compiled loop (NumPy input with Numba) and the array path (JAX, or NumPy
without Numba). Across the fuzz they give the same setups to rounding and the
same errors word for word. Deterministic guards of the design: the jitted fit
traces to a bounded number of primitives (validation cannot creep back into the
hot path), concrete JAX input runs through one cached jit, and a batch sharded
over two devices runs unchanged.
"""

from __future__ import annotations

import contextlib
import importlib.util
import os
import re
import subprocess
import sys
import textwrap
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

import shadowmath as sm
from shadowmath._backends import _kernels

from .strategies import invalid_placements, placements, sized_maps

DTYPES = pytest.mark.parametrize("dtype", [np.float64, np.float32], ids=["f64", "f32"])


def array_path() -> contextlib.AbstractContextManager[None]:
    """Run on whole arrays (no compiled loop) inside the block."""
    return _kernels.array_path()


def test_numba_is_installed_for_the_compiled_path() -> None:
    # The dev install includes the `fast` extra: without it these tests compare a path with
    # itself. Installed, not necessarily enabled: SHADOWMATH_NUMBA=0 runs the suite without it.
    assert importlib.util.find_spec("numba") is not None


def _rigid(rng: np.random.Generator, scale: float) -> np.ndarray:
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    B = np.eye(4)
    B[:3, :3] = q * np.sign(np.linalg.det(q))
    B[:3, 3] = rng.normal(size=3) * scale
    return B


def _helper(frame: sm.LightFrame) -> int:
    """The helper axis a fit *used*: ``X = normalize(Z x e_k)`` has ``X_k = 0`` exactly.

    (``helper_axis`` of the returned, rounded ``Z`` may differ from the one decided on
    the fit's own unrounded ``Z`` at a near tie.)
    """
    return int(np.argmin(np.abs(np.asarray(frame.x_axis, np.float64))))


LOOPS = pytest.mark.parametrize("loop", ["compiled", "python"])


def _loop(loop: str) -> contextlib.AbstractContextManager[None]:
    """The compiled loop, or the same loop run by Python (one small fit without Numba)."""
    return contextlib.nullcontext() if loop == "compiled" else _kernels.disabled()


@LOOPS
@DTYPES
@given(data=st.data())
def test_compiled_loop_equals_array_path(loop: str, dtype: Any, data: st.DataObject) -> None:
    p = data.draw(placements(dtype))
    map_size, border = data.draw(sized_maps())
    aim = data.draw(st.sampled_from(["mean", "bbox"]))
    light, verts = p.light.astype(dtype), p.vertices.astype(dtype)
    options: dict[str, Any] = {"border_texels": border, "aim": aim}
    if data.draw(st.booleans()):  # a rigid placement: the vertices become local coordinates
        B = _rigid(np.random.default_rng(data.draw(st.integers(0, 2**32 - 1))), p.scale)
        verts = ((verts.astype(np.float64) - B[:3, 3]) @ B[:3, :3]).astype(dtype)
        options["blocker_to_world"] = B.astype(dtype)
    with array_path():
        try:
            ref = sm.fit_shadow(light, verts, map_size, **options)
        except ValueError:  # aim="bbox" may leave a vertex behind the light: not this test's
            assume(False)
    with _loop(loop):
        fast = sm.fit_shadow(light, verts, map_size, **options)
    eps = float(np.finfo(dtype).eps)
    # The scene's condition (as in test_fuzz): coordinates' size over the blocker's, + ratio.
    r = np.linalg.norm(p.vertices - p.vertices.mean(0), axis=-1).max()
    kappa = (np.abs(p.light).max() + np.abs(p.vertices).max()) / r + p.distance_ratio
    # The compiled loop sums in float64: its Z differs from the array path's by the
    # array path's rounding, and at a helper-axis tie the two may pick different axes.
    np.testing.assert_allclose(fast.frame.z_axis, ref.frame.z_axis, rtol=0, atol=64 * eps * kappa)
    assume(_helper(fast.frame) == _helper(ref.frame))
    tol = 64 * eps * kappa * p.distance_ratio
    # Compared where they act: on the scene's points, relative to |M_i| |p| + |t_i| per
    # row i (M's linear rows are rounded relative to their norms, not entry by entry: an
    # axis entry that is 0 in one fit is a rounding residue in the other).
    pts = np.concatenate([light[None], verts]).astype(np.float64)
    norms = np.linalg.norm(pts, axis=-1)
    pts = np.c_[pts, np.ones(len(pts))].T
    for name in ("world_to_light", "blocker_to_clip", "world_to_texture"):
        a, b = (
            np.asarray(getattr(fast, name), np.float64),
            np.asarray(getattr(ref, name), np.float64),
        )
        rows = np.linalg.norm(a[:, :3], axis=-1) + np.linalg.norm(b[:, :3], axis=-1)
        bound = rows[:, None] * norms + (np.abs(a[:, 3]) + np.abs(b[:, 3]))[:, None]
        assert np.all(np.abs(a @ pts - b @ pts) <= tol * bound), name
    for field in ("rx_max", "ry_max", "near", "far"):
        np.testing.assert_allclose(
            getattr(fast.frustum, field), getattr(ref.frustum, field), rtol=tol
        )
    floats = (*fast[2:6], *fast.frame, *fast.frustum[:8])  # (casters_used: integers)
    assert all(np.asarray(v).dtype == dtype for v in floats)
    assert type(fast.frustum) is type(ref.frustum) is sm.Frustum  # a 3-vector light


@LOOPS
@given(bad=invalid_placements())
def test_both_paths_raise_the_same_error(loop: str, bad: Any) -> None:
    bad = bad._replace(message=bad.message.replace("light_position:", "light:"))  # its name
    with _loop(loop), pytest.raises(ValueError, match=re.escape(bad.message)) as fast:
        sm.fit_shadow(*bad.args, 64)
    with array_path(), pytest.raises(ValueError, match=re.escape(bad.message)) as ref:
        sm.fit_shadow(*bad.args, 64)
    assert str(fast.value) == str(ref.value)


@pytest.mark.parametrize(
    ("light_shape", "verts_shape"),
    [((3,), (5, 8, 3)), ((4, 1, 3), (1, 2, 8, 3)), ((2, 3), (2, 8, 3)), ((3, 1, 3), (2, 8, 3))],
)
def test_batches_broadcast_the_same_on_both_paths(
    light_shape: tuple[int, ...], verts_shape: tuple[int, ...]
) -> None:
    rng = np.random.default_rng(7)
    light = rng.normal(size=light_shape)
    verts = rng.normal(size=verts_shape) + [0.0, 0.0, 10.0]
    near = np.full(light_shape[:-1], 2.0)  # a batched argument of its own
    fast = sm.fit_shadow(light, verts, 64, near=near)
    with array_path():
        ref = sm.fit_shadow(light, verts, 64, near=near)
    shape = np.broadcast_shapes(light_shape[:-1], verts_shape[:-2])
    assert fast.blocker_to_clip.shape == (*shape, 4, 4)
    np.testing.assert_allclose(fast.blocker_to_clip, ref.blocker_to_clip, rtol=1e-12, atol=1e-12)
    L = np.broadcast_to(light, (*shape, 3))
    V = np.broadcast_to(verts, (*shape, *verts_shape[-2:]))
    for index in np.ndindex(*shape):  # each entry is the unbatched fit on the same path
        with array_path():
            one = sm.fit_shadow(L[index], V[index], 64, near=2.0)
        np.testing.assert_array_equal(ref.world_to_texture[index], one.world_to_texture)
        if _kernels.available():  # (without Numba one small fit runs the loop in Python)
            one = sm.fit_shadow(L[index], V[index], 64, near=2.0)
            np.testing.assert_array_equal(fast.world_to_texture[index], one.world_to_texture)


#: Top-level primitives of the jitted fit of one light and 8 vertices: 552 before the
#: rewrite (over half of them validation bookkeeping: 7 conversions, 38 checks), 434
#: after it, of which the value checks are about 40 and about 80 are the per-component
#: slices that let XLA fuse each pass over the vertices into one loop (the 4M-vertex
#: fit: 315 ms before them, 90 ms after); 465 with the checks of degenerate fits (the
#: caster within rounding of the light, the field of view: per entry, not per vertex).
#: The bound leaves room for small changes, not for a second round of validation.
MAX_FIT_PRIMITIVES = 480


def test_jitted_fit_stays_small() -> None:
    light = jnp.zeros(3)
    verts = jnp.asarray(np.random.default_rng(1).normal(size=(8, 3)) + [0, 0, 6])
    jaxpr = jax.make_jaxpr(lambda L, V: sm.fit_shadow(L, V, 256))(light, verts)
    assert len(jaxpr.jaxpr.eqns) <= MAX_FIT_PRIMITIVES


def test_concrete_jax_runs_one_cached_jit_and_raises_eagerly() -> None:
    light = jnp.zeros(3)
    verts = jnp.asarray(np.random.default_rng(2).normal(size=(8, 3)) + [0, 0, 6])
    setup = sm.fit_shadow(light, verts, 256)
    assert isinstance(setup.blocker_to_clip, jax.Array)
    on_numpy = sm.fit_shadow(np.asarray(light), np.asarray(verts), 256)
    np.testing.assert_allclose(
        setup.blocker_to_clip, on_numpy.blocker_to_clip, rtol=1e-12, atol=1e-12
    )
    from shadowmath._fits.shadow._driver import _jitted_fit

    before = _jitted_fit.cache_info().currsize
    sm.fit_shadow(light + 1.0, verts, 256)
    assert _jitted_fit.cache_info().currsize == before  # the same compiled function
    with pytest.raises(ValueError, match="not strictly in front of the light"):
        sm.fit_shadow(jnp.asarray([0.0, 0.0, 6.0]), verts, 256)


def test_a_batch_sharded_over_two_devices_runs_unchanged() -> None:
    script = textwrap.dedent(
        """
        import jax, numpy as np
        from jax.sharding import Mesh, NamedSharding, PartitionSpec as P
        import shadowmath as sm
        assert len(jax.devices()) == 2
        rng = np.random.default_rng(3)
        lights = rng.normal(size=(64, 3)).astype(np.float32)
        verts = (rng.normal(size=(64, 8, 3)) + [0, 0, 10]).astype(np.float32)
        mesh = Mesh(np.array(jax.devices()), ("batch",))
        L = jax.device_put(lights, NamedSharding(mesh, P("batch")))
        V = jax.device_put(verts, NamedSharding(mesh, P("batch")))
        out = jax.jit(lambda L, V: sm.fit_shadow(L, V, 256).blocker_to_clip)(L, V)
        assert len(out.sharding.device_set) == 2, out.sharding
        ref = sm.fit_shadow(lights, verts, 256).blocker_to_clip
        np.testing.assert_allclose(np.asarray(out), ref, rtol=2e-5, atol=2e-5)
        print("ok")
        """
    )
    env = {**os.environ, "XLA_FLAGS": "--xla_force_host_platform_device_count=2"}
    env["JAX_PLATFORMS"] = "cpu"
    run = subprocess.run(
        [sys.executable, "-c", script], env=env, capture_output=True, text=True, timeout=300
    )
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == "ok"


@DTYPES
@given(data=st.data())
def test_bounds_about_a_point_are_the_per_vertex_bounds(dtype: Any, data: st.DataObject) -> None:
    # One pass keeps the world points' bounds; the bounds about any point o, the reach
    # and the coordinates' size follow exactly (fl(p - o) is monotone in p).
    from shadowmath._math._specialize import formulas

    n = data.draw(st.integers(1, 40))
    values = st.floats(-1e6, 1e6, width=32 if dtype is np.float32 else 64)
    p = np.asarray(data.draw(st.lists(values, min_size=3 * n, max_size=3 * n)), dtype)
    p = p.reshape(n, 3)
    o = np.asarray(data.draw(st.lists(values, min_size=3, max_size=3)), dtype)
    lo_o, hi_o, reach, coords = formulas(np).bounds_about(
        tuple(p.min(0)), tuple(p.max(0)), tuple(o)
    )
    d = p - o
    np.testing.assert_array_equal(np.array(lo_o), d.min(0))
    np.testing.assert_array_equal(np.array(hi_o), d.max(0))
    assert reach == np.abs(d).max()
    assert coords == np.abs(p).max()


def test_compiled_passes_give_the_per_vertex_bounds_in_any_order() -> None:
    # The compiled passes keep their bounds and sums in vector lanes (reordered): the
    # bounds are exact whatever the order, the sums equal to rounding, and a NaN vertex
    # still reaches the status word.
    from shadowmath._boundary._status import VERTICES

    loops = _kernels.loops()
    rng = np.random.default_rng(5)
    V = (rng.normal(size=(100_003, 3)) * [2.0, 1.0, 0.5] + [1.0, 0.5, 10.0]).astype(np.float32)
    P = V.astype(np.float64)
    o, none = (0.25, -0.5, 0.125), (0.0,) * 16
    sums, lo, hi, status, n = loops.spread((V.reshape(-1), none, False), o)
    assert (status, n) == (0, len(V))
    np.testing.assert_array_equal(lo, P.min(0))
    np.testing.assert_array_equal(hi, P.max(0))
    np.testing.assert_allclose(sums, (P - o).sum(0), rtol=1e-13)
    a = tuple(np.linalg.qr(rng.normal(size=(3, 3)))[0].T.ravel().tolist())
    bounds = loops.light_pass((V.reshape(-1), none, False), o, a, True)
    q = P - o
    x, y, z = (
        q[:, 0] * a[3 * i] + q[:, 1] * a[3 * i + 1] + q[:, 2] * a[3 * i + 2] for i in range(3)
    )
    inv = 1.0 / np.where(z > 0, z, 1.0)
    rx, ry = x * inv, y * inv
    expected = (rx.max(), rx.min(), ry.max(), ry.min(), z.max(), z.min())
    assert bounds == expected
    V[77_777, 1] = np.nan
    assert loops.spread((V.reshape(-1), none, False), o)[3] & VERTICES
    assert np.isnan(loops.light_pass((V.reshape(-1), none, False), o, a, True)[2])
