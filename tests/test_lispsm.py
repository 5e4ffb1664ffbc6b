"""Light-space perspective warping of cascades (``fit_cascades(..., warp="lispsm")``).

The oracle of containment is SciPy's half-space intersection (Qhull) of each camera slice
with the scene box, computed from the slice's definition without shadowmath's code. The
texel density is measured from the matrices alone: the world area, in the plane
perpendicular to the light, that one texel covers at a point (the inverse of the
Jacobian of the texture coordinates ``(s / q, t / q)``).
"""

from __future__ import annotations

import importlib
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.optimize import linprog
from scipy.spatial import HalfspaceIntersection

import shadowmath as sm
from shadowmath._fits.cascades._lispsm import WARP_MIN_SIN

from .cameras import look_at, perspective
from .cameras import scene as _scene

SIZE = 1024
APIS = ["opengl", "vulkan", "direct3d", "metal", "webgpu"]


def scene(seed: int) -> tuple[np.ndarray, ...]:
    """:func:`tests.cameras.scene` with views tilted down by up to 0.3."""
    return _scene(seed, lowest_pitch=-0.3)


def horizon() -> tuple[np.ndarray, ...]:
    """A camera 2 m above the ground looking toward the horizon along +x, a sun from the side."""
    view = look_at([0.0, 2.0, 0.0], [10.0, 1.0, 0.0])
    proj = perspective(1.0, 16 / 9, 0.1, 100.0)
    box = np.array([[-200.0, -1.0, -200.0], [200.0, 12.0, 200.0]])
    return np.array([0.0, 1.0, 1.0]), view, proj, box


def body(view: np.ndarray, proj: np.ndarray, box: np.ndarray, a: float, b: float) -> np.ndarray:
    """Vertices of {camera slice a <= depth <= b} intersected with the box (Qhull)."""
    pv = proj @ view
    rows = [-(pv[3] - pv[0]), -(pv[3] + pv[0]), -(pv[3] - pv[1]), -(pv[3] + pv[1])]
    depth = -view[2]  # a right-handed camera's view depth is -z
    rows += [np.r_[-depth[:3], a - depth[3]], np.r_[depth[:3], depth[3] - b]]
    for i in range(3):
        e = np.eye(3)[i]
        rows += [np.r_[-e, box[0, i]], np.r_[e, -box[1, i]]]
    hs = np.array(rows)
    norms = np.linalg.norm(hs[:, :3], axis=1)
    res = linprog(
        np.r_[0, 0, 0, -1], A_ub=np.c_[hs[:, :3], norms], b_ub=-hs[:, 3],
        bounds=[(None, None)] * 3 + [(0, None)],
    )  # fmt: skip
    assert res.status == 0 and res.x[3] > 1e-6, "the slice misses the box"
    return np.asarray(HalfspaceIntersection(hs, res.x[:3]).intersections)


def homogeneous(m: np.ndarray, p: np.ndarray) -> np.ndarray:
    return np.asarray(np.c_[p, np.ones(len(p))] @ m.T)


def texel_size(tex: np.ndarray, p: np.ndarray, sun: np.ndarray) -> np.ndarray:
    """The side of a square of one texel's area, in the plane perpendicular to the light.

    ``(s, t) = (h_0, h_1) / h_3`` with ``h = M p``, so
    ``d(s, t) / dp = (M_i - (s, t)_i M_3) / h_3``; restricted to two unit axes
    ``e_1, e_2`` perpendicular to the light it is a 2x2 ``J``,
    and a texel covers ``1 / (W H |det J|)`` of that plane.
    """
    h = homogeneous(tex, p)
    st = h[:, :2] / h[:, 3:]
    jac = (tex[None, :2, :3] - st[:, :, None] * tex[None, 3:, :3]) / h[:, 3:, None]
    d = sun / np.linalg.norm(sun)
    e1 = np.cross(d, [0.3, 0.5, 0.7])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(d, e1)
    j2 = jac @ np.stack([e1, e2], axis=1)
    return np.asarray(np.sqrt(1.0 / (SIZE * SIZE * np.abs(np.linalg.det(j2)))))


def axis_point(view: np.ndarray, depth: float) -> np.ndarray:
    """The point on the camera's axis at a view depth."""
    inv = np.linalg.inv(view)
    return inv[:3, 3] - depth * inv[:3, 2]


def leaves(c: sm.Cascades) -> list[np.ndarray]:
    """Every array of a fit, the frustum's fields included, as NumPy."""
    out = []
    for v in c:
        fields = v[:8] if isinstance(v, sm.OrthographicBox) else (v,)
        fields = tuple(v) if isinstance(v, sm.CascadeState) else fields
        out += [np.asarray(f) for f in fields]
    return out


def warped(c: sm.Cascades) -> np.ndarray:
    """Which cascades are warped: their clip ``w`` row is not ``(0, 0, 0, 1)``."""
    return np.asarray(np.any(np.abs(np.asarray(c.world_to_clip)[..., 3, :3]) > 0, axis=-1))


# --- containment ----------------------------------------------------------------------------


def check_contains(c: sm.Cascades, sun: Any, view: Any, proj: Any, box: Any, i: int) -> None:
    """Body vertices, random points of the body and their casters land in the map."""
    mx, my = c.frustum.margin_x[i], c.frustum.margin_y[i]
    v = body(view, proj, box, c.splits[i], c.band_end[i])
    rng = np.random.default_rng(i)
    weights = rng.dirichlet(np.full(len(v), 0.3), size=200)
    pts = np.r_[v, weights @ v]
    h = homogeneous(np.asarray(c.world_to_clip[i]), pts)
    assert np.all(h[:, 3] > 0)
    p = h[:, :3] / h[:, 3:]
    tol = 1e-9
    assert np.all(np.abs(p[:, 0]) <= mx * (1 + tol)) and np.all(np.abs(p[:, 1]) <= my * (1 + tol))
    assert np.all((p[:, 2] > -1) & (p[:, 2] < 1))
    # The fit is tight: vertices touch all four margins.
    q = p[: len(v)]
    np.testing.assert_allclose([q[:, 0].max(), -q[:, 0].min()], [mx, mx], rtol=1e-8)
    np.testing.assert_allclose([q[:, 1].max(), -q[:, 1].min()], [my, my], rtol=1e-8)
    # Casters: toward the sun from each vertex, up to the box's face; same texel, nearer.
    d = sun / np.linalg.norm(sun)
    with np.errstate(divide="ignore"):
        exits = np.where(d > 0, (box[1] - v) / d, np.where(d < 0, (box[0] - v) / d, np.inf))
    top = v + np.min(exits, axis=1, keepdims=True) * d
    for k in (0.5, 1.0):
        hc = homogeneous(np.asarray(c.world_to_clip[i]), v + k * (top - v))
        pc = hc[:, :3] / hc[:, 3:]
        np.testing.assert_allclose(pc[:, :2], q[:, :2], atol=1e-9)
        assert np.all((pc[:, 2] > -1) & (pc[:, 2] <= q[:, 2] + 1e-12))


@pytest.mark.parametrize("seed", range(8))
def test_every_point_of_each_slice_lands_inside_the_map(seed: int) -> None:
    sun, view, proj, box = scene(seed)
    c = sm.fit_cascades(sun, view, proj, box, SIZE, pcf_radius=2, warp="lispsm")
    for i in np.flatnonzero(warped(c)):  # the others are the orthographic cascade's
        check_contains(c, sun, view, proj, box, i)


def test_the_containment_scenes_are_warped() -> None:
    """The warp's cap leaves enough of the cascades above warped to test them."""
    count = 0
    for seed in range(8):
        sun, view, proj, box = scene(seed)
        c = sm.fit_cascades(sun, view, proj, box, SIZE, pcf_radius=2, warp="lispsm")
        count += int(warped(c).sum())
    assert count >= 12


def test_the_warped_horizon_scene_lands_inside_the_map() -> None:
    sun, view, proj, box = horizon()
    c = sm.fit_cascades(sun, view, proj, box, SIZE, warp="lispsm")
    for i in np.flatnonzero(warped(c)):
        check_contains(c, sun, view, proj, box, i)


# --- resolution -----------------------------------------------------------------------------


# tests/test_lispsm_fade.py: the warp's strength and its resolution.


# --- fallback -------------------------------------------------------------------------------


def test_view_parallel_to_the_light_falls_back_to_the_orthographic_cascade() -> None:
    view = look_at([0.0, 9.0, 0.0], [0.0, 0.0, 0.0], up=(0.0, 0.0, -1.0))  # looking down
    proj = perspective(1.0, 1.5, 0.5, 9.5)  # every slice inside the box
    box = np.array([[-50.0, -1.0, -50.0], [50.0, 10.0, 50.0]])
    for sun in ([0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [0.6 * WARP_MIN_SIN, 1.0, 0.0]):
        flat = sm.fit_cascades(np.array(sun), view, proj, box, SIZE)
        warp = sm.fit_cascades(np.array(sun), view, proj, box, SIZE, warp="lispsm")
        assert not warped(warp).any()
        for a, b in zip(leaves(flat), leaves(warp), strict=True):
            np.testing.assert_allclose(b, a, rtol=1e-12, atol=1e-12)


def test_an_orthographic_camera_is_not_warped() -> None:
    sun, _, _, box = scene(1)
    view = look_at([0, 30, 0.1], [0, 0, 0])
    proj = np.diag([1 / 20, 1 / 15, -2 / 29, 1.0])
    proj[2, 3] = -31 / 29
    c = sm.fit_cascades(sun, view, proj, box, 256, count=3, warp="lispsm")
    np.testing.assert_allclose(
        c.world_to_clip, sm.fit_cascades(sun, view, proj, box, 256, count=3).world_to_clip,
        rtol=1e-12, atol=1e-12,
    )  # fmt: skip


def test_a_batch_mixing_warped_and_fallback_cameras_equals_one_by_one() -> None:
    sun, view, proj, box = scene(1)
    down = look_at([0.0, 30.0, 0.0], [0.0, 0.0, 0.0], up=(0.0, 0.0, -1.0))
    views = np.stack([view, down])
    light = np.stack([sun, [0.0, 1.0, 0.0]])
    c = sm.fit_cascades(light, views, proj, box, SIZE, warp="lispsm")
    assert warped(c)[0].all() and not warped(c)[1].any()
    for k in range(2):
        one = sm.fit_cascades(light[k], views[k], proj, box, SIZE, warp="lispsm")
        for a, b in zip(leaves(one), leaves(c), strict=True):
            np.testing.assert_allclose(b if b.shape == a.shape else b[k], a, rtol=1e-12)


# --- options and conventions ----------------------------------------------------------------


def test_stable_mode_refuses_the_warp() -> None:
    sun, view, proj, box = scene(0)
    with pytest.raises(ValueError, match="warp: 'lispsm' cannot be combined with stable=True"):
        sm.fit_cascades(sun, view, proj, box, SIZE, stable=True, warp="lispsm")
    spec = sm.ShadowMapSpec(SIZE, stable=True)
    with pytest.raises(ValueError, match="warp:"):
        sm.fit_cascades(sun, view, proj, box, spec, warp="lispsm")
    with pytest.raises(ValueError, match="warp: expected None or 'lispsm'"):
        sm.fit_cascades(sun, view, proj, box, SIZE, warp="tsm")  # type: ignore[arg-type]


@pytest.mark.parametrize("reversed_z", [False, True])
@pytest.mark.parametrize("api", APIS)
def test_each_api_is_opengl_times_its_conventions(api: Any, reversed_z: bool) -> None:
    sun, view, proj, box = scene(2)
    gl = sm.fit_cascades(sun, view, proj, box, SIZE, warp="lispsm")
    c = sm.fit_cascades(
        sun, view, proj, box, SIZE, api=api, reversed_z=reversed_z, camera_api="opengl",
        warp="lispsm",
    )  # fmt: skip
    conv = sm.api_convention(api=api, reversed_z=reversed_z)
    C, T = conv.gl_clip_to_clip, conv.clip_to_texture
    np.testing.assert_allclose(c.world_to_clip, C @ gl.world_to_clip, rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(c.world_to_texture, T @ C @ gl.world_to_clip, rtol=1e-13, atol=1e-15)
    # Every vertex of every slice samples inside its map, at depth in [0, 1].
    for i in range(4):
        h = homogeneous(np.asarray(c.world_to_texture[i]), body(view, proj, box, c.splits[i],
                                                                c.band_end[i]))  # fmt: skip
        assert np.all(h[:, 3] > 0)
        st = h[:, :3] / h[:, 3:]
        assert np.all((st > 0) & (st < 1))


def test_atlas_tiles_hold_the_warped_cascades() -> None:
    sun, view, proj, box = scene(5)
    c = sm.fit_cascades(sun, view, proj, box, 256, layout="atlas", warp="lispsm")
    for i in range(4):
        h = homogeneous(np.asarray(c.world_to_texture[i]), body(view, proj, box, c.splits[i],
                                                                c.band_end[i]))  # fmt: skip
        st = h[:, :2] / h[:, 3:]
        x, y, w, hh = c.viewports[i]
        assert np.all((st[:, 0] * 512 > x) & (st[:, 0] * 512 < x + w))
        assert np.all((st[:, 1] * 512 > y) & (st[:, 1] * 512 < y + hh))


def test_float32_input_gives_the_float64_values() -> None:
    sun, view, proj, box = scene(3)
    s32, v32, p32, b32 = (np.asarray(v, np.float32) for v in (sun, view, proj, box))
    c = sm.fit_cascades(s32, v32, p32, b32, SIZE, warp="lispsm")
    s64, v64, p64, b64 = (np.float64(a) for a in (s32, v32, p32, b32))
    c64 = sm.fit_cascades(s64, v64, p64, b64, SIZE, warp="lispsm")
    np.testing.assert_allclose(c.world_to_texture, c64.world_to_texture, rtol=2e-3, atol=2e-4)


# --- JAX ------------------------------------------------------------------------------------


def test_jax_gives_numpy_values_under_jit() -> None:
    sun, view, proj, box = scene(6)
    ref = sm.fit_cascades(sun, view, proj, box, SIZE, warp="lispsm")

    @jax.jit
    def run(light: Any) -> Any:
        return sm.fit_cascades(light, view, proj, box, SIZE, warp="lispsm")

    for c in (sm.fit_cascades(jnp.asarray(sun), view, proj, box, SIZE, warp="lispsm"),
              run(jnp.asarray(sun))):  # fmt: skip
        assert isinstance(c.world_to_clip, jax.Array)
        for a, b in zip(leaves(ref), leaves(c), strict=True):
            np.testing.assert_allclose(b, a, rtol=1e-11, atol=1e-13)


def test_jax_traces_the_newton_steps_once(monkeypatch: pytest.MonkeyPatch) -> None:
    """Under JAX the warp cap's Newton steps are one loop: the traced program does not grow
    with their number (traced as copies, they were a quarter of the gradient's program and
    doubled its compile time)."""
    sun, view, proj, box = scene(6)
    # The warp's module, beside the module that defines fit_cascades.
    lispsm = importlib.import_module(sm.fit_cascades.__module__.rpartition(".")[0] + "._lispsm")

    def equations(steps: int) -> int:
        monkeypatch.setattr(lispsm, "NEWTON_STEPS", steps)
        program = jax.make_jaxpr(
            lambda light: sm.fit_cascades(light, view, proj, box, SIZE, warp="lispsm")
        )
        return len(program(jnp.asarray(sun)).jaxpr.eqns)

    assert equations(2) == equations(8)


def test_jax_gradient_wrt_the_light_matches_central_differences() -> None:
    sun, view, proj, box = scene(7)
    weights = np.random.default_rng(0).normal(size=(4, 4, 4))

    def loss(light: Any) -> Any:
        c = sm.fit_cascades(light, view, proj, box, SIZE, warp="lispsm")
        return jnp.sum(c.world_to_texture * weights) + jnp.sum(c.texel_size)

    grad = np.asarray(jax.grad(loss)(jnp.asarray(sun)))
    assert np.all(np.isfinite(grad))
    h = 1e-6
    fd = [
        (float(loss(jnp.asarray(sun + h * e))) - float(loss(jnp.asarray(sun - h * e)))) / (2 * h)
        for e in np.eye(3)
    ]
    np.testing.assert_allclose(grad, fd, rtol=1e-5, atol=1e-6 * np.abs(fd).max())


def test_quantile_loop_form_equals_the_array_form() -> None:
    """The compiled loop's weighted quantile (buckets, the crossing one sorted) is the
    array form's (every sample sorted) on samples with ties, values at 0, 1 and the
    buckets' edges, and zero weights."""
    from shadowmath._fits.cascades._lispsm import _quantile
    from shadowmath._math._specialize import scalar_formulas

    loop = scalar_formulas()._quantile_loop
    rng = np.random.default_rng(1)
    for trial in range(600):
        k = int(rng.integers(1, 60))
        a = rng.uniform(-0.3, 1.3, k).clip(0, 1)
        if trial % 3 == 0:
            a = np.round(a * 8) / 8  # ties, on the buckets' edges
        w = rng.uniform(0, 2, k) * (rng.uniform(size=k) < 0.8)
        share = float(rng.choice([0.01, 0.5, 0.9, 0.95, 1.0]))
        expected = float(_quantile(np, a[None], w[None], share)[0])
        got = loop(([*a.tolist(), 0.0], [*w.tolist(), 0.0]), k, share)
        assert got == pytest.approx(expected, rel=0, abs=1e-12)
