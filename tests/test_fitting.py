"""Off-centre and smooth frusta, the rolled frame, coverage measures and the fitter.

Every property is checked against geometry computed here from the light frame's
axes (ratios ``x / z`` of the blocker's vertices), not against the code's own numbers.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import shadowmath as sm

from .conftest import rtol_for

MAP = 128


def _blocker(seed: int, n: int = 20) -> tuple[np.ndarray, np.ndarray]:
    """A light and a random elongated blocker several units in front of it, off the axis."""
    rng = np.random.default_rng(seed)
    light = rng.uniform(-2, 2, 3)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    shape = rng.normal(size=(n, 3)) * np.array([2.0, 0.6, 0.3])
    centre = light + rng.normal(size=3) * 1.5 + np.array([0.0, 0.0, 8.0])
    return light, shape @ q.T + centre


def _ratios(frame: sm.LightFrame, verts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The vertices' projection ratios, computed directly from the frame's axes."""
    o = np.asarray(verts, float) - np.asarray(frame.origin, float)[..., None, :]
    x, y, z = (np.sum(o * np.asarray(ax, float)[..., None, :], -1) for ax in frame[1:])
    assert np.all(z > 0)
    return x / z, y / z


def _ndc(P: Any, W: Any, verts: np.ndarray) -> np.ndarray:
    hom = np.c_[verts, np.ones(len(verts))] @ (np.asarray(P, float) @ np.asarray(W, float)).T
    return hom[:, :3] / hom[:, 3:]


# --- the off-centre frustum ---------------------------------------------------------------


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_offcenter_projection_touches_all_four_margins(to: Any, dtype: Any, seed: int) -> None:
    light, verts = _blocker(seed)
    frame = sm.light_frame(to(light), to(verts))
    fr = sm.offcenter_frustum(frame, to(verts), (MAP, MAP // 2))
    mx, my = sm.border_margin((MAP, MAP // 2))
    ndc = _ndc(sm.blocker_projection(fr), sm.world_to_light(frame), verts)
    tol = 20 * rtol_for(dtype)
    # Inside the margins, and on them on all four sides.
    assert np.all(np.abs(ndc[:, 0]) <= mx + tol)
    assert np.all(np.abs(ndc[:, 1]) <= my + tol)
    assert np.isclose(ndc[:, 0].min(), -mx, atol=tol) and np.isclose(ndc[:, 0].max(), mx, atol=tol)
    assert np.isclose(ndc[:, 1].min(), -my, atol=tol) and np.isclose(ndc[:, 1].max(), my, atol=tol)
    assert np.all(ndc[:, 2] > -1) and np.all(ndc[:, 2] < 1)
    # x_ndc is the affine map of the ratio x / z taking [min, max] onto [-m, m].
    rx, ry = _ratios(frame, verts)
    lo, hi = rx.min(), rx.max()
    assert np.allclose(ndc[:, 0], -mx + 2 * mx * (rx - lo) / (hi - lo), atol=tol)
    # The receiver's texture coordinates are the same picture scaled into [0, 1].
    stq = (
        np.c_[verts, np.ones(len(verts))]
        @ np.asarray(sm.receiver_projection(fr) @ sm.world_to_light(frame), float).T
    )
    assert np.allclose(stq[:, :2] / stq[:, 3:], 0.5 + 0.5 * ndc[:, :2], atol=tol)
    z = (verts - np.asarray(frame.origin, float)) @ np.asarray(frame.z_axis, float)
    assert np.allclose(stq[:, 3], z, rtol=tol)  # q = z_light
    # Its usable cross-section is the ratios' bounding box, never larger than the article's.
    assert np.isclose(float(sm.cross_section_area(fr)), (hi - lo) * (ry.max() - ry.min()), rtol=tol)
    sym = sm.adaptive_frustum(frame, to(verts), (MAP, MAP // 2))
    assert float(sm.cross_section_area(fr)) <= float(sm.cross_section_area(sym)) * (1 + tol)


def test_symmetric_frusta_keep_their_matrices() -> None:
    """A six-field frustum (the core's original form) and zero offsets give the same matrices."""
    six = (0.5, 0.25, 1.0, 3.0, 0.98, 0.98)
    for fn in (sm.blocker_projection, sm.receiver_projection):
        assert np.array_equal(fn(six), fn(sm.Frustum(*six)))
        assert np.array_equal(fn(six), fn(sm.Frustum(*six, x_offset=0.0, y_offset=0.0)))
    f32 = sm.Frustum(*(np.float32(v) for v in six))
    assert sm.blocker_projection(f32).dtype == np.float32
    with pytest.raises(ValueError, match="frustum"):
        sm.blocker_projection((0.5, 0.25, 1.0, 3.0, 0.98))


def test_offsets_shift_the_map_centre() -> None:
    """The point at ratio (c_x, c_y) lands at the map's centre; ratios c +- R on the margins."""
    fr = sm.Frustum(0.2, 0.1, 1.0, 10.0, 0.9, 0.8, x_offset=0.3, y_offset=-0.4)
    z = 4.0
    pts = np.array(
        [[0.3 * z, -0.4 * z, z, 1], [(0.3 + 0.2) * z, -0.4 * z, z, 1], [0.3 * z, -0.5 * z, z, 1]]
    )
    clip = pts @ np.asarray(sm.blocker_projection(fr)).T
    ndc = clip[:, :2] / clip[:, 3:]
    assert np.allclose(ndc, [[0, 0], [0.9, 0], [0, -0.8]])


# --- smooth variants -----------------------------------------------------------------------


def test_smooth_max_bounds_the_maximum() -> None:
    rng = np.random.default_rng(5)
    x = rng.normal(size=(4, 30))
    for T in (1.0, 0.1, 1e-3):
        s = sm.smooth_max(x, T)
        assert np.all(s >= x.max(-1)) and np.all(s <= x.max(-1) + T * np.log(30) + 1e-12)
    assert np.allclose(sm.smooth_max(x, 1e-9), x.max(-1), atol=1e-8)
    with pytest.raises(ValueError, match="temperature"):
        sm.smooth_max(x, 0.0)
    assert np.isnan(jax.jit(sm.smooth_max)(jnp.asarray(x), -1.0)).all()


@pytest.mark.parametrize("symmetric", [True, False])
def test_smooth_frustum_is_conservative_and_converges(symmetric: bool) -> None:
    light, verts = _blocker(3)
    frame = sm.light_frame(light, verts)
    exact = (sm.adaptive_frustum if symmetric else sm.offcenter_frustum)(frame, verts, MAP)
    rx, ry = _ratios(frame, verts)
    n_terms = 2 * len(verts) if symmetric else len(verts)
    m = sm.border_margin(MAP)[0]
    for T in (0.05, 0.005, 1e-4):
        soft = sm.smooth_frustum(frame, verts, MAP, temperature=T, symmetric=symmetric)
        lo = np.asarray(soft.x_offset - soft.rx_max)
        hi = np.asarray(soft.x_offset + soft.rx_max)
        # The soft interval contains every ratio, and exceeds the hard one by <= T log n.
        assert lo <= rx.min() and hi >= rx.max()
        slack = T * np.log(n_terms) + 1e-12
        if symmetric:
            assert soft.x_offset == 0 and soft.rx_max <= np.abs(rx).max() + slack
        else:
            assert rx.min() - lo <= slack and hi - rx.max() <= slack
        ndc = _ndc(sm.blocker_projection(soft), sm.world_to_light(frame), verts)
        assert np.all(np.abs(ndc[:, :2]) <= m + 1e-12)  # never clips
    assert np.allclose(soft.rx_max, exact.rx_max, atol=1e-3) and np.allclose(
        soft.ry_max, exact.ry_max, atol=1e-3
    )
    assert np.all(np.abs(ry) <= np.asarray(exact.ry_max + np.abs(exact.y_offset)) + 1e-12)


# --- the rolled frame ----------------------------------------------------------------------


def test_rolled_frame_is_the_article_frame_turned() -> None:
    rng = np.random.default_rng(6)
    for _ in range(5):
        p, d, theta = rng.normal(size=3), rng.normal(size=3), rng.uniform(-3, 3)
        base = sm.light_frame_from_direction(p, d)
        same = sm.rolled_light_frame(p, d, 0.0, up=sm.helper_axis(d))
        for a, b in zip(base, same, strict=True):
            assert np.allclose(a, b, atol=1e-14)
        f = sm.rolled_light_frame(p, d, theta, up=sm.helper_axis(d))
        R = np.stack([f.x_axis, f.y_axis, f.z_axis])
        assert np.allclose(R @ R.T, np.eye(3), atol=1e-14)
        assert np.allclose(np.cross(f.x_axis, f.y_axis), -f.z_axis, atol=1e-14)  # left-handed
        assert np.isclose(f.x_axis @ base.x_axis, np.cos(theta))
        assert np.isclose(f.x_axis @ base.y_axis, np.sin(theta))


def test_rolled_frame_is_continuous_where_the_helper_axis_jumps() -> None:
    # |z_x| = |z_y| at d = (1, 1, 2): the article's helper axis switches from X to Y.
    delta = 1e-7
    d_a, d_b = np.array([1.0, 1 + delta, 2.0]), np.array([1.0, 1 - delta, 2.0])
    jump = sm.light_frame_from_direction(np.zeros(3), d_a).x_axis
    jump = jump - sm.light_frame_from_direction(np.zeros(3), d_b).x_axis
    assert np.linalg.norm(jump) > 0.5
    smooth = sm.rolled_light_frame(np.zeros(3), d_a, 0.2).x_axis
    smooth = smooth - sm.rolled_light_frame(np.zeros(3), d_b, 0.2).x_axis
    assert np.linalg.norm(smooth) < 10 * delta


def test_rolled_frame_rejects_up_along_the_direction() -> None:
    with pytest.raises(ValueError, match="up"):
        sm.rolled_light_frame([0, 0, 0], [0, 2, 0], 0.1)  # default up is +Y
    f = jax.jit(sm.rolled_light_frame)(jnp.zeros(3), jnp.array([0.0, -1, 0]), 0.1)
    assert all(np.isnan(v).all() for v in f)


# --- measures ------------------------------------------------------------------------------


def test_silhouette_coverage_counts_the_interior() -> None:
    mask = np.zeros((2, 10, 12))
    mask[0, 2:6, 2:10] = 1  # 32 of the 8 x 10 interior
    assert np.allclose(sm.silhouette_coverage(mask), [32 / 80, 0])
    assert np.isclose(sm.silhouette_coverage(np.ones((10, 12)), border_texels=2), 1.0)
    with pytest.raises(ValueError, match="border_texels"):
        sm.silhouette_coverage(np.ones((4, 4)), border_texels=2)


def test_receiver_texel_size_matches_a_mapped_square() -> None:
    light, verts = _blocker(7)
    setup = sm.fit_shadow(light, verts, (256, 128))
    M = np.asarray(setup.world_to_texture)
    rng = np.random.default_rng(8)
    for _ in range(4):
        # A receiver point beyond the blocker, with a random tilt toward the light.
        point = light + setup.frame.z_axis * 14 + rng.normal(size=3)
        normal = -setup.frame.z_axis + 0.6 * rng.normal(size=3)
        u = np.cross(normal, rng.normal(size=3))
        u /= np.linalg.norm(u)
        v = np.cross(normal / np.linalg.norm(normal), u)
        h = 1e-4  # a tiny square in the surface, mapped to (s, t) and measured there
        corners = point + h * np.array([[0, 0], [1, 0], [1, 1], [0, 1]]) @ np.stack([u, v])
        stq = np.c_[corners, np.ones(4)] @ M.T
        st = stq[:, :2] / stq[:, 3:] * np.array([256, 128])  # in texels
        x, y = st[:, 0], st[:, 1]
        texels = 0.5 * abs(x @ np.roll(y, -1) - y @ np.roll(x, -1))
        expected = h / np.sqrt(texels)  # side of the square of one texel's area
        got = sm.receiver_texel_size(M, point, normal, (256, 128))
        assert np.isclose(got, expected, rtol=1e-3)


def test_receiver_texel_size_on_a_facing_wall() -> None:
    # A symmetric frustum R = 0.25: at distance D a texel is 2 R D / (m W) wide.
    quad = [[-1, -1, 4], [1, 1, 4], [1, -1, 4], [-1, 1, 4]]
    s = sm.fit_shadow([0, 0, 0], quad, 64)
    m = sm.border_margin(64)[0]
    for D in (5.0, 20.0):
        size = sm.receiver_texel_size(s.world_to_texture, [0, 0, D], [0, 0, -3], 64)
        assert np.isclose(size, 2 * 0.25 * D / (m * 64))
    with pytest.raises(ValueError, match="behind the light"):
        sm.receiver_texel_size(s.world_to_texture, [0, 0, -5], [0, 0, 1], 64)


# --- the fitter ----------------------------------------------------------------------------


def _bar(angle: float, distance: float = 10.0) -> np.ndarray:
    """A thin bar at ``distance`` on the z axis, turned by ``angle`` in the xy plane."""
    bar = np.array([[x, y, z] for x in (-3, 3) for y in (-0.1, 0.1) for z in (-0.1, 0.1)])
    c, s = np.cos(angle), np.sin(angle)
    return bar @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]).T + [0, 0, distance]


def test_fit_aligns_the_frame_with_a_bar() -> None:
    verts = _bar(0.6)
    fit = sm.optimize_frustum([0, 0, 0], verts, MAP)
    axis = np.array([np.cos(0.6), np.sin(0.6), 0])
    along = max(abs(fit.frame.x_axis @ axis), abs(fit.frame.y_axis @ axis))
    assert along > np.cos(np.radians(1.0))
    # The cross-section shrinks to near the bar's own (bounding) rectangle.
    ideal = (6.0 / 9.9) * (0.2 / 9.9)
    assert float(sm.cross_section_area(fit.frustum)) < 1.2 * ideal


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_fit_never_clips_and_never_loses_to_the_article(seed: int) -> None:
    light, verts = _blocker(seed)
    fit = sm.optimize_frustum(light, verts, MAP)
    m = sm.border_margin(MAP)[0]
    ndc = _ndc(sm.blocker_projection(fit.frustum), sm.world_to_light(fit.frame), verts)
    assert np.all(np.abs(ndc[:, :2]) <= m + 1e-12)
    for k in (0, 1):
        assert np.isclose(ndc[:, k].min(), -m) and np.isclose(ndc[:, k].max(), m)
    # The proxy never gets worse than the article's frame with either frustum.
    mdv = sm.light_frame(light, verts)
    area = float(sm.cross_section_area(fit.frustum))
    assert area <= float(sm.cross_section_area(sm.offcenter_frustum(mdv, verts, MAP))) + 1e-12
    ref = float(sm.cross_section_area(sm.adaptive_frustum(mdv, verts, MAP)))
    # The reported losses are the log of that ratio, the best of them is the result.
    assert fit.losses.shape == (80,)
    assert np.log(area / ref) <= fit.losses.min() + 1e-9
    # The frame is the rolled frame of the returned direction.
    R = np.stack(fit.frame[1:])
    assert np.allclose(R @ R.T, np.eye(3), atol=1e-12)
    assert np.allclose(fit.frame.z_axis, fit.direction / np.linalg.norm(fit.direction))


def test_fit_batches_and_backends() -> None:
    (l0, v0), (l1, v1) = _blocker(4), _blocker(5)
    lights, verts = np.stack([l0, l1]), np.stack([v0, v1])
    fit = sm.optimize_frustum(lights, verts, MAP)
    assert isinstance(fit.frame.x_axis, np.ndarray) and fit.frame.x_axis.shape == (2, 3)
    assert fit.frustum.rx_max.shape == (2,) and fit.losses.shape == (2, 80)
    one = sm.optimize_frustum(l1, v1, MAP)
    assert np.allclose(fit.frame.x_axis[1], one.frame.x_axis, atol=1e-9)
    jfit = sm.optimize_frustum(jnp.asarray(l1), jnp.asarray(v1), MAP)
    assert isinstance(jfit.frustum.rx_max, jax.Array)
    assert np.allclose(jfit.frustum.rx_max, one.frustum.rx_max, rtol=1e-9)


def test_fit_symmetric_keeps_the_frustum_centred() -> None:
    light, verts = _blocker(1)
    fit = sm.optimize_frustum(light, verts, MAP, symmetric=True, steps=30, starts=2)
    assert fit.frustum.x_offset == 0 and fit.frustum.y_offset == 0
    mdv = sm.adaptive_frustum(sm.light_frame(light, verts), verts, MAP)
    assert sm.cross_section_area(fit.frustum) <= sm.cross_section_area(mdv) * (1 + 1e-12)
    with pytest.raises(ValueError, match="steps"):
        sm.optimize_frustum(light, verts, MAP, steps=0)


def test_fit_shadow_optimized_is_a_drop_in_setup() -> None:
    light, verts = _blocker(2)
    B = np.eye(4)
    B[:3, 3] = [0.5, -1.0, 2.0]
    s = sm.fit_shadow(light, verts, MAP, blocker_to_world=B, method="optimized")
    fit = sm.optimize_frustum(light, verts + B[:3, 3], MAP)
    P, W = sm.blocker_projection(fit.frustum), sm.world_to_light(fit.frame)
    assert np.allclose(s.blocker_to_clip, P @ W @ B, atol=1e-12)
    assert np.allclose(s.world_to_texture, sm.receiver_projection(fit.frustum) @ W, atol=1e-12)
    with pytest.raises(ValueError, match="method"):
        sm.fit_shadow(light, verts, MAP, method="best")  # type: ignore[arg-type]


def test_new_functions_under_jit_and_vmap_match_numpy() -> None:
    pairs = [_blocker(s) for s in (10, 11, 12)]
    lights = np.stack([p[0] for p in pairs])
    verts = np.stack([p[1] for p in pairs])
    rolls = np.array([0.1, -0.7, 2.0])

    def pipeline(light: Any, v: Any, roll: Any) -> tuple[Any, ...]:
        frame = sm.rolled_light_frame(light, v.mean(-2) - light, roll)
        soft = sm.smooth_frustum(frame, v, MAP, temperature=0.01, symmetric=False)
        hard = sm.offcenter_frustum(frame, v, MAP)
        M = sm.receiver_projection(hard) @ sm.world_to_light(frame)
        size = sm.receiver_texel_size(M, v[..., 0, :] * 2 - light, frame.z_axis, MAP)
        return (
            *frame,
            *soft,
            sm.cross_section_area(hard),
            sm.smooth_max(v[..., 2], 0.1),
            size,
        )

    expected = pipeline(lights, verts, rolls)  # NumPy, batched by broadcasting
    got = jax.jit(jax.vmap(pipeline))(jnp.asarray(lights), jnp.asarray(verts), jnp.asarray(rolls))
    for e, g in zip(expected, got, strict=True):
        assert isinstance(g, jax.Array)
        assert np.allclose(g, e, rtol=1e-10, atol=1e-12)
