"""Cascaded shadow maps: splits, containment against an independent intersection, stability.

The oracle of the fit is SciPy's half-space intersection (Qhull): the vertices of each
camera slice intersected with the scene's box, computed from the slice's definition
(the camera's clip-space side planes and two view depths) without shadowmath's code.
"""

from __future__ import annotations

import contextlib
from typing import Any

import numpy as np
import pytest
from scipy.optimize import linprog
from scipy.spatial import HalfspaceIntersection

import shadowmath as sm

from .cameras import look_at, orthographic, perspective, scene

RNG = np.random.default_rng(17)


def body(view: np.ndarray, proj: np.ndarray, box: np.ndarray, a: float, b: float) -> np.ndarray:
    """Vertices of {camera slice a <= depth <= b} intersected with the box (Qhull)."""
    pv = proj @ view
    rows = []  # halfspaces as A x + c <= 0
    for r in (pv[3] - pv[0], pv[3] + pv[0], pv[3] - pv[1], pv[3] + pv[1]):
        rows.append(-r)  # w -+ x >= 0
    depth = -view[2]  # a right-handed camera's view depth is -z
    rows.append(np.r_[-depth[:3], a - depth[3]])
    rows.append(np.r_[depth[:3], depth[3] - b])
    for i in range(3):
        e = np.eye(3)[i]
        rows.append(np.r_[-e, box[0, i]])
        rows.append(np.r_[e, -box[1, i]])
    hs = np.array(rows)
    norms = np.linalg.norm(hs[:, :3], axis=1)
    res = linprog(
        np.r_[0, 0, 0, -1],
        A_ub=np.c_[hs[:, :3], norms],
        b_ub=-hs[:, 3],
        bounds=[(None, None)] * 3 + [(0, None)],
    )
    assert res.status == 0 and res.x[3] > 1e-6, "the slice misses the box"
    return HalfspaceIntersection(hs, res.x[:3]).intersections


def ndc(m: np.ndarray, p: np.ndarray) -> np.ndarray:
    h = np.c_[p, np.ones(len(p))] @ m.T
    return h[:, :3] / h[:, 3:]


# --- splits ---------------------------------------------------------------------------------


def test_uniform_splits_are_equally_spaced() -> None:
    s = sm.cascade_splits(0.5, 80.5, 4, scheme="uniform")
    np.testing.assert_allclose(np.diff(s), 20.0, rtol=1e-14)
    assert s[0] == 0.5 and s[-1] == 80.5


def test_log_splits_keep_a_constant_ratio() -> None:
    s = sm.cascade_splits(0.1, 1000.0, 4, scheme="log")
    np.testing.assert_allclose(s[1:] / s[:-1], 10.0, rtol=1e-12)


@pytest.mark.parametrize("lam", [0.0, 0.25, 0.5, 1.0])
def test_practical_splits_blend_the_two(lam: float) -> None:
    n, f = 0.3, 200.0
    s = sm.cascade_splits(n, f, 5, lam=lam)
    i = np.arange(6) / 5
    np.testing.assert_allclose(
        s, lam * n * (f / n) ** i + (1 - lam) * (n + (f - n) * i), rtol=1e-13
    )
    assert s[0] == n and s[-1] == f and np.all(np.diff(s) > 0)


def test_splits_broadcast_over_a_batch() -> None:
    s = sm.cascade_splits(np.array([0.1, 1.0]), np.array([[50.0], [60.0]]), 3)
    assert s.shape == (2, 2, 4)
    np.testing.assert_allclose(s[1, 0], sm.cascade_splits(0.1, 60.0, 3), rtol=1e-15)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"count": 0}, "count: expected an integer >= 1"),
        ({"count": True}, "count: expected an integer >= 1"),
        ({"scheme": "linear"}, "scheme: expected 'uniform', 'log' or 'practical'"),
        ({"lam": 1.5}, r"lam: the practical scheme's blend must lie in \[0, 1\]"),
        ({"near": 0.0}, "near: logarithmic splits need near > 0"),
        ({"far": 0.5}, "far: the split range must end beyond near"),
        ({"near": np.nan}, "near: contains non-finite values"),
    ],
)
def test_split_errors_name_the_argument(kwargs: dict[str, Any], message: str) -> None:
    args = {"near": 1.0, "far": 10.0, "count": 3} | kwargs
    with pytest.raises(ValueError, match=message):
        sm.cascade_splits(args.pop("near"), args.pop("far"), args.pop("count"), **args)


def test_uniform_splits_may_start_at_the_camera() -> None:
    np.testing.assert_allclose(sm.cascade_splits(0.0, 9.0, 3, scheme="uniform"), [0, 3, 6, 9])


# --- the fit against the exact intersection -------------------------------------------------


@pytest.mark.parametrize("seed", range(6))
def test_each_cascade_holds_its_slice_of_the_scene_and_touches_its_margins(seed: int) -> None:
    sun, view, proj, box = scene(seed)
    c = sm.fit_cascades(sun, view, proj, box, 512, pcf_radius=2)
    m = c.frustum.margin_x[0]
    assert m == pytest.approx(1 - 2 * 2 / 512)
    corners = np.array([[box[i & 1, 0], box[i >> 1 & 1, 1], box[i >> 2, 2]] for i in range(8)])
    for i in range(4):
        v = body(view, proj, box, c.splits[i], c.band_end[i])
        p = ndc(c.world_to_clip[i], v)
        # Inside the margins, and the bounds are tight: a vertex on each side.
        assert np.all(np.abs(p[:, :2]) <= m * (1 + 1e-9))
        np.testing.assert_allclose(p[:, :2].max(0), [m, m], rtol=1e-9)
        np.testing.assert_allclose(p[:, :2].min(0), [-m, -m], rtol=1e-9)
        assert np.all((p[:, 2] > -1) & (p[:, 2] < 1))
        # Every caster of the scene lies beyond the near plane (seen or not).
        assert np.all(ndc(c.world_to_clip[i], corners)[:, 2] > -1)


def test_a_scene_smaller_than_the_slice_sets_the_box() -> None:
    sun, view, proj, _ = scene(3)
    eye = np.linalg.inv(view)[:3, 3]
    ahead = eye - 30 * np.linalg.inv(view)[:3, 2]
    box = np.array([ahead - 1.0, ahead + 1.0])
    near = proj[2, 3] / (proj[2, 2] - 1)
    c = sm.fit_cascades(sun, view, proj, box, 256, splits=[near, 120.0])
    # The whole box is in view: the box's silhouette, not the slice's, fills the map.
    corners = np.array([[box[i & 1, 0], box[i >> 1 & 1, 1], box[i >> 2, 2]] for i in range(8)])
    p = ndc(c.world_to_clip[0], corners)
    np.testing.assert_allclose(np.abs(p[:, :2]).max(0), c.frustum.margin_x[0], rtol=1e-9)


def test_orthographic_camera() -> None:
    sun, _, _, _ = scene(1)
    box = np.array([[-150.0, -0.5, -150.0], [150.0, 25.0, 150.0]])
    view = look_at([0, 30, 0.1], [0, 0, 0])
    proj = orthographic(20, 15, 1, 30)
    c = sm.fit_cascades(sun, view, proj, box, 256, count=3, scheme="uniform")
    np.testing.assert_allclose(c.splits, [1, 1 + 29 / 3, 1 + 58 / 3, 30], rtol=1e-14)
    for i in range(3):
        p = ndc(c.world_to_clip[i], body(view, proj, box, c.splits[i], c.band_end[i]))
        assert np.all(np.abs(p[:, :2]) <= c.frustum.margin_x[i] * (1 + 1e-9))
        np.testing.assert_allclose(np.abs(p[:, :2]).max(), c.frustum.margin_x[i], rtol=1e-9)


def test_an_infinite_far_plane_with_a_shadow_distance() -> None:
    sun, view, proj, box = scene(2)
    near = proj[2, 3] / (proj[2, 2] - 1)
    infinite = proj.copy()
    infinite[2, 2], infinite[2, 3] = -1.0, -2 * near
    a = sm.fit_cascades(sun, view, proj, box, 256, max_distance=80.0)
    b = sm.fit_cascades(sun, view, infinite, box, 256, max_distance=80.0)
    np.testing.assert_allclose(b.splits, a.splits, rtol=1e-12)
    np.testing.assert_allclose(b.world_to_clip, a.world_to_clip, rtol=1e-9, atol=1e-12)
    with pytest.raises(ValueError, match="max_distance: the projection's far plane is at infinity"):
        sm.fit_cascades(sun, view, infinite, box, 256)


def test_overlap_bands() -> None:
    sun, view, proj, box = scene(0)
    c = sm.fit_cascades(sun, view, proj, box, 256, overlap=0.25)
    s = c.splits
    np.testing.assert_allclose(c.band_end[:-1], s[1:-1] + 0.25 * np.diff(s)[:-1], rtol=1e-14)
    assert c.band_end[-1] == s[-1]


# --- conventions ----------------------------------------------------------------------------


@pytest.mark.parametrize("api", sm.GRAPHICS_APIS)
@pytest.mark.parametrize("reversed_z", [False, True])
def test_each_api_is_opengl_times_its_conventions(api: str, reversed_z: bool) -> None:
    sun, view, proj, box = scene(4)
    gl = sm.fit_cascades(sun, view, proj, box, 256)
    c = sm.fit_cascades(sun, view, proj, box, 256, api=api, reversed_z=reversed_z,
                        camera_api="opengl")  # fmt: skip
    conv = sm.api_convention(api=api, reversed_z=reversed_z)
    np.testing.assert_allclose(c.world_to_clip, conv.gl_clip_to_clip @ gl.world_to_clip,
                               rtol=1e-12, atol=1e-12)  # fmt: skip
    np.testing.assert_allclose(c.world_to_texture, conv.gl_clip_to_texture @ gl.world_to_clip,
                               rtol=1e-12, atol=1e-12)  # fmt: skip


@pytest.mark.parametrize("api", sm.GRAPHICS_APIS)
@pytest.mark.parametrize("reversed_z", [False, True])
def test_a_camera_in_any_api_gives_the_same_cascades(api: str, reversed_z: bool) -> None:
    sun, view, proj, box = scene(5)
    gl = sm.fit_cascades(sun, view, proj, box, 256)
    C = sm.api_convention(api=api, reversed_z=reversed_z).gl_clip_to_clip
    c = sm.fit_cascades(sun, view, C @ proj, box, 256, camera_api=api,
                        camera_reversed_z=reversed_z, api="opengl")  # fmt: skip
    np.testing.assert_allclose(c.splits, gl.splits, rtol=1e-12)
    np.testing.assert_allclose(c.world_to_clip, gl.world_to_clip, rtol=1e-9, atol=1e-12)


def test_atlas_tiles() -> None:
    sun, view, proj, box = scene(0)
    layers = sm.fit_cascades(sun, view, proj, box, 256, count=3)
    atlas = sm.fit_cascades(sun, view, proj, box, 256, count=3, layout="atlas")
    np.testing.assert_array_equal(atlas.viewports, [[0, 0, 256, 256], [256, 0, 256, 256],
                                                    [0, 256, 256, 256]])  # fmt: skip
    for i, (col, row) in enumerate([(0, 0), (1, 0), (0, 1)]):
        v = body(view, proj, box, atlas.splits[i], atlas.band_end[i])
        st = ndc(atlas.world_to_texture[i], v)
        st_layer = ndc(layers.world_to_texture[i], v)
        np.testing.assert_allclose(st[:, 0], (st_layer[:, 0] + col) / 2, rtol=1e-12)
        np.testing.assert_allclose(st[:, 1], (st_layer[:, 1] + row) / 2, rtol=1e-12)
        # Inside its own tile, a border of texels from its edges.
        border = 1 / 512
        assert np.all(
            (st[:, 0] >= col / 2 + border * 0.999) & (st[:, 0] <= (col + 1) / 2 - border * 0.999)
        )
        assert np.all(
            (st[:, 1] >= row / 2 + border * 0.999) & (st[:, 1] <= (row + 1) / 2 - border * 0.999)
        )


# --- stable cascades ------------------------------------------------------------------------


def test_stable_cascades_keep_their_size_and_move_by_whole_texels() -> None:
    sun, _, proj, box = scene(6)
    sizes, first = None, None
    for k in range(12):
        eye = np.array([0.37 * k, 2 + 0.05 * k, -0.61 * k])
        yaw = 0.13 * k
        view = look_at(eye, eye + [np.sin(yaw), -0.1, np.cos(yaw)])
        c = sm.fit_cascades(sun, view, proj, box, 512, stable=True)
        if sizes is None:
            sizes, first = (c.frustum.half_width, c.frustum.half_height), c
        np.testing.assert_array_equal(c.frustum.half_width, sizes[0])  # exactly
        np.testing.assert_array_equal(c.frustum.half_height, sizes[1])
        # The frame's rotation is the light's alone.
        np.testing.assert_array_equal(c.world_to_light[:, :3, :3], first.world_to_light[:, :3, :3])
        texel = c.texel_size
        for axis, offset in ((0, c.frustum.center_x), (1, c.frustum.center_y)):
            steps = offset / texel[:, axis]
            np.testing.assert_allclose(steps, np.round(steps), atol=1e-6)


def test_stable_cascades_still_hold_their_slices() -> None:
    sun, view, proj, box = scene(7)
    c = sm.fit_cascades(sun, view, proj, box, 512, stable=True)
    for i in range(4):
        p = ndc(c.world_to_clip[i], body(view, proj, box, c.splits[i], c.band_end[i]))
        assert np.all(np.abs(p[:, :2]) <= c.frustum.margin_x[i])
        assert np.all((p[:, 2] > -1) & (p[:, 2] < 1))


def test_stable_size_is_the_slice_sphere() -> None:
    """A symmetric camera: the minimal sphere of the slice, by brute force over axis centres."""
    sun, view, proj, box = scene(8)
    c = sm.fit_cascades(sun, view, proj, box, 512, stable=True, count=2)
    inv = np.linalg.inv(proj)
    for i in range(2):
        a, b = c.splits[i], c.band_end[i]
        pts = []
        for z_ndc, d in ((-1, a), (1, b)):
            for x in (-1, 1):
                for y in (-1, 1):
                    h = inv @ [x, y, z_ndc, 1]
                    p = h[:3] / h[3]
                    pts.append(p * d / -p[2])
        pts = np.array(pts)
        zs = np.linspace(-b, -a, 200001)
        r = np.min([np.max(np.linalg.norm(pts - [0, 0, z], axis=1)) for z in zs])
        m, w = c.frustum.margin_x[i], 512
        half = r / (1 - 1 / (m * w))
        assert c.frustum.half_width[i] == pytest.approx(half, rel=1e-6)


# --- batches and JAX ------------------------------------------------------------------------


def test_a_batch_of_cameras_equals_one_by_one() -> None:
    scenes = [scene(s) for s in range(3)]
    sun, view, proj, box = (np.stack(v) for v in zip(*scenes, strict=True))
    c = sm.fit_cascades(sun, view, proj, box, 256, stable=True)
    for k in range(3):
        one = sm.fit_cascades(*scenes[k], 256, stable=True)
        np.testing.assert_allclose(c.world_to_clip[k], one.world_to_clip, rtol=1e-12)


def test_jax_values_jit_and_gradients() -> None:
    jax = pytest.importorskip("jax")
    jnp = jax.numpy
    sun, view, proj, box = scene(9)
    want = sm.fit_cascades(sun, view, proj, box, 256)
    got = sm.fit_cascades(jnp.asarray(sun), jnp.asarray(view), jnp.asarray(proj),
                          jnp.asarray(box), 256)  # fmt: skip
    np.testing.assert_allclose(np.asarray(got.world_to_clip), want.world_to_clip, rtol=1e-10)

    def area(d: Any, lam: Any) -> Any:
        c = sm.fit_cascades(d, view, proj, box, 256, lam=lam)
        return jnp.sum(c.frustum.half_width * c.frustum.half_height)

    g = jax.jit(jax.grad(area, argnums=(0, 1)))(jnp.asarray(sun), 0.5)
    h = 1e-6
    for k in range(3):
        e = np.eye(3)[k] * h
        fd = (area(jnp.asarray(sun + e), 0.5) - area(jnp.asarray(sun - e), 0.5)) / (2 * h)
        assert float(g[0][k]) == pytest.approx(float(fd), rel=1e-5, abs=1e-8)
    fd = (area(jnp.asarray(sun), 0.5 + h) - area(jnp.asarray(sun), 0.5 - h)) / (2 * h)
    assert float(g[1]) == pytest.approx(float(fd), rel=1e-5)


def test_jax_invalid_inputs_are_nan_under_jit() -> None:
    jax = pytest.importorskip("jax")
    sun, view, proj, box = scene(9)
    fit = jax.jit(lambda d: sm.fit_cascades(d, view, proj, box, 256).world_to_clip)
    assert np.all(np.isnan(np.asarray(fit(jax.numpy.zeros(3)))))
    assert np.all(np.isfinite(np.asarray(fit(jax.numpy.asarray(sun)))))


# --- errors ---------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"light": np.zeros(3)}, "light: zero direction"),
        ({"light": np.array([0.0, 1.0, 0.0, 1.0])}, "light: cascades need a directional light"),
        ({"light": np.ones(2)}, r"light: expected a direction \(\*batch, 3\)"),
        ({"view": np.diag([1.0, 1.0, 0.0, 1.0])}, "view: singular"),
        ({"view": np.ones((4, 4))}, "view: expected an affine world-to-view matrix"),
        ({"projection": np.diag([0.0, 1, 1, 1])}, "projection: singular"),
        ({"projection": perspective(1.0, 1.5, 0.1, 100).T}, "projection: its last row is"),
        ({"scene_bounds": np.array([[1.0, 0, 0], [0, 1, 1]])}, "scene_bounds: the max corner"),
        ({"scene_bounds": np.zeros((3, 3))}, r"scene_bounds: expected shape \(\*batch, 2, 3\)"),
        ({"splits": [3.0, 2.0, 5.0]}, "splits: the depths must increase"),
        ({"splits": [0.01, 2.0]}, r"splits: the depths must lie within the camera's \[near, far\]"),
        ({"max_distance": 500.0}, "max_distance: the shadow distance must lie beyond"),
        ({"overlap": 1.0}, r"overlap: the blend band must be a fraction in \[0, 1\)"),
        ({"up": np.array([0.3, 1.0, 0.5])}, "up: the up hint is zero or parallel"),
        ({"layout": "grid"}, "layout: expected 'layers' or 'atlas'"),
        ({"camera_api": "glide"}, "api: unknown graphics API 'glide'"),
        ({"count": 0}, "count: expected an integer >= 1"),
    ],
)
@pytest.mark.parametrize("path", ["compiled", "python", "array"])
def test_errors_name_the_argument(change: dict[str, Any], message: str, path: str) -> None:
    from shadowmath._backends import _kernels

    view = look_at([0, 2, 0], [0, 1, -10])
    args: dict[str, Any] = {
        "light": np.array([0.3, 1.0, 0.5]),
        "view": view,
        "projection": perspective(1.0, 1.5, 0.1, 100),
        "scene_bounds": np.array([[-50.0, 0, -50], [50, 5, 50]]),
        "map_size": 256,
    } | change
    positional = [args.pop(k) for k in ("light", "view", "projection", "scene_bounds", "map_size")]
    paths = {"compiled": contextlib.nullcontext, "python": _kernels.disabled,
             "array": _kernels.array_path}  # fmt: skip
    with paths[path](), pytest.raises(ValueError, match=message):
        sm.fit_cascades(*positional, **args)


# --- the compiled loop (fast extra) and the array path agree --------------------------------


@pytest.mark.parametrize(
    "options",
    [{}, {"stable": True}, {"layout": "atlas", "count": 3}, {"splits": [0.5, 3.0, 20.0, 90.0]},
     {"max_distance": 60.0, "scheme": "log"}, {"up": np.array([0.0, 0.0, 1.0]), "api": "vulkan"},
     {"overlap": 0.0, "pcf_radius": 3}, {"depth_range": "visible"},
     {"orientation": "fitted"}, {"orientation": "fitted", "layout": "atlas", "api": "webgpu",
                                 "depth_range": "visible"},
     {"warp": "lispsm"}, {"warp": "lispsm", "layout": "atlas", "depth_range": "visible"},
     {"depth_range": np.array([[2.0, 50.0], [1.0, 30.0], [0.7, 200.0]]), "stable": True},
     {"depth_range": "visible", "stable": True,
      "state": sm.CascadeState(np.array([2.0, np.nan, 0.6]), np.array([60.0, np.nan, 99.0]),
                               np.array([[3.0, 9.0, 20.0, 40.0]] * 2 + [[np.nan] * 4]))}],
)  # fmt: skip
def test_compiled_loop_equals_array_path(options: dict[str, Any]) -> None:
    pytest.importorskip("numba")
    from shadowmath._backends import _kernels

    scenes = [scene(s) for s in range(10, 13)]
    sun, view, proj, box = (np.stack(v) for v in zip(*scenes, strict=True))
    proj[:, 2, 2:] = perspective(1.0, 1.0, 0.5, 120)[2, 2:]  # near 0.5 for the custom splits
    fast = sm.fit_cascades(sun, view, proj, box, 256, **options)
    with _kernels.array_path():
        slow = sm.fit_cascades(sun, view, proj, box, 256, **options)
    with _kernels.disabled():  # three cameras: the same loop run by Python
        python = sm.fit_cascades(sun, view, proj, box, 256, **options)
    for a, b in [*zip(fast, slow, strict=True), *zip(python, slow, strict=True)]:
        for x, y in zip(a if isinstance(a, tuple) else [a], b if isinstance(b, tuple) else [b],
                        strict=True):  # fmt: skip
            np.testing.assert_allclose(np.asarray(x, float), np.asarray(y, float), rtol=1e-9,
                                       atol=1e-12)  # fmt: skip


@pytest.mark.parametrize("depth_range", ["visible", "camera"])
def test_a_batch_of_views_over_one_scene_is_each_views_fit(depth_range: str) -> None:
    """Cameras batched in ``view`` alone (one sun, projection and scene box): on every path
    each entry is that camera's own fit (the visible range's depths are one per camera while
    the box is shared: the array form broadcasts the two)."""
    from shadowmath._backends import _kernels

    sun, _, proj, box = scene(10)
    views = np.stack([scene(s)[1] for s in range(10, 14)])  # 4 cameras
    paths = [contextlib.nullcontext, _kernels.array_path, _kernels.disabled]
    for path in paths:
        with path():
            batch = sm.fit_cascades(sun, views, proj, box, 256, depth_range=depth_range)
        for i, view in enumerate(views):
            with path():
                one = sm.fit_cascades(sun, view, proj, box, 256, depth_range=depth_range)
            np.testing.assert_allclose(batch.splits[i], one.splits, rtol=1e-12)
            np.testing.assert_allclose(batch.world_to_clip[i], one.world_to_clip, rtol=1e-9,
                                       atol=1e-12)  # fmt: skip


@pytest.mark.parametrize(
    "options",
    [{}, {"layout": "atlas", "api": "webgpu", "depth_range": "visible"},
     {"count": 2, "pcf_radius": 3, "max_distance": 60.0}],
)  # fmt: skip
def test_compiled_warp_equals_array_path(options: dict[str, Any]) -> None:
    """``warp="lispsm"``'s loop form (compiled) gives the array form's matrices and texel
    sizes to rounding, on cameras where the warp applies and on an orthographic camera
    (where it falls back to the orthographic cascade)."""
    pytest.importorskip("numba")
    from shadowmath._backends import _kernels

    scenes = [scene(s) for s in range(10, 16)]
    sun, view, proj, box = (np.stack(v) for v in zip(*scenes, strict=True))
    proj[-1] = orthographic(20, 15, 1, 120)
    fast = sm.fit_cascades(sun, view, proj, box, 256, warp="lispsm", **options)
    with _kernels.array_path():
        slow = sm.fit_cascades(sun, view, proj, box, 256, warp="lispsm", **options)
    plain = sm.fit_cascades(sun, view, proj, box, 256, **options)
    warped = np.any(np.abs(slow.world_to_clip - plain.world_to_clip) > 1e-6, axis=(-2, -1))
    assert warped[:-1].sum() >= warped[:-1].size // 2 and not warped[-1].any()
    for name in ("world_to_clip", "world_to_texture", "texel_size", "world_to_light", "splits"):
        np.testing.assert_allclose(getattr(fast, name), getattr(slow, name), rtol=1e-9,
                                   atol=1e-12)  # fmt: skip


def test_warp_loop_form_run_by_python_equals_compiled(monkeypatch: pytest.MonkeyPatch) -> None:
    """The warp's loop form gives the same cascades run by Python on lists and floats as
    compiled by Numba (NumPy alone keeps the array form, faster there: this runs the Python
    loop on purpose)."""
    pytest.importorskip("numba")
    from shadowmath._fits.cascades import _door

    scenes = [scene(s) for s in range(10, 13)]
    sun, view, proj, box = (np.stack(v) for v in zip(*scenes, strict=True))
    fast = sm.fit_cascades(sun, view, proj, box, 256, warp="lispsm", layout="atlas")
    compiled = _door._compiled
    monkeypatch.setattr(_door, "_compiled", lambda c, a, _: compiled(c, a, None))
    python = sm.fit_cascades(sun, view, proj, box, 256, warp="lispsm", layout="atlas")
    for name in ("world_to_clip", "world_to_texture", "texel_size"):
        np.testing.assert_allclose(getattr(python, name), getattr(fast, name), rtol=1e-9,
                                   atol=1e-12)  # fmt: skip


def test_inverse4_is_the_inverse() -> None:
    from shadowmath._math._specialize import scalar_formulas

    for seed in range(5):
        m = np.random.default_rng(seed).normal(size=(4, 4))
        inv, det = scalar_formulas().inverse4(tuple(m.ravel()))
        np.testing.assert_allclose(np.reshape(inv, (4, 4)) @ m, np.eye(4), atol=1e-12)
        assert det == pytest.approx(np.linalg.det(m), rel=1e-12)


def test_the_specialized_namespace_has_no_collisions() -> None:
    """Every formula module shares one namespace: a name defined twice would replace one."""
    from shadowmath._math import _specialize

    seen: dict[str, Any] = {}
    for module, _ in _specialize._MODULES:
        for name, value in vars(module).items():
            if name.startswith("__") or name in ("FUNCTIONS", "FORMS"):  # each module's own
                continue
            assert seen.setdefault(name, value) is value, (name, module.__name__)


@pytest.mark.parametrize("path", ["compiled", "python", "array"])
@pytest.mark.parametrize("options", [{}, {"stable": True}, {"layout": "atlas"}])
def test_float32_in_float32_out(path: str, options: dict[str, Any]) -> None:
    from shadowmath._backends import _kernels

    sun, view, proj, box = (a.astype(np.float32) for a in scene(0))
    paths = {"compiled": contextlib.nullcontext, "python": _kernels.disabled,
             "array": _kernels.array_path}  # fmt: skip
    with paths[path]():
        c = sm.fit_cascades(sun, view, proj, box, 256, **options)
    for name in ("world_to_light", "world_to_clip", "world_to_texture", "splits", "band_end",
                 "texel_size"):  # fmt: skip
        assert getattr(c, name).dtype == np.float32, name
    assert all(np.asarray(f).dtype == np.float32 for f in c.frustum[:8])
    want = sm.fit_cascades(*scene(0), 256, **options)
    np.testing.assert_allclose(c.world_to_clip, want.world_to_clip, rtol=2e-3, atol=2e-4)


def test_jax_gradients_in_the_camera_and_the_split_positions() -> None:
    jax = pytest.importorskip("jax")
    jnp = jax.numpy
    sun, view, proj, box = scene(9)
    near = proj[2, 3] / (proj[2, 2] - 1)
    splits = np.array([near, 5.0, 20.0, 60.0])

    def area(shift: Any, s: Any) -> Any:
        v = jnp.asarray(view).at[:3, 3].add(shift)  # the camera moved
        c = sm.fit_cascades(jnp.asarray(sun), v, proj, box, 256, splits=s)
        return jnp.sum(c.frustum.half_width * c.frustum.half_height)

    shift = jnp.asarray([0.3, -0.2, 0.1])
    g_shift, g_splits = jax.grad(area, argnums=(0, 1))(shift, jnp.asarray(splits))
    h = 1e-3  # the area is about 3e3: smaller steps drown in its rounding
    for k in range(3):
        e = np.eye(3)[k] * h
        fd = (area(shift + e, splits) - area(shift - e, splits)) / (2 * h)
        assert float(g_shift[k]) == pytest.approx(float(fd), rel=1e-5, abs=1e-8)
    for k in (1, 2):  # inner splits: both neighbouring cascades move
        e = np.eye(4)[k] * h
        fd = (area(shift, splits + e) - area(shift, splits - e)) / (2 * h)
        assert float(g_splits[k]) == pytest.approx(float(fd), rel=1e-5, abs=1e-8)
        assert float(g_splits[k]) != 0.0


def test_the_options_record_reads_back_each_option_by_name() -> None:
    """The compiled loop reads the options by name from a structured array: each field
    holds its option (a bool as a bool, a count as an int, a matrix as 16 numbers)."""
    from shadowmath._math._cascade_steps import CascadeOptions, options_record

    rows = tuple(tuple(float(16 * m + k) for k in range(16)) for m in range(3))
    o = CascadeOptions(True, False, True, False, 0.9, 0.8, 512.0, 256.0, 2.0**-52, 2.0**-26,
                       3, 0.01, 2, 2, *rows, 2, True, True)  # fmt: skip
    record = options_record(o)[0]
    for name, value in o._asdict().items():
        got = record[name]
        if isinstance(value, tuple):
            assert tuple(got) == value, name
        else:
            assert type(got.item()) is type(value) and got == value, name


@pytest.mark.parametrize("options", [{}, {"stable": True}, {"layout": "atlas"}])
def test_jax_gradient_program_gathers_and_scatters_nothing(options: dict[str, Any]) -> None:
    """Under JAX the cascades' edges are strided slices of the corners and the splits slices
    of their row (not gathers, whose derivatives are scatters: XLA compiles those slowly):
    the gradient's program reads nothing by index arrays (``orientation="fitted"`` does,
    by nature: it picks the best of the hull's edges)."""
    jax = pytest.importorskip("jax")
    jnp = jax.numpy
    sun, view, proj, box = scene(3)

    def loss(light: Any) -> Any:
        c = sm.fit_cascades(light, view, proj, box, 512, **options)
        return jnp.sum(c.world_to_clip**2) + jnp.sum(c.world_to_texture**2)

    def primitives(jaxpr: Any) -> set[str]:
        names = set()
        for eqn in jaxpr.eqns:
            names.add(eqn.primitive.name)
            for value in eqn.params.values():
                for sub in value if isinstance(value, tuple | list) else (value,):
                    inner = getattr(sub, "jaxpr", sub)
                    if hasattr(inner, "eqns"):
                        names |= primitives(inner)
        return names

    used = primitives(jax.make_jaxpr(jax.value_and_grad(loss))(jnp.asarray(sun)).jaxpr)
    assert "dot_general" in used  # the matrices as products: the program was read
    assert not {n for n in used if n.startswith(("gather", "scatter"))}, sorted(used)
