"""Spot lights: the MDV fit along the cone's axis, clipped to the cone's bounding square."""

from __future__ import annotations

import contextlib
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import shadowmath as sm
from shadowmath._backends import _kernels

BOX = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (4, 6)], dtype=float)
AXIS = np.array([0.0, 0.0, 1.0])


def _ndc(M: Any, pts: np.ndarray) -> np.ndarray:
    clip = np.c_[pts, np.ones(len(pts))] @ np.asarray(M).T
    return clip[:, :3] / clip[:, 3:]


def _ratios(s: sm.ShadowSetup, pts: np.ndarray) -> np.ndarray:
    p = (pts - s.frame.origin) @ np.stack([s.frame.x_axis, s.frame.y_axis, s.frame.z_axis]).T
    return p[:, :2] / p[:, 2:]


PATHS = {
    "compiled": contextlib.nullcontext,
    "python loop": _kernels.disabled,
    "array path": _kernels.array_path,
}


@pytest.mark.parametrize("path", PATHS)
def test_a_wide_cone_fits_the_blocker_off_centre(path: str) -> None:
    # Light beside the box, aimed straight ahead: the box's ratios lie off the axis.
    spot = sm.SpotLight(np.array([2.0, 0.5, 0.0]), AXIS, np.array(1.2))
    with PATHS[path]():
        s = sm.fit_shadow(spot, BOX, 128)
    np.testing.assert_allclose(s.frame.z_axis, AXIS, atol=1e-15)
    ndc = _ndc(s.blocker_to_clip, BOX)
    m = sm.border_margin(128)[0]
    # Every vertex inside, one on each of the four sides (an off-centre tight fit).
    for axis in (0, 1):
        assert ndc[:, axis].max() == pytest.approx(m, abs=1e-12)
        assert ndc[:, axis].min() == pytest.approx(-m, abs=1e-12)
    assert np.all(np.abs(ndc[:, 2]) < 1)
    r = _ratios(s, BOX)
    assert float(s.frustum.x_offset) == pytest.approx(0.5 * (r[:, 0].max() + r[:, 0].min()))
    assert float(s.frustum.rx_max) == pytest.approx(0.5 * (r[:, 0].max() - r[:, 0].min()))


@pytest.mark.parametrize("path", PATHS)
def test_a_narrow_cone_spends_the_map_on_its_square_only(path: str) -> None:
    angle = 0.1
    spot = sm.SpotLight(np.array([0.5, 0.0, 0.0]), AXIS, np.array(angle))
    with PATHS[path]():
        s = sm.fit_shadow(spot, BOX, 64)
    t = np.tan(angle)
    np.testing.assert_allclose([s.frustum.rx_max, s.frustum.ry_max], [t, t], rtol=1e-14)
    np.testing.assert_allclose([s.frustum.x_offset, s.frustum.y_offset], [0, 0], atol=1e-15)
    # The rays along the corners of the cone's square land on the map's margins.
    corners = np.array([[sx * t * 5, sy * t * 5, 5.0] for sx in (-1, 1) for sy in (-1, 1)])
    ndc = _ndc(s.blocker_to_clip, corners + [0.5, 0, 0])
    np.testing.assert_allclose(np.abs(ndc[:, :2]), sm.border_margin(64)[0], rtol=1e-13)


def test_a_cone_edge_clips_one_side_and_the_blocker_fixes_the_other() -> None:
    # From x = 0.5 the box spans world x / z in [-0.375, 0.125] and y / z in [-0.25, 0.25];
    # a cone of tan 0.2 cuts the first at -0.2 and both ends of the second.
    t = 0.2
    spot = sm.SpotLight(np.array([0.5, 0.0, 0.0]), AXIS, np.array(np.arctan(t)))
    s = sm.fit_shadow(spot, BOX, 100)
    r = _ratios(s, BOX)  # in the returned frame (its X, Y are the world's y, x here)
    half = (s.frustum.rx_max, s.frustum.ry_max)
    offset = (s.frustum.x_offset, s.frustum.y_offset)
    for k in (0, 1):
        lo, hi = max(r[:, k].min(), -t), min(r[:, k].max(), t)
        assert float(offset[k]) == pytest.approx(0.5 * (hi + lo), abs=1e-15)
        assert float(half[k]) == pytest.approx(0.5 * (hi - lo), rel=1e-13)
    clipped = int(np.argmax(np.abs(r).max(axis=0) > 0.3))  # world x's axis
    assert np.abs(r[:, clipped]).max() == pytest.approx(0.375, rel=1e-13)
    ndc = _ndc(s.blocker_to_clip, BOX)[:, clipped]
    inner = 1 if r[:, clipped].max() < t else 0  # the end the blocker fixes
    m = sm.border_margin(100)[0]
    assert (ndc.max() if inner else -ndc.min()) == pytest.approx(m, abs=1e-12)
    assert (-ndc.min() if inner else ndc.max()) > 1  # beyond the cone: outside the map


def test_spot_frame_follows_up_and_the_axis_not_the_blocker() -> None:
    axis = np.array([0.1, -0.2, 1.0])
    spot = sm.SpotLight(np.array([0.0, 0.0, 0.0]), axis, np.array(0.8))
    s = sm.fit_shadow(spot, BOX, 64, up=np.array([0.0, 1.0, 0.0]))
    np.testing.assert_allclose(s.frame.z_axis, axis / np.linalg.norm(axis), atol=1e-15)
    assert float(s.frame.y_axis[1]) > 0.9  # look-at: Y is up's part across Z
    np.testing.assert_allclose(np.cross(s.frame.x_axis, s.frame.y_axis), -s.frame.z_axis)


def test_receivers_inside_the_cone_widen_the_depth_range() -> None:
    spot = sm.SpotLight(np.array([0.0, 0.0, 0.0]), AXIS, np.array(0.6))
    floor = np.array([[0.0, 0.0, 9.0], [0.1, 0.1, 12.0], [40.0, 0.0, 20.0]])  # last: outside
    s = sm.fit_shadow(spot, BOX, 64, receivers=floor)
    ndc = _ndc(s.blocker_to_clip, floor)
    assert np.all(np.abs(ndc[:2, 2]) < 1)
    assert float(s.frustum.far) < 20  # the receiver outside the cone's square is not counted


@pytest.mark.parametrize(
    ("spot", "message"),
    [
        (sm.SpotLight(np.zeros(3), np.zeros(3), np.array(0.3)), "spot light's direction"),
        (sm.SpotLight(np.zeros(3), AXIS, np.array(np.pi / 2)), "spot light's angle"),
        (sm.SpotLight(np.zeros(3), AXIS, np.array(0.0)), "spot light's angle"),
    ],
)
@pytest.mark.parametrize("path", PATHS)
def test_bad_spots_raise_the_same_message_on_every_path(spot: Any, message: str, path: str) -> None:
    with PATHS[path](), pytest.raises(ValueError, match=message):
        sm.fit_shadow(spot, BOX, 64)


def test_jax_matches_numpy_poisons_and_differentiates() -> None:
    spot = sm.SpotLight(np.array([2.0, 0.5, 0.0]), AXIS, np.array(0.4))
    ref = sm.fit_shadow(spot, BOX, 64)

    def clip(p: Any, d: Any, a: Any) -> Any:
        return sm.fit_shadow(sm.SpotLight(p, d, a), jnp.asarray(BOX), 64).blocker_to_clip

    got = jax.jit(clip)(*(jnp.asarray(v) for v in spot))
    np.testing.assert_allclose(np.asarray(got), ref.blocker_to_clip, rtol=1e-5, atol=1e-5)
    bad = jax.jit(clip)(jnp.zeros(3), jnp.asarray(AXIS), jnp.asarray(2.0))
    assert bool(jnp.all(jnp.isnan(bad)))
    grads = jax.grad(lambda *v: jnp.sum(clip(*v)), argnums=(0, 1, 2))(
        *(jnp.asarray(v) for v in spot)
    )
    assert all(bool(jnp.all(jnp.isfinite(g))) for g in grads)

    # The narrow cone's sides depend on the angle alone: d rx_max / d angle = 1 / cos^2.
    def rx(a: Any) -> Any:
        return sm.fit_shadow(
            sm.SpotLight(jnp.zeros(3), jnp.asarray(AXIS), a), BOX, 64
        ).frustum.rx_max

    g = jax.grad(rx)(jnp.asarray(0.1, dtype=jnp.float32))
    assert float(g) == pytest.approx(1 / np.cos(0.1) ** 2, rel=1e-5)
