"""ShadowFitter: the per-frame path is fit_shadow, prepared once, into the caller's buffers."""

from __future__ import annotations

import re
from typing import Any

import numpy as np
import pytest

import shadowmath as sm
from shadowmath._backends import _kernels

RNG = np.random.default_rng(7)


def _box(shift: Any = (0.0, 0.0, 6.0), n: int = 8) -> np.ndarray:
    return RNG.normal(size=(n, 3)) + np.asarray(shift)


def _same(frame: sm.PreparedFit, setup: sm.ShadowSetup) -> None:
    for name in ("world_to_texture", "blocker_to_clip", "world_to_light"):
        np.testing.assert_allclose(getattr(frame, name), getattr(setup, name), rtol=0, atol=1e-12)
    np.testing.assert_array_equal(frame.casters_used, setup.casters_used)


# (a light of this frame, the map's options, this frame's other operands)
CASES = {
    "point": (lambda: sm.PointLight(RNG.normal(size=3) * 0.1), {}, {}),
    "sun, stable, receivers": (
        lambda: sm.DirectionalLight(np.array([0.3, 1.0, -0.2]) + RNG.normal(size=3) * 0.05),
        {"stable": True},
        {"receivers": _box((0.0, -2.0, 6.0), 30)},
    ),
    "spot, some casters outside": (
        lambda: sm.SpotLight(np.zeros(3), np.array([0.0, 0.2, 1.0]), 0.35),
        {},
        {},
    ),
    "point, triangles, up": (
        lambda: sm.PointLight(RNG.normal(size=3) * 0.1),
        {"api": "vulkan"},
        {"up": np.array([0.0, 1.0, 0.0])},
    ),
}


@pytest.mark.parametrize("name", CASES)
@pytest.mark.parametrize("numba", [True, False])
def test_each_frame_is_fit_shadow_of_that_frame(name: str, numba: bool) -> None:
    make_light, spec, options = CASES[name]
    triangles = "triangles" in name
    casters = _box(n=12)
    if triangles:
        casters = sm.Triangles(casters.reshape(4, 3, 3))
    fitter = sm.ShadowFitter(make_light(), casters, 256, **spec, **options)
    out = fitter.buffers()
    for frame in range(4):
        light = make_light()
        blob = _box(n=12 + 3 * frame)  # the number of casters may change every frame
        casters = sm.Triangles(blob.reshape(-1, 3, 3)) if triangles else blob
        if numba:
            got = fitter.fit(light, casters, out=out, **options)
        else:
            with _kernels.disabled():
                got = fitter.fit(light, casters, out=out, **options)
        _same(got, sm.fit_shadow(light, casters, 256, **spec, **options))
        assert np.shares_memory(got.world_to_texture, out.mats)


def test_spot_fitter_selects_casters_as_fit_shadow_does() -> None:
    spot = sm.SpotLight(np.zeros(3), np.array([0.0, 0.0, 1.0]), 0.3)
    inside = 0.3 * RNG.normal(size=(2, 3, 3)) + [0.0, 0.0, 6.0]
    outside = inside + [30.0, 0.0, 0.0]  # (triangles are clipped to the cone exactly)
    fitter = sm.ShadowFitter(spot, sm.Triangles(inside), 128)
    got = fitter.fit(spot, sm.Triangles(np.concatenate([inside, outside])))
    assert int(got.casters_used) == 2
    _same(got, sm.fit_shadow(spot, sm.Triangles(inside), 128)._replace(casters_used=2))


def test_the_whole_setup_when_asked() -> None:
    light, box = sm.PointLight(np.zeros(3)), _box()
    fitter = sm.ShadowFitter(light, box, 64)
    setup, expected = fitter.setup(fitter.fit(light, box)), sm.fit_shadow(light, box, 64)
    for a, b in zip(setup.frustum[:8], expected.frustum[:8], strict=True):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-12)
    np.testing.assert_allclose(setup.frame.z_axis, expected.frame.z_axis, rtol=0, atol=1e-15)


def test_bad_values_raise_every_frame_as_fit_shadow_does() -> None:
    light, box = sm.PointLight(np.zeros(3)), _box()
    fitter = sm.ShadowFitter(light, box, 64)
    bad = box.copy()
    bad[3, 1] = np.nan
    with pytest.raises(ValueError, match="blocker_vertices"):
        fitter.fit(light, bad)
    around = np.concatenate([box, -box])  # casters on both sides of the light
    with pytest.raises(ValueError, match="light") as expected:
        sm.fit_shadow(light, around, 64)
    with pytest.raises(ValueError, match=re.escape(str(expected.value))):
        fitter.fit(light, around)


def test_a_different_fit_is_refused_and_lists_go_through_the_door() -> None:
    light, box = sm.PointLight(np.zeros(3)), _box()
    fitter = sm.ShadowFitter(light, box, 64)
    with pytest.raises(ValueError, match="not the prepared fit"):
        fitter.fit(sm.DirectionalLight(np.array([0.0, 0.0, -1.0])), box)
    with pytest.raises(ValueError, match="not the prepared fit"):
        fitter.fit(light, box, up=np.array([0.0, 1.0, 0.0]))
    with pytest.raises(ValueError, match="not the prepared fit"):
        fitter.fit(sm.PointLight(np.zeros(3, np.float32)), box.astype(np.float32))
    _same(fitter.fit(light, box.tolist()), sm.fit_shadow(light, box, 64))


def test_jax_is_refused() -> None:
    import jax.numpy as jnp

    with pytest.raises(TypeError, match=r"jax\.jit"):
        sm.ShadowFitter(sm.PointLight(jnp.zeros(3)), jnp.asarray(_box()), 64)


def test_a_homogeneous_light_is_read_every_frame() -> None:
    box = _box()
    fitter = sm.ShadowFitter(np.array([0.0, 0.0, 0.0, 1.0]), box, 64)
    for light in (np.array([0.0, 0.2, 0.0, 0.5]), np.array([0.1, 0.0, 0.0, 2.0])):
        _same(fitter.fit(light, box), sm.fit_shadow(light, box, 64))
    with pytest.raises(ValueError, match="not the prepared fit"):
        fitter.fit(np.array([0.0, 0.0, -1.0, 0.0]), box)  # a directional light now
