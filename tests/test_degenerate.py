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
