"""The cascades' depth range: the visible range of the scene, a measured one, the ladder.

The oracle of the visible range is SciPy's half-space intersection (Qhull, ``body`` of
``test_cascades``): the vertices of the camera frustum intersected with the scene's box,
from the definitions alone; view depth is affine, so its extremes are at those vertices.
"""

from __future__ import annotations

import itertools
from typing import Any

import numpy as np
import pytest

import shadowmath as sm

from .cameras import look_at, orthographic, perspective
from .test_cascades import body, ndc

STEP = 2.0**0.25  # one step of the depth ladder
BOX = np.array([[-150.0, -0.5, -150.0], [150.0, 15.0, 150.0]])
SUN = np.array([0.3, 0.8, -0.4])


def pose(height: float, pitch: float, yaw: float = 0.4, x: float = 10.0) -> np.ndarray:
    """A camera ``height`` above the ground looking ``pitch`` radians below the horizon."""
    eye = np.array([x, height, -20.0])
    d = np.array([np.cos(yaw) * np.cos(pitch), -np.sin(pitch), np.sin(yaw) * np.cos(pitch)])
    return look_at(eye, eye + d)


def camera_range(proj: np.ndarray) -> tuple[float, float]:
    """OpenGL's near and far planes of a projection (perspective or orthographic)."""
    if proj[3, 3] == 1:
        a, b = proj[2, 2], proj[2, 3]
        return (b + 1) / a, (b - 1) / a
    return proj[2, 3] / (proj[2, 2] - 1), proj[2, 3] / (proj[2, 2] + 1)


def visible(view: np.ndarray, proj: np.ndarray, box: np.ndarray) -> tuple[float, float]:
    """The nearest and farthest view depth of the frustum intersected with the box."""
    near, far = camera_range(proj)
    v = body(view, proj, box, near, far)
    depth = -(v @ view[2, :3] + view[2, 3])
    return float(depth.min()), float(depth.max())


POSES = [(1.7, 0.05), (1.7, 0.6), (10.0, 0.3), (30.0, 0.5), (30.0, 1.2), (100.0, 0.7),
         (100.0, 1.5), (5.0, -0.1)]  # fmt: skip


@pytest.mark.parametrize(("height", "pitch"), POSES)
def test_the_visible_range_is_the_extreme_depth_of_frustum_and_scene(
    height: float, pitch: float
) -> None:
    view, proj = pose(height, pitch), perspective(1.0, 1.6, 0.1, 400.0)
    lo, hi = visible(view, proj, BOX)
    c = sm.fit_cascades(SUN, view, proj, BOX, 512, depth_range="visible")
    assert c.splits[0] == pytest.approx(lo, rel=1e-9)
    assert c.splits[-1] == pytest.approx(hi, rel=1e-9)
    assert np.all(np.diff(c.splits) > 0)
    # Every visible point of the scene is in [lo, hi]: random points along the camera's rays.
    rng = np.random.default_rng(int(height * 10 + pitch * 100))
    ndc = np.c_[rng.uniform(-1, 1, (20000, 2)), np.zeros(20000), np.ones(20000)]
    ray = (np.linalg.inv(proj) @ ndc.T).T
    ray = ray[:, :3] / ray[:, 3:]
    depth = rng.uniform(0.1, 400.0, 20000)
    w = (np.linalg.inv(view) @ np.c_[ray * (depth / -ray[:, 2])[:, None], np.ones(20000)].T).T
    inside = np.all((w[:, :3] >= BOX[0]) & (w[:, :3] <= BOX[1]), axis=1)
    assert inside.sum() > 100
    assert np.all((depth[inside] >= c.splits[0]) & (depth[inside] <= c.splits[-1]))


def test_high_cameras_start_their_first_cascade_at_the_scene() -> None:
    """The camera's range puts the first cascades before the nearest visible point; the
    visible range starts there."""
    view, proj = pose(100.0, 0.7), perspective(1.0, 1.6, 0.1, 400.0)
    lo, _ = visible(view, proj, BOX)
    assert sm.fit_cascades(SUN, view, proj, BOX, 512).splits[2] < lo  # two cascades wasted
    c = sm.fit_cascades(SUN, view, proj, BOX, 512, depth_range="visible")
    assert c.splits[0] == pytest.approx(lo, rel=1e-9) and lo > 50


def test_a_scene_out_of_view_keeps_the_cameras_range() -> None:
    view, proj = look_at([0, 5, 0], [0, 50, 1]), perspective(0.5, 1.0, 0.1, 100.0)
    box = np.array([[-10.0, -1.0, -10.0], [10.0, 0.0, 10.0]])  # below, behind the view
    c = sm.fit_cascades(SUN, view, proj, box, 256, depth_range="visible")
    np.testing.assert_allclose(c.splits[[0, -1]], [0.1, 100.0], rtol=1e-12)


def test_the_visible_range_of_an_orthographic_camera_and_a_shadow_distance() -> None:
    view = pose(30.0, 0.8)
    proj = orthographic(20.0, 12.0, 1.0, 300.0)
    lo, hi = visible(view, proj, BOX)
    c = sm.fit_cascades(SUN, view, proj, BOX, 256, depth_range="visible", scheme="uniform")
    np.testing.assert_allclose(c.splits[[0, -1]], [lo, hi], rtol=1e-9)
    # max_distance cuts the range the visible part is taken from.
    proj = perspective(1.0, 1.6, 0.1, 400.0)
    view = pose(1.7, 0.05)
    lo, hi = visible(view, perspective(1.0, 1.6, 0.1, 60.0), BOX)
    c = sm.fit_cascades(SUN, view, proj, BOX, 256, depth_range="visible", max_distance=60.0)
    np.testing.assert_allclose(c.splits[[0, -1]], [lo, hi], rtol=1e-9)


def test_a_measured_range_is_clipped_to_the_cameras() -> None:
    view, proj = pose(10.0, 0.3), perspective(1.0, 1.6, 0.5, 200.0)
    c = sm.fit_cascades(SUN, view, proj, BOX, 256, depth_range=np.array([3.0, 90.0]))
    np.testing.assert_array_equal(c.splits[[0, -1]], [3.0, 90.0])
    c = sm.fit_cascades(SUN, view, proj, BOX, 256, depth_range=np.array([0.01, 900.0]))
    np.testing.assert_allclose(c.splits[[0, -1]], [0.5, 200.0], rtol=1e-12)


@pytest.mark.parametrize(("height", "pitch"), [(1.7, 0.05), (30.0, 0.5), (100.0, 1.2)])
def test_the_auto_scheme_cuts_a_fitted_range_into_equal_depth_ratios(
    height: float, pitch: float
) -> None:
    """``scheme="auto"`` (the default) over a visible or measured range is the log scheme:
    a slice ``[a, b]`` serves pixels whose texel-to-footprint ratio is at most ``b / a``,
    and the product of the ratios is ``f / n``, so the worst is least when every ratio is
    ``(f / n)^{1/N}`` (``docs/cascades.md``); over the camera's range, the practical blend
    with ``lam = 0.75``; a given ``lam`` is the practical scheme's."""
    view, proj = pose(height, pitch), perspective(1.0, 1.6, 0.1, 400.0)
    lo, hi = visible(view, proj, BOX)
    for rng in ("visible", np.array([0.8 * lo + 0.2 * hi, 0.2 * lo + 0.8 * hi])):
        c = sm.fit_cascades(SUN, view, proj, BOX, 256, depth_range=rng)
        n, f = c.splits[0], c.splits[-1]
        np.testing.assert_allclose(c.splits[1:] / c.splits[:-1], (f / n) ** 0.25, rtol=1e-12)
        blend = sm.fit_cascades(SUN, view, proj, BOX, 256, depth_range=rng, lam=0.75)
        assert np.max(blend.splits[1:] / blend.splits[:-1]) > (f / n) ** 0.25 * (1 + 1e-9)
    i = np.arange(5) / 4
    for kwargs in ({}, {"depth_range": "visible", "lam": 0.75}):
        c = sm.fit_cascades(SUN, view, proj, BOX, 256, **kwargs)
        n, f = c.splits[0], c.splits[-1]
        want = 0.75 * n * (f / n) ** i + 0.25 * (n + (f - n) * i)
        np.testing.assert_allclose(c.splits, want, rtol=1e-12)
    assert sm.fit_cascades(SUN, view, proj, BOX, 256).splits[0] == pytest.approx(0.1)


def is_ladder(x: np.ndarray) -> np.ndarray:
    k = 4 * np.log2(x)
    return np.abs(k - np.round(k)) < 1e-9


def path() -> Any:
    """A camera that climbs to 100, dives back to 3, turns, then bobs by 2 cm."""
    heights = np.r_[np.linspace(1.7, 100, 30), np.linspace(100, 3, 30), np.full(20, 3.0)]
    pitches = np.r_[np.linspace(0.1, 1.2, 30), np.linspace(1.2, 0.2, 30), np.full(20, 0.2)]
    bob = np.r_[np.zeros(61), 0.02 * np.sin(np.arange(1, 20))]
    for k, (h, p) in enumerate(zip(heights + bob, pitches, strict=True)):
        yield k, pose(h, p, yaw=0.4 + 0.02 * min(k, 60))


def test_the_ladder_with_hysteresis_along_a_path() -> None:
    """The range in use holds the visible range, its ends are ladder values (or the
    camera's planes), an end grows at once and shrinks only once the visible end's ladder
    value is more than a step inside it."""
    proj = perspective(1.0, 1.6, 0.1, 400.0)
    state, used, changes = sm.CascadeState.initial(), None, 0
    for k, view in path():
        lo, hi = visible(view, proj, BOX)
        c = sm.fit_cascades(SUN, view, proj, BOX, 512, depth_range="visible", state=state)
        near, far = c.state.near, c.state.far
        assert near <= lo * (1 + 1e-12) and far >= hi * (1 - 1e-12)  # holds the visible range
        assert (is_ladder(near) or near == 0.1) and (is_ladder(far) or far == 400.0)
        assert far < hi * STEP**2 and near > lo / STEP**2  # within the margin and one step
        if used is not None:
            # Shrunk: the visible end's ladder value lies more than one step (the margin)
            # inside the end in use, so the end is two steps beyond it.
            if far < used[1]:
                assert hi <= used[1] / STEP**2 * (1 + 1e-12)
            if near > used[0]:
                assert lo >= used[0] * STEP**2 * (1 - 1e-12)
            if far > used[1]:
                assert hi > used[1]  # grew only to hold the range
            if near < used[0]:
                assert lo < used[0]
            changes += (near, far) != used
        used, state = (near, far), c.state
        if k == 60:
            settled = changes
    assert changes == settled  # the bobbing camera kept its range
    assert changes < 30


def test_stable_squares_along_a_path() -> None:
    """Each stable square holds the visible part of its slice (Qhull); its half-width is
    the lesser of the slice's sphere's and a ladder value that grows at once and shrinks
    only once the part's ladder value is more than a step inside; it keeps its size bit
    for bit while both hold, and moves by whole texels."""
    proj = perspective(1.0, 1.6, 0.1, 400.0)
    state, prev, changes = sm.CascadeState.initial(), None, 0
    for k, view in path():
        c = sm.fit_cascades(SUN, view, proj, BOX, 512, depth_range="visible", stable=True,
                            state=state)  # fmt: skip
        sphere = sm.fit_cascades(SUN, view, proj, BOX, 512, splits=c.splits, stable=True)
        hw = c.state.half_width
        for i in range(4):
            v = body(view, proj, BOX, c.splits[i], c.band_end[i])
            q = ndc(c.world_to_clip[i], v)
            assert np.all(np.abs(q[:, :2]) <= c.frustum.margin_x[i] * (1 + 1e-12))
            assert np.all((q[:, 2] > -1) & (q[:, 2] < 1))
            xy = v @ c.world_to_light[i, :2, :3].T
            need = 0.5 * np.max(xy.max(axis=0) - xy.min(axis=0))
            assert hw[i] >= need * (1 - 1e-9)
            assert is_ladder(hw[i]) and hw[i] < need * STEP**2
            half = c.frustum.half_width[i] * (1 - 1 / (c.frustum.margin_x[i] * 512))
            assert half == pytest.approx(min(hw[i], sphere.state.half_width[i]), rel=1e-12)
            if prev is not None:
                if hw[i] < prev.state.half_width[i]:  # shrank past the margin
                    assert need <= prev.state.half_width[i] / STEP**2 * (1 + 1e-9)
                if hw[i] > prev.state.half_width[i]:  # grew: only to hold the part
                    assert need > prev.state.half_width[i]
        if prev is not None:
            same = (hw == prev.state.half_width) & np.all(c.splits == prev.splits)
            np.testing.assert_array_equal(c.frustum.half_width[same], prev.frustum.half_width[same])
            changes += int(np.sum(~same))
        steps = c.frustum.center_x / c.texel_size[:, 0]
        np.testing.assert_allclose(steps, np.round(steps), atol=1e-6)  # whole texels
        prev, state = c, c.state
        if k == 60:
            settled = changes
    assert changes == settled  # the bobbing camera kept its squares
    assert changes < 120


def test_without_hysteresis_the_range_follows_every_frame() -> None:
    """The counterpart: the exact range changes the stable sizes at every frame."""
    proj = perspective(1.0, 1.6, 0.1, 400.0)
    sizes = []
    for k in range(5):
        view = pose(3 + 0.02 * np.sin(k), 0.2)
        c = sm.fit_cascades(SUN, view, proj, BOX, 512, depth_range="visible", stable=True)
        sizes.append(c.frustum.half_width)
    assert all(not np.array_equal(a, b) for a, b in itertools.pairwise(sizes))


def test_the_ladder_values() -> None:
    """Without a previous range the ends are the nearest ladder values outside the target."""
    from shadowmath._math._specialize import formulas, scalar_formulas

    x = np.geomspace(1e-3, 1e4, 997)
    nan = float("nan")
    for F in (formulas(np), scalar_formulas()):
        up = np.array([F.ladder_up(float(v)) for v in x])
        ends = np.array([F.depth_hysteresis(float(v), float(v), nan, nan) for v in x])
        for lo_hi in (up, ends[:, 0], ends[:, 1]):
            assert np.all(is_ladder(lo_hi))
        assert np.all((up >= x) & (up < x * STEP * (1 + 1e-12)))
        np.testing.assert_array_equal(ends[:, 1], up)
        assert np.all((ends[:, 0] <= x) & (ends[:, 0] > x / STEP))
        for v in (2.0, 2.0**0.25, 0.5):  # ladder values are their own ends (to a rounding
            lo, hi = F.depth_hysteresis(v, v, nan, nan)  # of 1 / v that may cost a step)
            assert hi == pytest.approx(v, rel=1e-14)
            assert lo == pytest.approx(v, rel=1e-14) or lo == pytest.approx(v / STEP, rel=1e-14)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"depth_range": "scene"}, "depth_range: expected 'camera', 'visible'"),
        ({"scheme": "linear"}, "scheme: expected 'auto', 'uniform', 'log' or 'practical'"),
        ({"depth_range": "visible", "splits": [0.5, 2.0, 9.0]}, "depth_range: custom splits"),
        ({"state": sm.CascadeState(1.0, 9.0, 2.0)}, "state: needs depth_range"),
        ({"depth_range": "visible", "state": (1.0, 9.0)}, "state: expected"),
        ({"depth_range": np.array([9.0, 1.0])}, "depth_range: the measured near exceeds"),
        ({"depth_range": np.array([np.nan, 1.0])}, "depth_range"),
        ({"depth_range": np.array([1.0, 2.0, 3.0])}, "depth_range"),
        ({"depth_range": "visible", "state": sm.CascadeState(1.0, 9.0, -2.0)},
         "state: half_width must be positive"),
        ({"depth_range": "visible", "state": sm.CascadeState(1.0, 9.0, np.ones(3))},
         r"state: half_width must be \(\*batch, n\)"),
        ({"depth_range": "visible", "state": sm.CascadeState(9.0, 1.0, 2.0)},
         "state: its near exceeds"),
    ],
)  # fmt: skip
def test_range_errors_name_the_argument(kwargs: dict[str, Any], message: str) -> None:
    view, proj = pose(10.0, 0.3), perspective(1.0, 1.6, 0.5, 200.0)
    with pytest.raises(ValueError, match=message):
        sm.fit_cascades(SUN, view, proj, BOX, 256, **kwargs)


def test_jax_gradients_of_the_visible_range() -> None:
    jax = pytest.importorskip("jax")
    jax.config.update("jax_enable_x64", True)
    jnp = jax.numpy
    proj = jnp.asarray(perspective(1.0, 1.6, 0.1, 400.0))

    def ends(height: Any) -> Any:
        eye = jnp.stack([10.0, height, -20.0])
        v = jnp.asarray(pose(30.0, 0.5))
        view = v.at[:3, 3].set(-v[:3, :3] @ eye)
        c = sm.fit_cascades(jnp.asarray(SUN), view, proj, jnp.asarray(BOX), 256,
                            depth_range="visible")  # fmt: skip
        return c.splits[0] + 2.0 * c.splits[-1]

    g = jax.grad(ends)(30.0)
    h = 1e-4
    numeric = (ends(30.0 + h) - ends(30.0 - h)) / (2 * h)
    assert np.isfinite(g) and g == pytest.approx(float(numeric), rel=1e-6)
    assert abs(g) > 0.1
    bad = jax.jit(
        lambda m: (
            sm.fit_cascades(
                jnp.asarray(SUN),
                jnp.asarray(pose(3, 0.2)),
                proj,
                jnp.asarray(BOX),
                256,
                depth_range=m,
            ).splits
        )
    )
    assert np.all(np.isnan(bad(jnp.array([9.0, 1.0]))))


def test_jax_stable_squares_with_a_state_equal_numpy() -> None:
    jax = pytest.importorskip("jax")
    jax.config.update("jax_enable_x64", True)
    jnp = jax.numpy
    proj, views = perspective(1.0, 1.6, 0.1, 400.0), [pose(30.0, 0.5), pose(31.0, 0.55)]
    state = sm.CascadeState.initial()
    fit = jax.jit(lambda v, s: sm.fit_cascades(jnp.asarray(SUN), v, jnp.asarray(proj),
                                               jnp.asarray(BOX), 256, depth_range="visible",
                                               stable=True, state=s))  # fmt: skip
    jstate = sm.CascadeState(jnp.nan, jnp.nan, jnp.full(4, jnp.nan))
    for view in views:
        want = sm.fit_cascades(SUN, view, proj, BOX, 256, depth_range="visible", stable=True,
                               state=state)  # fmt: skip
        got = fit(jnp.asarray(view), jstate)
        np.testing.assert_allclose(got.world_to_clip, want.world_to_clip, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(got.state.half_width, want.state.half_width, rtol=1e-12)
        state, jstate = want.state, got.state
    bad = fit(jnp.asarray(views[0]), jstate._replace(half_width=-jstate.half_width))
    assert np.all(np.isnan(bad.world_to_clip))  # an invalid state: NaN, as every invalid input
