"""The adaptive frustum, its projections and fit_shadow, held to the article's geometry.

The first two tests are the ones a newcomer should read: with one fitted set-up,
every blocker vertex lands inside the margin, and some vertex touches it on each axis.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from shadowmath import (
    NEAR_FAR_SLACK,
    Frustum,
    adaptive_frustum,
    blocker_projection,
    border_margin,
    fit_shadow,
    light_frame,
    receiver_projection,
    receiver_texture_matrix,
    world_to_light,
)

from .conftest import rtol_for
from .test_frame import coords, directions

TETRAHEDRON = np.array([[1.0, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]]) / np.sqrt(3)


@st.composite
def light_and_blocker(draw: st.DrawFn) -> tuple[np.ndarray, np.ndarray]:
    """A solid blocker (a tetrahedron plus random points) in a ball of radius r, light beyond 3 r.

    A solid blocker's silhouette always has a width and a height, so a frustum exists.
    """
    centre = draw(arrays(np.float64, 3, elements=coords))
    r = draw(st.floats(0.1, 3))
    extra = draw(arrays(np.float64, (draw(st.integers(0, 8)), 3), elements=st.floats(-0.5, 0.5)))
    rotation, _ = np.linalg.qr(
        draw(arrays(np.float64, (3, 3), elements=st.floats(-1, 1))) + np.eye(3) * 3
    )
    offsets = np.concatenate([TETRAHEDRON, extra]) @ rotation.T
    direction = draw(directions)
    light = centre + direction / np.linalg.norm(direction) * r * draw(st.floats(3, 20))
    return light, centre + r * offsets


map_sizes = st.one_of(st.integers(3, 4096), st.tuples(st.integers(3, 4096), st.integers(3, 4096)))


def homog(p: np.ndarray) -> np.ndarray:
    return np.concatenate([p, np.ones((*p.shape[:-1], 1))], axis=-1)


def ndc(M: Any, points: np.ndarray) -> np.ndarray:
    clip = homog(points) @ np.asarray(M, np.float64).T
    assert np.all(clip[:, 3] > 0), "the blocker must be in front of the light (clip w > 0)"
    return clip[:, :3] / clip[:, 3:]


@given(light_and_blocker(), map_sizes)
def test_every_blocker_vertex_lands_inside_the_margin(
    to: Any, dtype: Any, scene: Any, size: Any
) -> None:
    light, verts = scene
    setup = fit_shadow(to(light), to(verts), size)
    p = ndc(setup.blocker_to_clip, verts)
    mx, my = border_margin(size)
    slack = 1 + 20 * rtol_for(dtype)
    assert np.all(np.abs(p[:, 0]) <= mx * slack)
    assert np.all(np.abs(p[:, 1]) <= my * slack)
    assert np.all(np.abs(p[:, 2]) < 1), "default near/far must not clip the blocker"


@given(light_and_blocker(), map_sizes)
def test_some_vertex_touches_the_margin_on_each_axis(
    to: Any, dtype: Any, scene: Any, size: Any
) -> None:
    light, verts = scene
    setup = fit_shadow(to(light), to(verts), size)
    p = ndc(setup.blocker_to_clip, verts)
    mx, my = border_margin(size)
    np.testing.assert_allclose(np.abs(p[:, 0]).max(), mx, rtol=20 * rtol_for(dtype))
    np.testing.assert_allclose(np.abs(p[:, 1]).max(), my, rtol=20 * rtol_for(dtype))


@pytest.mark.parametrize(
    ("size", "border", "expected"),
    [
        (100, 1, (0.98, 0.98)),  # the article's constant is the 100-texel case
        (16, 1, (14 / 16, 14 / 16)),
        ((512, 64), 2, (508 / 512, 60 / 64)),
        (3, 1, (1 / 3, 1 / 3)),
    ],
)
def test_border_margin_is_derived_from_the_resolution(
    size: Any, border: int, expected: tuple[float, float]
) -> None:
    assert border_margin(size, border_texels=border) == pytest.approx(expected, rel=1e-15)


@given(st.integers(3, 4096), st.integers(0, 8))
def test_margin_keeps_every_border_texel_untouched(size: int, border: int) -> None:
    if size <= 2 * border:
        with pytest.raises(ValueError, match="map_size"):
            border_margin(size, border_texels=border)
        return
    m, _ = border_margin(size, border_texels=border)
    # texel i spans NDC [-1 + 2 i / size, -1 + 2 (i + 1) / size]: the silhouette within
    # [-m, m] can reach texels border .. size-1-border only
    first = int(np.floor((-m + 1) * size / 2 + 1e-9))
    last = int(np.ceil((m + 1) * size / 2 - 1e-9)) - 1
    assert (first, last) == (border, size - 1 - border)


def test_the_article_constant_is_not_enough_below_100_texels() -> None:
    for size in (16, 64, 99):
        assert border_margin(size)[0] < 0.98
    for size in (100, 256, 1024):
        assert border_margin(size)[0] >= 0.98


@given(light_and_blocker(), map_sizes)
def test_frustum_matches_brute_force_ratios(scene: Any, size: Any) -> None:
    light, verts = scene
    f = light_frame(light, verts)
    fr = adaptive_frustum(f, verts, size)
    p = homog(verts) @ world_to_light(f).T
    np.testing.assert_allclose(fr.rx_max, np.max(np.abs(p[:, 0] / p[:, 2])), rtol=1e-12)
    np.testing.assert_allclose(fr.ry_max, np.max(np.abs(p[:, 1] / p[:, 2])), rtol=1e-12)
    np.testing.assert_allclose(fr.near, p[:, 2].min() * (1 - NEAR_FAR_SLACK), rtol=1e-12)
    np.testing.assert_allclose(fr.far, p[:, 2].max() * (1 + NEAR_FAR_SLACK), rtol=1e-12)
    assert (float(fr.margin_x), float(fr.margin_y)) == border_margin(size)


def test_forced_article_margin() -> None:
    verts = np.array([[-1.0, -2, 5], [1, 2, 5], [0.5, -1, 6]])
    fr = adaptive_frustum(light_frame([0, 0, 0], verts), verts, 16, margin=0.98)
    assert float(fr.margin_x) == float(fr.margin_y) == 0.98


frusta = st.builds(
    lambda rx, ry, n, gap, mx, my: Frustum(rx, ry, n, n + gap, mx, my),
    st.floats(0.01, 10),
    st.floats(0.01, 10),
    st.floats(0.01, 100),
    st.floats(0.01, 100),
    st.floats(0.1, 1),
    st.floats(0.1, 1),
)


@given(frusta, arrays(np.float64, (6, 3), elements=st.floats(-1, 1)))
def test_blocker_projection_geometry(fr: Frustum, unit: np.ndarray) -> None:
    P = blocker_projection(fr)
    # points inside the frustum: |x| <= rx z, |y| <= ry z, near <= z <= far
    z = fr.near + (unit[:, 2] + 1) / 2 * (fr.far - fr.near)
    pts = np.c_[unit[:, 0] * fr.rx_max * z, unit[:, 1] * fr.ry_max * z, z]
    clip = homog(pts) @ P.T
    np.testing.assert_allclose(clip[:, 3], z, rtol=1e-12)  # clip w = +z
    p = clip[:, :3] / clip[:, 3:]
    np.testing.assert_allclose(p[:, 0], unit[:, 0] * fr.margin_x, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(p[:, 1], unit[:, 1] * fr.margin_y, rtol=1e-9, atol=1e-12)
    # depth: -1 at near, +1 at far, increasing with z
    ends = homog(np.array([[0, 0, fr.near], [0, 0, fr.far]])) @ P.T
    np.testing.assert_allclose(ends[:, 2] / ends[:, 3], [-1, 1], atol=1e-9)
    order = np.argsort(z)
    assert np.all(np.diff(p[order, 2]) >= -1e-12)


@given(frusta, arrays(np.float64, (6, 3), elements=st.floats(-5, 5)))
def test_receiver_projection_is_the_scale_and_bias_of_the_blocker_projection(
    fr: Frustum, pts: np.ndarray
) -> None:
    pts = pts + [0, 0, 6]  # z in [1, 11]: in front of the light
    clip = homog(pts) @ blocker_projection(fr).T
    stq = homog(pts) @ receiver_projection(fr).T
    np.testing.assert_allclose(stq[:, 3], pts[:, 2], rtol=1e-12)  # q = z
    s = stq[:, :3] / stq[:, 3:]
    np.testing.assert_allclose(s, 0.5 + 0.5 * clip[:, :3] / clip[:, 3:], rtol=1e-9, atol=1e-12)
    expected_s = 0.5 + 0.5 * fr.margin_x * pts[:, 0] / (fr.rx_max * pts[:, 2])
    np.testing.assert_allclose(s[:, 0], expected_s, rtol=1e-9, atol=1e-12)


def test_receiver_scale_is_the_article_049_at_100_texels() -> None:
    verts = np.array([[-1.0, -1, 4], [1, 1, 4], [1, -1, 4], [-1, 1, 4]])
    fr = adaptive_frustum(light_frame([0, 0, 0], verts), verts, 100)
    T = receiver_projection(fr)
    np.testing.assert_allclose(T[0, 0] * fr.rx_max, 0.49)
    np.testing.assert_allclose(T[1, 1] * fr.ry_max, 0.49)


@given(light_and_blocker(), st.floats(1.0, 5.0), st.integers(16, 1024))
def test_receiver_points_behind_a_vertex_share_its_texel(
    to: Any, dtype: Any, scene: Any, k: float, size: int
) -> None:
    """The projective property: the shadow of a vertex on any receiver samples that vertex."""
    light, verts = scene
    setup = fit_shadow(to(light), to(verts), size)
    T = np.asarray(setup.world_to_texture, np.float64)
    behind = light + k * (verts - light)
    a, b = homog(verts) @ T.T, homog(behind) @ T.T
    assert np.all(a[:, 3] > 0) and np.all(b[:, 3] > 0)
    np.testing.assert_allclose(
        a[:, :2] / a[:, 3:],
        b[:, :2] / b[:, 3:],
        rtol=50 * rtol_for(dtype),
        atol=50 * rtol_for(dtype),
    )
    # and the texel is the one the blocker was drawn into
    clip = ndc(setup.blocker_to_clip, verts)
    np.testing.assert_allclose(
        a[:, :2] / a[:, 3:], 0.5 + 0.5 * clip[:, :2], atol=50 * rtol_for(dtype)
    )


def _placement(rng: np.random.Generator) -> np.ndarray:
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    B = np.eye(4)
    B[:3, :3] = q * rng.uniform(0.5, 2)
    B[:3, 3] = rng.normal(size=3) * 3
    return B


@pytest.mark.parametrize("seed", range(5))
def test_blocker_placement_equals_pretransformed_vertices(seed: int) -> None:
    rng = np.random.default_rng(seed)
    local = rng.normal(size=(20, 3))
    B = _placement(rng)
    world = (homog(local) @ B.T)[:, :3]
    light = world.mean(0) + rng.normal(size=3) * 10 + [0, 0, 15]
    placed = fit_shadow(light, local, (64, 32), blocker_to_world=B)
    direct = fit_shadow(light, world, (64, 32))
    np.testing.assert_allclose(placed.blocker_to_clip, direct.blocker_to_clip @ B, atol=1e-10)
    np.testing.assert_allclose(placed.world_to_texture, direct.world_to_texture, atol=1e-12)
    np.testing.assert_allclose(placed.blocker_to_world, B)
    R = _placement(rng)
    p = homog(rng.normal(size=(5, 3)))
    np.testing.assert_allclose(
        p @ receiver_texture_matrix(placed, R).T, (p @ R.T) @ placed.world_to_texture.T, atol=1e-10
    )


def test_batched_fit_equals_a_loop() -> None:
    rng = np.random.default_rng(7)
    lights = rng.normal(size=(4, 1, 3)) * 3 + [0, 0, -12]
    verts = rng.normal(size=(3, 9, 3))
    s = fit_shadow(lights, verts, 128)
    assert s.blocker_to_clip.shape == (4, 3, 4, 4) and s.frustum.rx_max.shape == (4, 3)
    for i in range(4):
        for j in range(3):
            one = fit_shadow(lights[i, 0], verts[j], 128)
            np.testing.assert_allclose(s.blocker_to_clip[i, j], one.blocker_to_clip, rtol=1e-12)
            np.testing.assert_allclose(s.world_to_texture[i, j], one.world_to_texture, rtol=1e-12)


def test_user_near_far_are_used() -> None:
    verts = np.array([[-1.0, -1, 4], [1, 1, 4], [1, -1, 5]])
    s = fit_shadow([0, 0, 0], verts, 64, near=0.5, far=100.0)
    assert float(s.frustum.near) == 0.5 and float(s.frustum.far) == 100.0
    with pytest.raises(ValueError, match="near"):
        fit_shadow([0, 0, 0], verts, 64, near=5.0, far=2.0)
    with pytest.raises(ValueError, match="near"):
        fit_shadow([0, 0, 0], verts, 64, near=-1.0)
