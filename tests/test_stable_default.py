"""Stable cascades by default are at least as fine as three.js's stable cascades, at every depth.

The reference is three.js's own fit, written here from its source
(``src/lights/SunLightShadow.js``, ``SunLightShadow.updateMatrices``), not from shadowmath's:
four cascades over ``[camera near, min(shadow far, camera far)]`` cut by the practical
splits ``(uniform + log) / 2``; cascade ``i > 0`` starts at the previous cascade's fade start
(``_cascadeFade = 0.1`` of its depth range before its split), and blends into the next over
``[fade start, split]``; each cascade's square is the sphere about the mean of its slice's
eight corners with the largest distance as radius, ``radius /= 1 - 1 / resolution``, and its
texel ``2 radius / resolution``. (Rotating the corners into the light's frame, as three.js
does, keeps their distances: the sphere is computed here in view space.)

At a view depth ``d`` a shader that blends cascade ``i`` (weight ``w``) with ``i + 1`` reads
texels of area ``w t_i^2 + (1 - w) t_{i+1}^2`` in expectation; the test asserts that
shadowmath's default stable cascades give at most three.js's at every depth of the shadow
distance, for cameras of several fields of view, aspects, near planes and distances, the
maps' usable resolution the same (a border of 2 texels, three.js's inset for PCF radius 1).
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

import shadowmath as sm
from shadowmath._backends import _kernels

from .cameras import look_at, perspective

W = 1024
BORDER = 2  # three.js's inset: ceil(shadow.radius = 1) + 1 texels on each side of a tile
FADE = 0.1  # three.js's _cascadeFade


class ThreeJs:
    """``SunLightShadow.updateMatrices``' splits, fade starts and texel sizes (view space)."""

    def __init__(self, proj: np.ndarray, shadow_far: float) -> None:
        near = proj[2, 3] / (proj[2, 2] - 1)  # an OpenGL perspective's near and far planes
        camera_far = proj[2, 3] / (proj[2, 2] + 1)
        far = max(near + 1e-6, min(shadow_far, camera_far))
        amount = np.arange(1, 4) / 4
        uniform = near + (far - near) * amount
        log = near * (far / near) ** amount
        self.splits = np.r_[near, (uniform + log) * 0.5, far]
        inverse = np.linalg.inv(proj)
        corners = []
        for x, y in ((1, 1), (1, -1), (-1, -1), (-1, 1)):
            h = inverse @ [x, y, -1.0, 1.0]
            corners.append(h[:3] / h[3])
        near_corners = np.array(corners)
        far_corners = near_corners * (far / near)
        resolution = W - 2 * BORDER
        self.fade = np.empty(4)
        self.texel = np.empty(4)
        start = self.splits[0]
        for i in range(4):
            end = self.splits[i + 1]
            self.fade[i] = end - FADE * (end - self.splits[i])
            alphas = ((start - near) / (far - near), (end - near) / (far - near))
            pts = np.array([n + a * (f - n) for a in alphas
                            for n, f in zip(near_corners, far_corners, strict=True)])  # fmt: skip
            radius = np.max(np.linalg.norm(pts - pts.mean(axis=0), axis=1))
            radius /= 1 - 1 / resolution
            self.texel[i] = 2 * radius / resolution
            start = self.fade[i]

    def area(self, d: np.ndarray) -> np.ndarray:
        """Texel area read at view depth ``d``: cascade ``i`` up to its fade start, then
        blended linearly into ``i + 1`` up to its split."""
        i = np.clip(np.searchsorted(self.splits, d, side="right") - 1, 0, 3)
        a = self.texel**2
        fade, end = self.fade[i], self.splits[i + 1]
        w = np.where((d > fade) & (i < 3), (end - d) / (end - fade), 1.0)
        return np.asarray(w * a[i] + (1 - w) * a[np.minimum(i + 1, 3)])


def shadowmath_area(c: sm.Cascades, d: np.ndarray) -> np.ndarray:
    """The same for shadowmath's cascades: cascade ``i`` serves ``[splits[i], splits[i+1])``
    and is blended with ``i - 1`` over ``[splits[i], band_end[i - 1]]``."""
    splits, band = np.asarray(c.splits), np.asarray(c.band_end)
    a = np.prod(np.asarray(c.texel_size), axis=1)
    i = np.clip(np.searchsorted(splits, d, side="right") - 1, 0, 3)
    prev = np.maximum(i - 1, 0)
    in_band = (i > 0) & (d <= band[prev])
    w = np.where(in_band, (band[prev] - d) / (band[prev] - splits[i]), 0.0)
    return np.asarray(w * a[prev] + (1 - w) * a[i])


CAMERAS = [  # (vertical field of view in degrees, aspect, near, far, shadow distance)
    (60.0, 16 / 9, 0.1, 1000.0, 300.0),
    (60.0, 16 / 9, 0.1, 1000.0, 200.0),
    (45.0, 4 / 3, 0.5, 500.0, 450.0),
    (90.0, 1.0, 0.05, 200.0, 120.0),
    (30.0, 2.4, 1.0, 5000.0, 2000.0),
    (75.0, 0.6, 0.2, 800.0, 60.0),
]


@pytest.mark.parametrize(("fov", "aspect", "near", "far", "distance"), CAMERAS)
def test_the_stable_default_is_no_coarser_than_threejs_at_any_depth(
    fov: float, aspect: float, near: float, far: float, distance: float
) -> None:
    proj = perspective(math.radians(fov), aspect, near, far)
    three = ThreeJs(proj, distance)
    rng = np.random.default_rng(int(fov * aspect))
    box = np.array([[-3000.0, 0.0, -3000.0], [3000.0, 40.0, 3000.0]])
    d = np.linspace(near, min(distance, far), 20001)
    for _ in range(3):  # the sizes hold whatever the pose (stable): a few to be sure
        eye = rng.uniform([-50, 1, -50], [50, 120, 50])
        view = look_at(eye, eye + rng.normal(size=3))
        sun = rng.normal(size=3) + [0, 3, 0]
        c = sm.fit_cascades(sun, view, proj, box, W, max_distance=distance, stable=True,
                            border_texels=BORDER)  # fmt: skip
        # Each cascade, band included, lies within three.js's (its sphere then no larger):
        starts = np.r_[three.splits[0], three.fade[:-1]]
        assert np.all(c.splits[:-1] >= starts * (1 - 1e-12))
        assert np.all(c.band_end <= three.splits[1:] * (1 + 1e-12))
        assert np.all(c.texel_size <= three.texel[:, None] * (1 + 1e-12))
        # ... and at every depth the blended texels are no larger.
        ours, theirs = shadowmath_area(c, d), three.area(d)
        assert np.all(ours <= theirs * (1 + 1e-12)), d[np.argmax(ours / theirs)]


def test_the_old_default_was_coarser_than_threejs_somewhere() -> None:
    """The test above can fail: the practical splits with ``lam = 0.75`` and the band after
    each split (the tight default's rule) leave depths where three.js's texels are finer."""
    proj = perspective(math.radians(60.0), 16 / 9, 0.1, 1000.0)
    three = ThreeJs(proj, 300.0)
    view = look_at(np.array([0.0, 100.0, 0.0]), np.array([0.0, 0.0, -30.0]))
    box = np.array([[-1000.0, 0.0, -1000.0], [1000.0, 8.0, 1000.0]])
    d = np.linspace(0.1, 300.0, 20001)
    for lam in (0.75, 0.5):  # 0.5: three.js's splits, but each band beyond its split
        c = sm.fit_cascades([0.3, 1.0, 0.2], view, proj, box, W, max_distance=300.0,
                            stable=True, border_texels=BORDER, lam=lam)  # fmt: skip
        assert np.max(shadowmath_area(c, d) / three.area(d)) > 1.01


def test_the_stable_default_bands_end_at_the_practical_splits() -> None:
    """``scheme="auto"`` with ``stable=True`` over the camera's range: every band ends at the
    practical split with ``lam = 0.5``, and the bands are ``overlap`` of their cascades; the
    NumPy and JAX paths agree."""
    proj = perspective(math.radians(50.0), 1.5, 0.3, 900.0)
    view = look_at(np.array([3.0, 12.0, 1.0]), np.array([40.0, 0.0, -60.0]))
    box = np.array([[-500.0, 0.0, -500.0], [500.0, 30.0, 500.0]])
    for overlap in (0.1, 0.25):
        c = sm.fit_cascades([0.2, 1.0, 0.4], view, proj, box, 512, max_distance=400.0,
                            stable=True, overlap=overlap)  # fmt: skip
        want = sm.cascade_splits(0.3, 400.0, 4, lam=0.5)
        np.testing.assert_allclose(c.band_end, want[1:], rtol=1e-12)
        s = np.asarray(c.splits)
        np.testing.assert_allclose(s[[0, -1]], [0.3, 400.0], rtol=1e-12)
        np.testing.assert_allclose(c.band_end[:-1], s[1:-1] + overlap * np.diff(s)[:-1],
                                   rtol=1e-12)  # fmt: skip
    jnp = pytest.importorskip("jax").numpy  # float64: tests/conftest.py enables it
    j = sm.fit_cascades(jnp.asarray([0.2, 1.0, 0.4]), jnp.asarray(view), jnp.asarray(proj),
                        jnp.asarray(box), 512, max_distance=400.0, stable=True,
                        overlap=0.25)  # fmt: skip
    np.testing.assert_allclose(np.asarray(j.splits), c.splits, rtol=1e-12)
    for path in (_kernels.disabled, _kernels.array_path):  # the Python loop, the array mode
        with path():
            p = sm.fit_cascades([0.2, 1.0, 0.4], view, proj, box, 512, max_distance=400.0,
                                stable=True, overlap=0.25)  # fmt: skip
        np.testing.assert_allclose(p.splits, c.splits, rtol=1e-12)
        np.testing.assert_allclose(p.world_to_texture, c.world_to_texture, rtol=1e-9, atol=1e-12)
    # A given lam, a tight fit: the scheme's own splits, each band after its split.
    for kwargs in ({"lam": 0.5, "stable": True}, {"stable": False}):
        c = sm.fit_cascades([0.2, 1.0, 0.4], view, proj, box, 512, max_distance=400.0, **kwargs)
        lam = kwargs.get("lam", 0.75)
        np.testing.assert_allclose(c.splits, sm.cascade_splits(0.3, 400.0, 4, lam=lam),
                                   rtol=1e-12)  # fmt: skip


# --- widen_cascades on stable cascades: refused, with the border that holds the search -------


def slice_corners(view: np.ndarray, proj: np.ndarray, a: float, b: float) -> np.ndarray:
    """World corners of the camera's slice between view depths ``a`` and ``b``."""
    inverse, to_world = np.linalg.inv(proj), np.linalg.inv(view)
    out = []
    for d in (a, b):
        for x, y in ((1, 1), (1, -1), (-1, -1), (-1, 1)):
            h = inverse @ [x, y, -1.0, 1.0]
            p = h[:3] / h[3] * (d / -(h[2] / h[3]))
            out.append((to_world @ np.r_[p, 1.0])[:3])
    return np.array(out)


@pytest.mark.parametrize("degrees", [0.27, 1.0, 3.0])
def test_widening_stable_cascades_is_refused_with_a_border_that_holds_the_search(
    degrees: float,
) -> None:
    """The message names ``border_texels=B``; refitted with it, each stable map reaches the
    blocker search's ``w = tan(theta) (f - n)`` past every corner of its slice (its whole
    map, border included: the search may read it), and its half-extent holds ``h + w``
    (``h``: the square's half-width, the sphere's radius plus the half texel its snapped
    centre may have moved); with ``B - 1`` some cascade's does not."""
    proj = perspective(math.radians(60.0), 16 / 9, 0.1, 300.0)
    view = look_at(np.array([2.0, 6.0, 1.0]), np.array([30.0, 0.0, -50.0]))
    box = np.array([[-200.0, 0.0, -200.0], [200.0, 15.0, 200.0]])
    sun, theta = np.array([0.4, 1.0, -0.3]), math.radians(degrees)
    c = sm.fit_cascades(sun, view, proj, box, W, max_distance=120.0, stable=True, pcf_radius=1)
    with pytest.raises(ValueError, match="stable cascades cannot be widened") as info:
        sm.widen_cascades(c, angular_radius=theta)
    found = re.search(r"border_texels=(\d+)", str(info.value))
    assert found is not None, str(info.value)
    border = int(found.group(1))
    radius = c.frustum.half_width * (1 - 1 / (c.frustum.margin_x * W))  # the slices' spheres
    for b, holds in ((border, True), (border - 1, False)):
        r = sm.fit_cascades(sun, view, proj, box, W, max_distance=120.0, stable=True,
                            border_texels=b)  # fmt: skip
        # the same spheres, whatever the border:
        np.testing.assert_allclose(r.frustum.half_width * (1 - 1 / (r.frustum.margin_x * W)),
                                   radius, rtol=1e-12)  # fmt: skip
        w = math.tan(theta) * (r.frustum.far - r.frustum.near)
        extent = r.frustum.half_width / r.frustum.margin_x  # the whole map's half-width
        assert bool(np.all(extent >= r.frustum.half_width + w)) == holds
        if holds:
            for i in range(4):
                p = slice_corners(view, proj, r.splits[i], r.band_end[i])
                st = (np.c_[p, np.ones(8)] @ r.world_to_texture[i].T)[:, :2] * W
                reach = w[i] / r.texel_size[i]
                assert np.all(st - reach >= -1e-6) and np.all(st + reach <= W + 1e-6)
