"""Fits that would be finite but useless say so: a warning past a soft limit, an error
(NaN under JAX transformations) past a hard one, each message naming the argument."""

from __future__ import annotations

import contextlib
import math
import re
import warnings
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import shadowmath as sm
from shadowmath._backends import _kernels
from shadowmath._boundary import _messages as msg

BOX = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (4, 6)], dtype=float)
# The messages' words (a changed message must fail here).
TOO_WIDE = (
    re.escape(
        "light: the fitted frustum would be wider than 170 degrees (the light is too close to "
        "the blocker, or inside its hull)"
    )
    + ".*use a cube map"
)
NEAR_ROUNDING = re.escape("light: the nearest caster is within rounding of the light")
SINGULAR = re.escape("blocker_to_world: the placement is singular") + ".*flattens the blocker"
PATHS = {
    "compiled": contextlib.nullcontext,
    "python loop": _kernels.disabled,
    "array path": _kernels.array_path,
}


def _fov_degrees(s: sm.ShadowSetup) -> float:
    """The map's full field of view along its wider axis, from the returned frustum."""
    f = s.frustum
    tx = abs(float(f.x_offset)) + float(f.rx_max) / float(f.margin_x)
    ty = abs(float(f.y_offset)) + float(f.ry_max) / float(f.margin_y)
    return 2 * math.degrees(math.atan(max(tx, ty)))


#: Wider along x than along y, so that (with up = y: light X is world x) the light's X
#: axis decides the field of view.
SLAB = BOX * [1.0, 0.4, 1.0]
UP = np.array([0.0, 1.0, 0.0])


def _fit_quietly(light: Any, spec: sm.ShadowMapSpec) -> tuple[sm.ShadowSetup, list[str]]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        s = sm.fit_shadow(light, SLAB, spec, up=UP)
    return s, [str(w.message) for w in caught if w.category is sm.ShadowFitWarning]


@pytest.mark.parametrize("border", [1, 15])  # margins 0.97 and 0.53: the map's edge, not h
@pytest.mark.parametrize("path", PATHS)
def test_the_field_of_view_warns_past_120_and_is_refused_past_170_degrees(
    path: str, border: int
) -> None:
    # The light approaches the centre of the box's face (z = 4) along the axis: the
    # frustum widens toward 180 degrees.
    seen = []
    spec = sm.ShadowMapSpec(64, border_texels=border)
    with PATHS[path]():
        for z in (0.0, 2.0, 2.5, 2.8, 3.0, 3.2, 3.4, 3.6, 3.7, 3.8):
            s, caught = _fit_quietly([0.0, 0.0, z], spec)
            fov = _fov_degrees(s)
            seen.append(fov)
            assert (fov > msg.WIDE_FOV_DEGREES) == bool(caught), (z, fov, caught)
            assert fov <= msg.MAX_FOV_DEGREES
            assert float(s.frustum.rx_max) > float(s.frustum.ry_max)
            if caught:
                assert caught == [msg.WIDE]
                assert caught[0].startswith("light: the fitted frustum is wider than 120 degrees")
        # The case: 0.001 from the face's centre, about 179.9 degrees.
        with pytest.raises(ValueError, match=TOO_WIDE):
            sm.fit_shadow([0.0, 0.0, 3.999], SLAB, spec, up=UP)
    assert min(seen) < 120 < max(seen)  # both sides of the soft limit were tried


def test_too_wide_is_nan_under_jit() -> None:
    def clip(light: Any) -> Any:
        return sm.fit_shadow(sm.PointLight(light), jnp.asarray(BOX), 64).blocker_to_clip

    assert bool(jnp.isnan(jax.jit(clip)(jnp.asarray([0.0, 0.0, 3.999]))).all())
    assert bool(jnp.isfinite(jax.jit(clip)(jnp.asarray([0.0, 0.0, 3.0]))).all())
    with pytest.raises(ValueError, match=TOO_WIDE):
        sm.fit_shadow(jnp.asarray([0.0, 0.0, 3.999]), jnp.asarray(BOX), 64)  # concrete: raises


@pytest.mark.parametrize("path", PATHS)
def test_a_caster_within_rounding_of_the_light_is_refused(path: str) -> None:
    # Far from the origin, a vertex 1e-9 in front of the light is below the rounding
    # of the coordinates (32 eps 1e6 = 7e-9): the near plane would be noise.
    L = np.array([1e6, 0.0, 0.0])
    offsets = np.array([[0.0, 0.0, 1e-9], [1, 1, 10], [-1, 1, 10], [0, -1, 10]])
    with PATHS[path](), pytest.raises(ValueError, match=NEAR_ROUNDING):
        sm.fit_shadow(L, L + offsets, 64)
    # The same scene about a nearby origin is fine: its coordinates are small.
    s = sm.fit_shadow(np.zeros(3), offsets, 64)
    assert 0 < float(s.frustum.near) <= 1e-9


@pytest.mark.parametrize("path", PATHS)
def test_a_singular_placement_is_named_on_blocker_to_world(path: str) -> None:
    with PATHS[path]():
        for B in (np.diag([0.0, 0.0, 0.0, 1.0]), np.diag([1.0, 1.0, 0.0, 1.0])):
            with pytest.raises(ValueError, match=SINGULAR):
                sm.fit_shadow([0.0, 0.0, -3.0], BOX, 64, blocker_to_world=B)
        # A uniformly tiny (or huge) placement is invertible: it passes.
        for scale in (1e-6, 1e6):
            B = np.diag([scale, scale, scale, 1.0])
            s = sm.fit_shadow([0.0, 0.0, -3.0 * scale], BOX, 64, blocker_to_world=B)
            assert np.isfinite(s.blocker_to_clip).all()


ROW_MAJOR = re.escape("blocker_to_world: its last row is not (0, 0, 0, 1)") + ".*row-major"


def _placement(dtype: Any = np.float64) -> np.ndarray:
    """A rigid placement (a turn about y, then far along x and z), column-vector convention."""
    c, s = math.cos(0.7), math.sin(0.7)
    return np.array([[c, 0, s, 40.0], [0, 1, 0, 2.0], [-s, 0, c, 30.0], [0, 0, 0, 1]], dtype)


@pytest.mark.parametrize("path", PATHS)
def test_a_row_major_placement_is_refused(path: str) -> None:
    """The transpose of a placement (its translation in the bottom row, as a row-vector API
    stores it) is refused by name; the placement itself fits, as the vertices placed by
    hand do. (Before the check, the transpose was fitted whenever every w was > 0.)"""
    B = _placement()
    light = np.array([40.0, 2.0, 20.0])
    with PATHS[path]():
        placed = sm.fit_shadow(light, BOX, 64, blocker_to_world=B)
        by_hand = sm.fit_shadow(light, BOX @ B[:3, :3].T + B[:3, 3], 64)
        np.testing.assert_allclose(placed.world_to_texture, by_hand.world_to_texture, atol=1e-12)
        with pytest.raises(ValueError, match=ROW_MAJOR):
            sm.fit_shadow(light, BOX * 1e-3, 64, blocker_to_world=B.T)  # every w > 0
        fitter = sm.ShadowFitter(light, BOX, 64, blocker_to_world=B)
        with pytest.raises(ValueError, match=ROW_MAJOR):
            fitter.fit(light, BOX * 1e-3, blocker_to_world=B.T)
    assert np.all(B.T[3] @ np.c_[BOX * 1e-3, np.ones(8)].T > 0)  # not refused for w <= 0


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_the_last_row_is_read_to_rounding(dtype: Any) -> None:
    """``4 eps`` times the largest entry: rounding in a last row passes, more is refused."""
    B = _placement(dtype)
    eps, big = float(np.finfo(dtype).eps), float(np.abs(B).max())
    light = np.array([40.0, 2.0, 20.0], dtype)
    for j, off in ((0, 2.0), (3, -3.0)):
        noisy = B.copy()
        noisy[3, j] += dtype(off * eps * big)
        assert np.isfinite(sm.fit_shadow(light, BOX.astype(dtype), 64, blocker_to_world=noisy)
                           .blocker_to_clip).all()  # fmt: skip
        noisy[3, j] += dtype(8 * eps * big)
        with pytest.raises(ValueError, match=ROW_MAJOR):
            sm.fit_shadow(light, BOX.astype(dtype), 64, blocker_to_world=noisy)


def test_a_row_major_placement_is_nan_under_jit_and_refused_by_the_optimized_fit() -> None:
    B = _placement()
    light = np.array([40.0, 2.0, 20.0])
    fit = jax.jit(lambda M: sm.fit_shadow(sm.PointLight(jnp.asarray(light)), jnp.asarray(BOX),
                                          64, blocker_to_world=M))  # fmt: skip
    assert np.isfinite(fit(jnp.asarray(B)).blocker_to_clip).all()
    assert np.isnan(fit(jnp.asarray(B.T)).blocker_to_clip).all()
    with pytest.raises(ValueError, match=ROW_MAJOR):
        sm.fit_shadow(jnp.asarray(light), jnp.asarray(BOX), 64, blocker_to_world=jnp.asarray(B.T),
                      method="optimized")  # fmt: skip
    with pytest.raises(ValueError, match=re.escape("receiver_to_world: its last row")):
        sm.receiver_texture_matrix(sm.fit_shadow(light, BOX, 64, blocker_to_world=B), B.T)


def test_a_border_wider_than_half_the_map_warns() -> None:
    with pytest.warns(sm.ShadowFitWarning, match=r"map_size: a border of 20 texel\(s\) on each"):
        sm.ShadowMapSpec(64, border_texels=20)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sm.ShadowMapSpec(64, border_texels=15)  # 34 of 64 texels inside: no warning
    with pytest.raises(ValueError, match="map_size: 64x64 texels leave no room inside a border"):
        sm.ShadowMapSpec(64, border_texels=32)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_a_placement_far_from_the_origin_is_not_singular(dtype: Any) -> None:
    # Found by the fuzz: the translation must not enter the singularity test (a
    # renderer's model matrix moves a unit blocker far away).
    far = 1e6 if dtype == np.float64 else 1e3
    B = np.eye(4)
    B[:3, 3] = far
    s = sm.fit_shadow(np.array([far, far, far - 3.0], dtype), BOX.astype(dtype), 64,
                      blocker_to_world=B.astype(dtype))  # fmt: skip
    assert np.isfinite(s.blocker_to_clip).all()


# --- float32 far from the origin ------------------------------------------------------------

PRECISION = r"blocker_vertices: float32 coordinates this far from the origin are rounded in steps"
CENTRE = re.escape("the light sits at the blocker's centre")


def _far_scene(offset: float, dtype: Any) -> tuple[np.ndarray, np.ndarray]:
    """BOX (2 units across) and a light 3 units before it, moved ``offset`` along each axis."""
    o = np.full(3, offset)
    return (np.array([0.0, 0.0, -3.0]) + o).astype(dtype), (BOX + o).astype(dtype)


def _precision_warnings(light: Any, verts: Any, n: int) -> list[str]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sm.fit_shadow(light, verts, n)
    return [str(w.message) for w in caught if "rounded in steps" in str(w.message)]


@pytest.mark.parametrize("path", PATHS)
def test_float32_far_from_the_origin_warns_past_a_quarter_texel(path: str) -> None:
    """The rule: eps max|p| (the rounding step of the largest coordinate) over a quarter of
    a texel, the casters' extent E over the map's n texels, warns; the message names the
    remedies. Offsets a factor 2 on either side of the threshold (in float32), and the
    same scenes in float64 or recentred, which are quiet."""
    eps, E, n = float(np.finfo(np.float32).eps), 2.0, 256
    threshold = (E / n) / 4 / eps  # the largest coordinate at which the step is a quarter texel
    with PATHS[path]():
        for offset, warns in ((threshold / 2 - 6, False), (2 * threshold, True)):
            light, verts = _far_scene(offset, np.float32)
            assert (eps * np.abs(verts).max() > E / n / 4) == warns  # the rule, by hand
            got = _precision_warnings(light, verts, n)
            assert len(got) == int(warns), got
            if warns:
                assert "pass float64 arrays, or recentre the coordinates" in got[0]
            assert not _precision_warnings(*_far_scene(offset, np.float64), n)
            assert not _precision_warnings(*_far_scene(0.0, np.float32), n)
    # The warning is warranted: the float32 fit's stored depth of a receiver differs from
    # float64's by more than the step's share of the depth range.
    light, verts = _far_scene(1e6, np.float32)
    with pytest.warns(sm.ShadowFitWarning, match=PRECISION):
        s32 = sm.fit_shadow(light, verts, n)
    s64 = sm.fit_shadow(light.astype(np.float64), verts.astype(np.float64), n)
    p = np.r_[verts.astype(np.float64).mean(axis=0) + [0.3, 0.2, 5.0], 1.0]
    d32, d64 = (np.asarray(s.world_to_texture, np.float64) @ p for s in (s32, s64))
    assert abs(d32[2] / d32[3] - d64[2] / d64[3]) > 1e-3  # float64's own error: ~1e-10


@pytest.mark.parametrize("path", PATHS)
def test_a_float32_light_far_from_its_casters_counts_in_the_rounding(path: str) -> None:
    """A point light's position is rounded as the casters are, and the fit differences
    them: a light 2x the threshold from the origin warns with its casters at the origin;
    a sun (a direction, no position) along the same line does not."""
    eps, E, n = float(np.finfo(np.float32).eps), 2.0, 256
    threshold = (E / n) / 4 / eps
    light = np.array([0.0, 0.0, -2 * threshold], dtype=np.float32)
    verts = (BOX - [0.0, 0.0, 5.0]).astype(np.float32)  # 2 units across, |p| <= 1.8
    with PATHS[path]():
        assert eps * np.abs(verts).max() < E / n / 4 < eps * np.abs(light).max()
        got = _precision_warnings(light, verts, n)
        assert len(got) == 1 and "pass float64 arrays, or recentre" in got[0], got
        sun = sm.DirectionalLight(np.array([0.0, 0.0, -1.0], dtype=np.float32))
        assert not _precision_warnings(sun, verts, n)


@pytest.mark.parametrize("path", PATHS)
def test_a_refusal_at_1e7_names_the_precision(path: str) -> None:
    """At 1e7 in float32 the rounding step (about 1.2) is over a 32nd of the casters' 2
    units: the fit's rounding checks refuse it, and the message names the precision and
    its remedies, not the light sitting at the blocker's centre. The same scene in float64
    fits; a light truly at the centre is still named so."""
    light, verts = _far_scene(1e7, np.float32)
    with PATHS[path]():
        with pytest.raises(ValueError, match=PRECISION) as info:
            sm.fit_shadow(light, verts, 256)
        assert "pass float64 arrays, or recentre" in str(info.value)
        assert not re.search(CENTRE, str(info.value))
        assert np.isfinite(sm.fit_shadow(*_far_scene(1e7, np.float64), 256).blocker_to_clip).all()
        centre = np.float32(BOX.mean(axis=0))
        with pytest.raises(ValueError, match=CENTRE):
            sm.fit_shadow(centre, BOX.astype(np.float32), 256)
    with pytest.raises(ValueError, match=PRECISION):  # concrete JAX: the same message
        sm.fit_shadow(jnp.asarray(light), jnp.asarray(verts), 256)
