"""``fit_cascades(orientation="fitted")``: each map turned to its body's minimum-area rectangle.

The oracle is independent of shadowmath's code: the vertices of each slice intersected with
the scene box by Qhull (:func:`tests.test_cascades.body`), projected on the light's plane,
and the minimum-area rectangle over their convex hull's edges (SciPy's ``ConvexHull``;
Freeman and Shapira 1975: one side lies along a hull edge).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from scipy.spatial import ConvexHull

import shadowmath as sm
from shadowmath._math._enclosing_rectangle import min_area_rectangle

from .cameras import scene
from .test_cascades import body, ndc

SEEDS = range(8)


def hull_min_area(points: np.ndarray) -> float:
    """The least bounding-box area over frames along the hull's edges of 2-D ``points``."""
    hull = points[ConvexHull(points).vertices]
    best = np.inf
    for d in np.roll(hull, -1, axis=0) - hull:
        u = d / np.linalg.norm(d)
        a, b = hull @ u, hull @ np.array([-u[1], u[0]])
        best = min(best, float(np.ptp(a) * np.ptp(b)))
    return best


@pytest.mark.parametrize("seed", SEEDS)
def test_each_turned_cascade_holds_its_slice_tightly_in_its_least_area(seed: int) -> None:
    sun, view, proj, box = scene(seed)
    c = sm.fit_cascades(sun, view, proj, box, 512, pcf_radius=2, orientation="fitted")
    plain = sm.fit_cascades(sun, view, proj, box, 512, pcf_radius=2)
    m = c.frustum.margin_x[0]
    np.testing.assert_allclose(c.splits, plain.splits, rtol=1e-12)
    for i in range(4):
        v = body(view, proj, box, c.splits[i], c.band_end[i])
        p = ndc(c.world_to_clip[i], v)
        assert np.all(np.abs(p[:, :2]) <= m * (1 + 1e-9))  # inside, a vertex on each side
        np.testing.assert_allclose(p[:, :2].max(0), [m, m], rtol=1e-9)
        np.testing.assert_allclose(p[:, :2].min(0), [-m, -m], rtol=1e-9)
        assert np.all((p[:, 2] > -1) & (p[:, 2] < 1))
        # The map's area is the least rectangle's around the body's shadow on the light plane.
        R = c.world_to_light[i, :3, :3]
        np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-12)  # a rotation: square texels
        np.testing.assert_allclose(R[2], plain.world_to_light[i, 2, :3], atol=1e-12)
        area = 4 * c.frustum.half_width[i] * c.frustum.half_height[i]
        assert area == pytest.approx(hull_min_area(v @ R[:2].T), rel=1e-9)
        texel = c.texel_size[i]
        assert texel[0] * texel[1] * (512 * m) ** 2 == pytest.approx(area, rel=1e-12)
        # world_to_texture is world_to_clip's OpenGL texture rows: (clip + 1) / 2.
        np.testing.assert_allclose(
            c.world_to_texture[i][:3],
            0.5 * (c.world_to_clip[i][:3] + c.world_to_clip[i][3]),
            atol=1e-12,
        )


@pytest.mark.parametrize("seed", range(24))
def test_the_turned_map_is_never_larger_than_the_axis_aligned_one(seed: int) -> None:
    sun, view, proj, box = scene(seed, lowest_pitch=-1.2)
    turned = sm.fit_cascades(sun, view, proj, box, 1024, orientation="fitted").frustum
    plain = sm.fit_cascades(sun, view, proj, box, 1024).frustum
    a = turned.half_width * turned.half_height
    b = plain.half_width * plain.half_height
    assert np.all(a <= b * (1 + 1e-12))


def test_a_turned_rectangle_is_found_and_ties_keep_the_light_frame() -> None:
    t = np.radians(np.array([0.0, 20.0, -35.0]))[:, None]
    u, v = np.array([0, 4, 4, 0, 2.0]), np.array([0, 0, 1, 1, 0.5])  # and an inner point
    x, y = np.cos(t) * u - np.sin(t) * v, np.sin(t) * u + np.cos(t) * v
    ok = np.ones((3, 5), bool)
    x[:, 4], ok[:, 4] = 1e6, False  # a masked point far away changes nothing
    r = min_area_rectangle(np, x, y, ok)
    np.testing.assert_allclose((r.hi_u - r.lo_u) * (r.hi_v - r.lo_v), 4.0, rtol=1e-12)
    np.testing.assert_allclose(r.s, np.sin(t[:, 0]), atol=1e-12)
    assert r.s[0] == 0.0 and r.c[0] == 1.0


def _loop_rectangle(x: np.ndarray, y: np.ndarray) -> Any:
    """The loop form (Python floats) of the least-area rectangle of the points."""
    from shadowmath._math._specialize import scalar_formulas

    pts = [float(v) for p in zip(x, y, 0.0 * x, strict=True) for v in p]
    return scalar_formulas().rectangle_loop(pts, len(x))


@pytest.mark.parametrize("seed", range(40))
def test_the_loop_form_finds_the_least_area_rectangle_of_the_array_form(seed: int) -> None:
    """On the hull's edges only (the loop form) or over every pair of points (the array
    form), the same least area, the oracle's; the rectangle holds every point and touches
    each side; collinear and repeated points (a flat body) included."""
    rng = np.random.default_rng(seed)
    m = int(rng.integers(1, 30))
    x, y = rng.normal(size=m) * rng.uniform(0.1, 50), rng.normal(size=m)
    if seed % 4 == 1:  # on a line
        y = 0.3 * x + 2.0
    if seed % 4 == 2:  # repeated points
        x, y = np.concatenate([x, x[:3]]), np.concatenate([y, y[:3]])
    r = _loop_rectangle(x, y)
    a = min_area_rectangle(np, x, y, np.ones_like(x, bool))
    area = (r.hi_u - r.lo_u) * (r.hi_v - r.lo_v)
    scale = float(np.max(np.abs(np.concatenate([x, y])))) ** 2
    assert area == pytest.approx(float((a.hi_u - a.lo_u) * (a.hi_v - a.lo_v)), abs=1e-12 * scale)
    if np.linalg.matrix_rank(np.column_stack([x - x[0], y - y[0]])) == 2:
        assert area == pytest.approx(hull_min_area(np.column_stack([x, y])), rel=1e-9)
    assert r.c > 0 and abs(r.s) <= r.c and r.c * r.c + r.s * r.s == pytest.approx(1.0)
    u, v = r.c * x + r.s * y, r.c * y - r.s * x
    assert (u.min(), u.max(), v.min(), v.max()) == (r.lo_u, r.hi_u, r.lo_v, r.hi_v)


def test_the_loop_form_keeps_the_light_frame_on_a_tie() -> None:
    u, v = np.array([0, 4, 4, 0, 2.0]), np.array([0, 0, 1, 1, 0.5])  # axis-aligned: a tie
    r = _loop_rectangle(u, v)
    assert (r.c, r.s, r.lo_u, r.hi_u, r.lo_v, r.hi_v) == (1.0, 0.0, 0.0, 4.0, 0.0, 1.0)
    t = np.radians(-35.0)
    r = _loop_rectangle(np.cos(t) * u - np.sin(t) * v, np.sin(t) * u + np.cos(t) * v)
    assert (r.hi_u - r.lo_u) * (r.hi_v - r.lo_v) == pytest.approx(4.0, rel=1e-12)
    assert r.s == pytest.approx(np.sin(t), abs=1e-12)


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"orientation": "turned"}, "orientation: expected 'light' or 'fitted'"),
        ({"orientation": "fitted", "stable": True}, "orientation: 'fitted' cannot be combined"),
        ({"orientation": "fitted", "warp": "lispsm"}, "orientation: 'fitted' cannot be combined"),
    ],
)
def test_refusals_name_the_argument(options: dict[str, Any], message: str) -> None:
    sun, view, proj, box = scene(0)
    with pytest.raises(ValueError, match=message):
        sm.fit_cascades(sun, view, proj, box, 256, **options)


def test_a_batch_and_jax_agree_with_one_numpy_camera_and_gradients_match() -> None:
    jax = pytest.importorskip("jax")
    jnp = jax.numpy
    scenes = [scene(s) for s in (3, 4)]
    batch = [np.stack([s[k] for s in scenes]) for k in range(4)]
    both = sm.fit_cascades(*batch, 256, orientation="fitted")
    for k in range(2):
        one = sm.fit_cascades(*scenes[k], 256, orientation="fitted")
        np.testing.assert_allclose(both.world_to_clip[k], one.world_to_clip, rtol=1e-12)
    sun, view, proj, box = scenes[0]
    one = sm.fit_cascades(*scenes[0], 256, orientation="fitted")

    def clip(d: Any) -> Any:
        return sm.fit_cascades(d, view, proj, box, 256, orientation="fitted").world_to_clip

    got = jax.jit(clip)(jnp.asarray(sun))
    np.testing.assert_allclose(np.asarray(got), one.world_to_clip, rtol=1e-10)

    def area(d: Any) -> Any:
        c = sm.fit_cascades(d, view, proj, box, 256, orientation="fitted")
        return jnp.sum(c.frustum.half_width * c.frustum.half_height)

    value_and_grad = jax.jit(jax.value_and_grad(area))
    g = value_and_grad(jnp.asarray(sun))[1]
    h = 1e-6
    for k in range(3):
        e = np.eye(3)[k] * h
        fd = value_and_grad(jnp.asarray(sun + e))[0] - value_and_grad(jnp.asarray(sun - e))[0]
        assert float(g[k]) == pytest.approx(float(fd) / (2 * h), rel=1e-5, abs=1e-8)
