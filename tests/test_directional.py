"""Homogeneous and directional lights in ``fit_shadow``, and the :class:`OrthographicBox`."""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import shadowmath as sm
from shadowmath import meshes

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
    assert isinstance(s.frustum, sm.OrthographicBox)
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
    assert type(b.frustum) is sm.Frustum


def test_mixed_batch_is_refused_and_typed_lights_fit_each_kind() -> None:
    lights = np.array([[0.0, 0.0, 0.0, 1.0], [0.2, 0.3, -1.0, 0.0]])
    with pytest.raises(ValueError, match="light: a batch mixes point lights"):
        sm.fit_shadow(lights, BOX, 64)
    point = sm.fit_shadow(sm.PointLight(lights[0, :3]), BOX, 64)
    sun = sm.fit_shadow(sm.DirectionalLight(lights[1, :3]), BOX, 64)
    for typed, light in ((point, lights[0]), (sun, lights[1])):
        one = sm.fit_shadow(light, BOX, 64)
        np.testing.assert_array_equal(typed.blocker_to_clip, one.blocker_to_clip)
    assert type(point.frustum) is sm.Frustum and type(sun.frustum) is sm.OrthographicBox
    np.testing.assert_array_equal(point.blocker_to_clip[3, :3], point.frame.z_axis)
    np.testing.assert_array_equal(sun.blocker_to_clip[3], [0, 0, 0, 1])


def test_orthographic_frustum_projection() -> None:
    fr = sm.OrthographicBox(2.0, 1.0, 1.0, 5.0, 0.98, 0.96, 0.5, -0.25)
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
    # The same numbers as a perspective Frustum give the perspective matrix (by type).
    persp = sm.Frustum(*fr)
    np.testing.assert_array_equal(sm.blocker_projection(persp)[3], [0, 0, 1, 0])
    # A batch of boxes, centred by default: each entry's own matrix.
    boxes = sm.OrthographicBox(np.array([2.0, 3.0]), 1.0, 1.0, 5.0, 0.98, 0.96)
    for i, half in enumerate((2.0, 3.0)):
        one = sm.OrthographicBox(half, 1.0, 1.0, 5.0, 0.98, 0.96, 0.0, 0.0)
        np.testing.assert_allclose(
            sm.blocker_projection(boxes)[i], sm.blocker_projection(one), rtol=1e-15
        )
    # A box's near plane may lie behind its origin (it has no eye).
    behind = sm.blocker_projection(fr._replace(near=-3.0)) @ np.array([0.0, 0.0, -3.0, 1.0])
    np.testing.assert_allclose(behind[2] / behind[3], -1.0, rtol=1e-15)


def test_zero_directional_light_raises_and_poisons() -> None:
    with pytest.raises(ValueError, match="light: zero directional light"):
        sm.fit_shadow(np.zeros(4), BOX, 64)
    lights = jnp.asarray([[0.2, 0.3, -1.0], [0.0, 0.0, 0.0]])
    fit = jax.jit(lambda L: sm.fit_shadow(sm.DirectionalLight(L), jnp.asarray(BOX), 64))
    out = fit(lights)
    assert bool(jnp.all(jnp.isfinite(out.blocker_to_clip[0])))
    assert bool(jnp.all(jnp.isnan(out.blocker_to_clip[1])))


def test_homogeneous_light_under_jit_asks_for_a_typed_light() -> None:
    # Its kind would depend on the traced values of w: refused, never both fits.
    with pytest.raises(ValueError, match=r"pass sm.PointLight\(position\) or"):
        jax.jit(lambda L: sm.fit_shadow(L, jnp.asarray(BOX), 64))(jnp.ones(4))


@pytest.mark.parametrize(
    ("light", "typed"),
    [([0.2, 0.3, -1.0, 0.0], sm.DirectionalLight), ([0.0, 0.0, 0.0, 1.0], sm.PointLight)],
)
def test_jax_matches_numpy_and_gradients_are_finite(light: Any, typed: Any) -> None:
    ref = sm.fit_shadow(np.array(light), BOX, 64)
    got = sm.fit_shadow(jnp.asarray(light), jnp.asarray(BOX), 64)
    np.testing.assert_allclose(np.asarray(got.blocker_to_clip), ref.blocker_to_clip, atol=1e-12)

    def loss(L: Any, V: Any) -> Any:
        return jnp.sum(sm.fit_shadow(typed(L), V, 64).world_to_texture)

    grads = jax.grad(loss, argnums=(0, 1))(jnp.asarray(light[:3]), jnp.asarray(BOX))
    assert all(bool(jnp.all(jnp.isfinite(g))) for g in grads)


# ---- up: a frame that does not jump along a smooth light path --------------------------

TORUS = np.asarray(meshes.torus().vertices, dtype=float)
RADIUS, HEIGHT, STEP = float(np.hypot(2.2, 6.0)), 3.6, 2e-7  # the demo light's distance


def _circle(theta: Any) -> np.ndarray:
    theta = np.asarray(theta, dtype=float)
    return np.stack(
        [RADIUS * np.cos(theta), np.full_like(theta, HEIGHT), RADIUS * np.sin(theta)], -1
    )


def _largest_jump(**options: Any) -> float:
    """The largest change of blocker_to_clip over a STEP move along the circle."""
    theta = np.linspace(0, 2 * np.pi, 4001)
    z = sm.fit_shadow(_circle(theta), TORUS, 512, **options).frame.z_axis
    helper = np.asarray(sm.helper_axis(z))
    worst = 0.0
    for i in np.nonzero(np.any(helper[1:] != helper[:-1], axis=1))[0]:
        a, b = theta[i], theta[i + 1]
        for _ in range(60):  # bisect to the helper axis' switch
            c = 0.5 * (a + b)
            zc = sm.fit_shadow(_circle(c), TORUS, 512).frame.z_axis
            za = sm.fit_shadow(_circle(a), TORUS, 512).frame.z_axis
            same = np.array_equal(sm.helper_axis(za), sm.helper_axis(zc))
            a, b = (c, b) if same else (a, c)
        d = STEP / RADIUS
        m0 = sm.fit_shadow(_circle(a - d / 2), TORUS, 512, **options).blocker_to_clip
        m1 = sm.fit_shadow(_circle(a + d / 2), TORUS, 512, **options).blocker_to_clip
        worst = max(worst, float(np.abs(m1 - m0).max()))
    return worst


def test_up_hint_keeps_the_frame_from_jumping() -> None:
    # Baseline: without up the helper axis switches 8 times around the circle and a
    # 2e-7 move changes blocker_to_clip by 8.17 (the map's axes turn by 90 degrees).
    before = _largest_jump()
    assert before > 5
    # With up the same moves change it by at most a Lipschitz-like constant times the
    # step: the constant is the largest finite-difference slope along the whole path.
    after = _largest_jump(up=(0.0, 1.0, 0.0))
    theta = np.linspace(0, 2 * np.pi, 2001)
    M = sm.fit_shadow(_circle(theta), TORUS, 512, up=(0.0, 1.0, 0.0)).blocker_to_clip
    slope = np.abs(np.diff(M, axis=0)).max() / (RADIUS * (theta[1] - theta[0]))
    assert after <= 2 * slope * STEP
    assert after < 1e-5


def test_up_frame_is_the_look_at_frame() -> None:
    light, up = np.array([1.0, 2.0, -3.0]), np.array([0.1, 1.0, 0.2])
    s = sm.fit_shadow(light, BOX, 64, up=up)
    f = s.frame
    y = up - (up @ f.z_axis) * f.z_axis
    np.testing.assert_allclose(f.y_axis, y / np.linalg.norm(y), atol=1e-15)
    np.testing.assert_allclose(f.x_axis, np.cross(f.z_axis, f.y_axis), atol=1e-15)
    np.testing.assert_allclose(np.cross(f.x_axis, f.y_axis), -f.z_axis, atol=1e-15)
    with pytest.raises(ValueError, match=r"up: .*parallel"):
        sm.fit_shadow(light, BOX, 64, up=f.z_axis * 3)


# ---- every API: the receiver samples the texel the caster was drawn into ---------------


def _check_api_fit(api: str, reversed_z: bool, light: np.ndarray, seed: int) -> None:
    from .test_conventions import rasterize

    rng = np.random.default_rng(seed)
    verts = rng.normal(size=(30, 3)) + [0.0, 0.0, 6.0]
    W, H = 97, 64
    s = sm.fit_shadow(light, verts, (W, H), api=api, reversed_z=reversed_z)
    gl = sm.fit_shadow(light, verts, (W, H))
    conv = sm.api_convention(api=api, reversed_z=reversed_z)
    np.testing.assert_allclose(
        s.blocker_to_clip, conv.gl_clip_to_clip @ gl.blocker_to_clip, atol=1e-13
    )
    clip = np.c_[verts, np.ones(len(verts))] @ s.blocker_to_clip.T
    x_window, row, depth, inside = rasterize(api, clip, W, H)
    assert inside.all()
    tex = np.c_[verts, np.ones(len(verts))] @ s.world_to_texture.T
    st_ = tex[:, :3] / tex[:, 3:]
    np.testing.assert_allclose(st_[:, 0] * W, x_window, atol=1e-9)
    np.testing.assert_allclose(st_[:, 1] * H, row, atol=1e-9)
    np.testing.assert_allclose(st_[:, 2], depth, atol=1e-12)
    # The depth stored at the nearest vertex is nearer than the farthest's, in the API's order.
    z = (verts - s.frame.origin) @ s.frame.z_axis
    near_d, far_d = depth[np.argmin(z)], depth[np.argmax(z)]
    assert (near_d < far_d) == (conv.near_depth < conv.far_depth)


LIGHTS = [np.array([0.3, -0.2, 0.0]), np.array([0.3, -0.2, -1.0, 0.0])]


@pytest.mark.parametrize("reversed_z", [False, True])
@pytest.mark.parametrize("light", LIGHTS, ids=["point", "directional"])
@pytest.mark.parametrize("seed", [1, 2])
def test_opengl_fit_samples_the_texel_it_drew(reversed_z: bool, light: Any, seed: int) -> None:
    _check_api_fit("opengl", reversed_z, light, seed)


@pytest.mark.parametrize("reversed_z", [False, True])
@pytest.mark.parametrize("light", LIGHTS, ids=["point", "directional"])
@pytest.mark.parametrize("seed", [1, 2])
def test_vulkan_fit_samples_the_texel_it_drew(reversed_z: bool, light: Any, seed: int) -> None:
    _check_api_fit("vulkan", reversed_z, light, seed)


@pytest.mark.parametrize("reversed_z", [False, True])
@pytest.mark.parametrize("light", LIGHTS, ids=["point", "directional"])
@pytest.mark.parametrize("seed", [1, 2])
def test_direct3d_fit_samples_the_texel_it_drew(reversed_z: bool, light: Any, seed: int) -> None:
    _check_api_fit("direct3d", reversed_z, light, seed)


@pytest.mark.parametrize("reversed_z", [False, True])
@pytest.mark.parametrize("light", LIGHTS, ids=["point", "directional"])
@pytest.mark.parametrize("seed", [1, 2])
def test_metal_fit_samples_the_texel_it_drew(reversed_z: bool, light: Any, seed: int) -> None:
    _check_api_fit("metal", reversed_z, light, seed)


@pytest.mark.parametrize("reversed_z", [False, True])
@pytest.mark.parametrize("light", LIGHTS, ids=["point", "directional"])
@pytest.mark.parametrize("seed", [1, 2])
def test_webgpu_fit_samples_the_texel_it_drew(reversed_z: bool, light: Any, seed: int) -> None:
    _check_api_fit("webgpu", reversed_z, light, seed)


def test_unknown_api_lists_the_valid_ones() -> None:
    with pytest.raises(
        ValueError, match=r"api: .*'opengl', 'vulkan', 'direct3d', 'metal', 'webgpu'"
    ):
        sm.fit_shadow([0.0, 0.0, 0.0], BOX, 64, api="gles")  # type: ignore[arg-type]


# ---- receivers: the depth range encloses the receivers inside the frustum --------------


@pytest.mark.parametrize("light", LIGHTS, ids=["point", "directional"])
def test_receivers_inside_the_sides_fit_the_depth_range(light: Any) -> None:
    rng = np.random.default_rng(3)
    verts = rng.normal(size=(30, 3)) * 0.5 + [0.0, 0.0, 6.0]
    floor = np.stack(np.meshgrid(np.linspace(-8, 8, 41), np.linspace(-8, 8, 41)), -1).reshape(-1, 2)
    receivers = np.c_[floor, np.full(len(floor), 12.0)]  # a wall behind the blocker
    receivers = np.r_[receivers, [[0.0, 0.0, -5.0]]]  # behind the point light: ignored
    plain = sm.fit_shadow(light, verts, 64)
    s = sm.fit_shadow(light, verts, 64, receivers=receivers)
    np.testing.assert_allclose(
        s.blocker_to_clip[:2] @ [0, 0, 6, 1], plain.blocker_to_clip[:2] @ [0, 0, 6, 1], atol=1e-12
    )
    ndc = _ndc(s.blocker_to_clip, receivers)
    w = np.c_[receivers, np.ones(len(receivers))] @ s.blocker_to_clip[3]
    inside = (np.abs(ndc[:, 0]) <= 1) & (np.abs(ndc[:, 1]) <= 1) & (w > 0)
    assert inside.sum() > 10 and (~inside).sum() > 10
    assert np.all(np.abs(ndc[inside, 2]) < 1)  # inside the depth range
    assert np.all(np.abs(_ndc(s.blocker_to_clip, verts)[:, 2]) < 1)
    with pytest.raises(ValueError, match="receivers: expected shape"):
        sm.fit_shadow(light, verts, 64, receivers=receivers[:, :2])


# ---- stable directional maps ------------------------------------------------------------


def test_stable_map_keeps_its_scale_and_moves_by_whole_texels() -> None:
    W = 256
    light = np.array([0.3, 1.0, -0.4, 0.0])
    rng = np.random.default_rng(4)
    local = rng.normal(size=(40, 3)) * [1.0, 0.4, 0.7]
    probe = np.array([0.123, -0.456, 0.789, 1.0])  # a fixed world point
    scales, positions = [], []
    for k in range(60):  # a path of small steps: moving and turning
        a = 0.013 * k
        R = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
        verts = local @ R.T + [0.0037 * k, 0.0011 * k, -0.002 * k]
        s = sm.fit_shadow(light, verts, W, stable=True)
        scales.append(np.linalg.norm(s.blocker_to_clip[0, :3]))
        positions.append((s.world_to_texture @ probe)[:2] * W)
        ndc = _ndc(s.blocker_to_clip, verts)
        assert np.all(np.abs(ndc[:, :2]) <= sm.border_margin(W)[0] + 1e-12)
    np.testing.assert_allclose(scales, scales[0], rtol=1e-12)  # the scale stays fixed
    pos = np.array(positions)
    moves = np.diff(pos, axis=0)
    np.testing.assert_allclose(moves, np.round(moves), atol=1e-6)  # whole texels
    assert np.abs(moves).sum() > 0  # and the grid did move


def test_stable_point_light_needs_up() -> None:
    with pytest.raises(ValueError, match="up: stable=True"):
        sm.fit_shadow([0.0, 0.0, 0.0], BOX, 64, stable=True)
    a = sm.fit_shadow([0.0, 0.0, 0.0], BOX, 64, stable=True, up=(0, 1, 0))
    b = sm.fit_shadow([0.0, 0.0, 0.0], BOX, 64, up=(0, 1, 0))
    np.testing.assert_allclose(a.blocker_to_clip, b.blocker_to_clip)


def test_pcf_radius_sets_the_border() -> None:
    a = sm.fit_shadow([0.0, 0.0, 0.0], BOX, 64, pcf_radius=3)
    b = sm.fit_shadow([0.0, 0.0, 0.0], BOX, 64, border_texels=sm.pcf_border_texels(3))
    np.testing.assert_array_equal(a.blocker_to_clip, b.blocker_to_clip)
    c = sm.fit_shadow([0.0, 0.0, 0.0], BOX, 64, pcf_radius=3, pcf_filter="bilinear")
    assert float(c.frustum.margin_x) == (64 - 2 * 4) / 64
    with pytest.raises(ValueError, match="border_texels and pcf_radius: give one of"):
        sm.fit_shadow([0.0, 0.0, 0.0], BOX, 64, pcf_radius=3, border_texels=1)
