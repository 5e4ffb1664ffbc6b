"""Tests for the mutation classes a review found surviving the suite (issue 26).

``tools/mutations.py`` lists a mutation for each (``cascade-pad-min``, ``cascade-flat-box``,
``splits-far-equals-near``, ``atlas-hysteresis-upper``/``-lower``,
``camera-ortho-window-symmetric``) and checks that these tests kill it; five or more
cascades in an atlas (columns against rows) is the sixth class. Each test measures the
geometry independently of shadowmath: the slices of the camera are intersected with the
scene by Qhull (``body`` of ``test_cascades``), the light frame's axes are read from the
fit only as a rotation.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable
from contextlib import AbstractContextManager

import numpy as np
import pytest
from scipy.optimize import linprog
from scipy.spatial import HalfspaceIntersection

import shadowmath as sm
from shadowmath import allocate_atlas, shadow_camera
from shadowmath._backends import _kernels

from .cameras import look_at, perspective, scene
from .test_cascades import body, ndc

SLACK = 1 / 64  # NEAR_FAR_SLACK: docs/conventions.md's relative slack of near and far

# Both drivers of fit_cascades: the loop (compiled, or Python without Numba) and the arrays.
PATHS: dict[str, Callable[[], AbstractContextManager[None]]] = {
    "loop": contextlib.nullcontext,
    "array": _kernels.array_path,
}


def box_corners(box: np.ndarray) -> np.ndarray:
    return np.array([[box[i & 1, 0], box[i >> 1 & 1, 1], box[i >> 2, 2]] for i in range(8)])


def to_light(c: sm.Cascades, i: int, p: np.ndarray) -> np.ndarray:
    return p @ np.asarray(c.world_to_light[i])[:3, :3].T + np.asarray(c.world_to_light[i])[:3, 3]


# --- cascades: the pad, a flat scene box, five cascades in an atlas ---------------------------


@pytest.mark.parametrize("path", PATHS)
@pytest.mark.parametrize("seed", [0, 1])
def test_the_cascade_origin_lies_the_depth_range_plus_the_larger_half_size_behind(
    seed: int, path: str
) -> None:
    # The light origin of each cascade is moved back along Z from the scene box's corner
    # nearest the light by pad = (z_hi - z_lo) + max(h_x, h_y): the depth range plus the
    # map's larger half-size (as fit_shadow's sun), measured here on the exact slice.
    sun, view, proj, box = scene(seed)
    with PATHS[path]():
        c = sm.fit_cascades(sun, view, proj, box, 512)
    corners = box_corners(box)
    for i in range(4):
        v = to_light(c, i, body(view, proj, box, c.splits[i], c.band_end[i]))
        hx, hy = np.ptp(v[:, 0]) / 2, np.ptp(v[:, 1]) / 2
        assert abs(hx - hy) > 0.1 * max(hx, hy)  # the larger half-size is not the smaller
        z_lo = to_light(c, i, corners)[:, 2].min()  # the caster nearest the light
        depth = v[:, 2].max() - z_lo
        assert z_lo == pytest.approx(depth + max(hx, hy), rel=1e-9)
        assert c.frustum.near[i] == pytest.approx(z_lo * (1 - SLACK), rel=1e-9)


def ground_polygon(view: np.ndarray, proj: np.ndarray, rect: np.ndarray, a: float, b: float
                   ) -> np.ndarray:  # fmt: skip
    """Vertices of {camera slice a <= depth <= b} on the ground rectangle ``rect`` (y = 0):
    the slice's half-spaces restricted to the plane, intersected in (x, z) by Qhull."""
    pv = proj @ view
    depth = -view[2]
    rows3 = [-(pv[3] - pv[0]), -(pv[3] + pv[0]), -(pv[3] - pv[1]), -(pv[3] + pv[1])]
    rows3 += [np.r_[-depth[:3], a - depth[3]], np.r_[depth[:3], depth[3] - b]]
    rows = [np.r_[r[0], r[2], r[3]] for r in rows3]  # y = 0: the y column drops out
    rows += [np.r_[-1, 0, rect[0, 0]], np.r_[1, 0, -rect[1, 0]]]
    rows += [np.r_[0, -1, rect[0, 1]], np.r_[0, 1, -rect[1, 1]]]
    hs = np.array(rows)
    norms = np.linalg.norm(hs[:, :2], axis=1)
    res = linprog(np.r_[0, 0, -1], A_ub=np.c_[hs[:, :2], norms], b_ub=-hs[:, 2],
                  bounds=[(None, None)] * 2 + [(0, None)])  # fmt: skip
    assert res.status == 0 and res.x[2] > 1e-6, "the slice misses the rectangle"
    xz = HalfspaceIntersection(hs, res.x[:2]).intersections
    return np.c_[xz[:, 0], np.zeros(len(xz)), xz[:, 1]]


@pytest.mark.parametrize("path", PATHS)
@pytest.mark.parametrize("sun", [[0.3, 1.0, 0.2], [0.0, 1.0, 0.0]])
def test_a_flat_scene_box_is_held_and_touches_the_margins(sun: list[float], path: str) -> None:
    # A ground plane as the scene box (zero height), smaller than the slices on one side:
    # its edges, which lie on the box's top and bottom planes at once, bound the map.
    view = look_at([0.0, 10.0, 0.0], [0.0, 0.0, -30.0])
    proj = perspective(1.0, 1.5, 0.5, 120.0)
    rect = np.array([[-3.0, -70.0], [40.0, -3.0]])  # (x, z) of two opposite corners
    box = np.array([[rect[0, 0], 0.0, rect[0, 1]], [rect[1, 0], 0.0, rect[1, 1]]])
    with PATHS[path]():
        c = sm.fit_cascades(np.array(sun), view, proj, box, 512, splits=[0.5, 25.0, 80.0])
    m = c.frustum.margin_x[0]
    for i in range(2):
        p = ndc(c.world_to_clip[i], ground_polygon(view, proj, rect, c.splits[i], c.band_end[i]))
        assert np.all(np.abs(p[:, :2]) <= m * (1 + 1e-9))
        np.testing.assert_allclose(p[:, :2].max(0), [m, m], rtol=1e-9)
        np.testing.assert_allclose(p[:, :2].min(0), [-m, -m], rtol=1e-9)
        assert np.all((p[:, 2] > -1) & (p[:, 2] < 1))


@pytest.mark.parametrize("path", PATHS)
def test_five_cascades_fill_an_atlas_of_three_columns_and_two_rows(path: str) -> None:
    sun, view, proj, box = scene(1)
    with PATHS[path]():
        layers = sm.fit_cascades(sun, view, proj, box, (256, 128), count=5)
        atlas = sm.fit_cascades(sun, view, proj, box, (256, 128), count=5, layout="atlas")
    assert atlas.texture_size == (3 * 256, 2 * 128)
    cells = [(0, 0), (1, 0), (2, 0), (0, 1), (1, 1)]
    np.testing.assert_array_equal(atlas.viewports, [[x * 256, y * 128, 256, 128] for x, y in cells])
    for i, (col, row) in enumerate(cells):
        v = body(view, proj, box, atlas.splits[i], atlas.band_end[i])
        st, st_layer = ndc(atlas.world_to_texture[i], v), ndc(layers.world_to_texture[i], v)
        np.testing.assert_allclose(st[:, 0], (st_layer[:, 0] + col) / 3, rtol=1e-12)
        np.testing.assert_allclose(st[:, 1], (st_layer[:, 1] + row) / 2, rtol=1e-12)
        # Inside its own viewport of the texture, in texels.
        x, y = st[:, 0] * 3 * 256, st[:, 1] * 2 * 128
        assert np.all((x > col * 256) & (x < (col + 1) * 256))
        assert np.all((y > row * 128) & (y < (row + 1) * 128))


def test_splits_refuse_an_empty_range() -> None:
    with pytest.raises(ValueError, match=r"^far: the split range must end beyond near"):
        sm.cascade_splits(5.0, 5.0, 3)
    with pytest.raises(ValueError, match=r"^far: the split range must end beyond near"):
        sm.cascade_splits(0.0, 0.0, 2, scheme="uniform")


# --- the atlas allocator's hysteresis at its exact boundaries ---------------------------------


def test_hysteresis_keeps_a_class_up_to_its_upper_bound_inclusive() -> None:
    # max_tile 512: a coverage c wishes c * 512 texels. The last wish p = 256 is kept while
    # p (1 - h) / 2 < c * 512 <= p (1 + h); with h = 1/4 the bounds 96 and 320 are exact.
    first = allocate_atlas([0.5], atlas_size=1024, hysteresis=0.25)
    assert first.light_size.tolist() == [256]
    at_top = 320 / 512
    keep = allocate_atlas([at_top], atlas_size=1024, hysteresis=0.25, previous=first)
    assert keep.light_size.tolist() == [256]
    beyond = allocate_atlas(
        [np.nextafter(at_top, 1.0)], atlas_size=1024, hysteresis=0.25, previous=first
    )
    assert beyond.light_size.tolist() == [512]  # Godot's class of 320+: the next power of two


def test_hysteresis_drops_a_class_at_its_lower_bound_exclusive() -> None:
    first = allocate_atlas([0.5], atlas_size=1024, hysteresis=0.25)
    at_bottom = 96 / 512
    drop = allocate_atlas([at_bottom], atlas_size=1024, hysteresis=0.25, previous=first)
    assert drop.light_size.tolist() == [128]  # Godot's class of 96: 128
    above = allocate_atlas(
        [np.nextafter(at_bottom, 1.0)], atlas_size=1024, hysteresis=0.25, previous=first
    )
    assert above.light_size.tolist() == [256]


# --- shadow cameras: the symmetric orthographic window ----------------------------------------


def test_an_off_centre_orthographic_fit_gets_a_symmetric_window_about_its_eye() -> None:
    # Cascades sit off the light's Z axis (their texel grid is anchored at the world origin):
    # the camera's eye moves across to each box's centre line and its window is symmetric.
    sun, view, proj, box = scene(0)
    c = sm.fit_cascades(sun, view, proj, box, 512, count=3)
    assert np.abs(c.frustum.center_x).min() > 1.0 and np.abs(c.frustum.center_y).min() > 1.0
    cam = shadow_camera(c)
    np.testing.assert_array_equal(cam.left, -cam.right)
    np.testing.assert_array_equal(cam.bottom, -cam.top)
    right = np.cross(cam.forward, cam.up)
    for i in range(3):
        rel = body(view, proj, box, c.splits[i], c.band_end[i]) - cam.eye[i]
        x, y = rel @ right[i], rel @ cam.up[i]
        # The slice fills the window up to its margins, symmetrically about the eye.
        m = c.frustum.margin_x[i]
        np.testing.assert_allclose([x.max(), -x.min()], m * cam.right[i], rtol=1e-9)
        np.testing.assert_allclose([y.max(), -y.min()], m * cam.top[i], rtol=1e-9)


# --- spot light caster selection: the empty fit's depth -------------------------------------


def test_the_empty_fit_sits_at_the_farthest_casters_depth() -> None:
    # Every caster behind the spot (light z from -6 to -4): the empty fit's square lies at
    # the casters' largest |z| (6), a thin frustum around that depth.
    spot = sm.SpotLight(np.zeros(3), np.array([0.0, 0.0, -1.0]), np.array(0.3))
    casters = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (4.0, 6.0)])
    s = sm.fit_shadow(spot, casters, 64)
    assert int(s.casters_used) == 0
    near, far = float(s.frustum.near), float(s.frustum.far)
    assert near < 6.0 < far and far - near < 0.05 * 6.0


# --- the doors: PCSS radii in a batch, spot casters counted, refusals by name -----------------


def _spot_fit() -> sm.ShadowSetup:
    spot = sm.SpotLight(np.zeros(3), np.array([0.0, 0.0, 1.0]), np.array(0.6))
    casters = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (4.0, 6.0)])
    return sm.fit_shadow(spot, casters, 256)


def test_a_batch_of_light_radii_takes_a_point_light_of_radius_zero() -> None:
    # R = 0 is a point light: no penumbra (K = R s / |b| = 0), in a batch of radii as alone.
    fit = _spot_fit()
    radii = np.array([0.0, 0.25, 0.5])
    batch = sm.pcss_parameters(fit, light_radius=radii)
    assert np.all(np.asarray(batch.texels_per_depth)[0] == 0)
    for i, r in enumerate(radii):
        one = sm.pcss_parameters(fit, light_radius=float(r))
        np.testing.assert_allclose(
            np.asarray(batch.texels_per_depth)[i], one.texels_per_depth, rtol=1e-12, atol=0
        )
    # K is linear in R: the penumbra of twice the disk is twice as wide.
    np.testing.assert_allclose(
        np.asarray(batch.texels_per_depth)[2], 2 * np.asarray(batch.texels_per_depth)[1], rtol=1e-12
    )
    with pytest.raises(ValueError, match=r"^light_radius: expected finite values >= 0"):
        sm.pcss_parameters(fit, light_radius=np.array([0.5, -0.25]))


def test_casters_used_counts_each_lights_points_in_its_cone() -> None:
    # Three spots at different places, each with its own 5 points near its axis: all
    # inside the cone, so each fit uses 5 (not the batch size 3, nor 3 coordinates).
    rng = np.random.default_rng(5)
    positions = np.array([[0.0, 0.0, 0.0], [4.0, 1.0, 0.0], [-3.0, 2.0, 1.0]])
    spots = sm.SpotLight(positions, np.tile([0.0, 0.0, 1.0], (3, 1)), np.full(3, 0.5))
    points = positions[:, None, :] + np.concatenate(
        [rng.uniform(-0.3, 0.3, (3, 5, 2)), rng.uniform(5, 8, (3, 5, 1))], axis=-1
    )
    assert sm.fit_shadow(spots, points, 128).casters_used.tolist() == [5, 5, 5]
    one = sm.SpotLight(positions[1], np.array([0.0, 0.0, 1.0]), np.array(0.5))
    assert int(sm.fit_shadow(one, points[1], 128).casters_used) == 5


def test_method_optimized_refuses_a_spot_light_by_name() -> None:
    spot = sm.SpotLight(np.zeros(3), np.array([0.0, 0.0, 1.0]), np.array(0.6))
    casters = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (4.0, 6.0)])
    with pytest.raises(ValueError, match=r"^method: 'optimized' fits point lights"):
        sm.fit_shadow(spot, casters, 64, method="optimized")


@pytest.mark.parametrize("shape", [(3,), (2, 3), (6, 1)])
def test_a_shadow_fitter_refuses_another_batch_shape(shape: tuple[int, ...]) -> None:
    # Prepared for a batch of six lights: three, or six arranged otherwise, are not its fit
    # (its buffers and views have the prepared shape).
    box = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (4.0, 6.0)])
    fitter = sm.ShadowFitter(sm.PointLight(np.zeros((6, 3))), box, 64)
    assert fitter.fit(sm.PointLight(np.full((6, 3), 0.1)), box).world_to_texture.shape == (
        6, 4, 4,
    )  # fmt: skip
    with pytest.raises(ValueError, match=r"^ShadowFitter\.fit: the arguments are not"):
        fitter.fit(sm.PointLight(np.zeros((*shape, 3))), box)
