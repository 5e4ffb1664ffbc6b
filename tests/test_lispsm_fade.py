"""The LiSPSM warp's strength: capped so that the warp never makes a map coarser, faded
as the view turns toward the light (``shadowmath/_fits/cascades/_lispsm.py``, ``docs/lispsm.md``).

The resolution is measured as ``benchmarks/bench_cascades.py`` measures it (its scenes'
camera, its analytic ray casting and its texel-area-per-pixel-footprint ratio), the
texel sizes from the matrices alone (:func:`tests.test_lispsm.texel_size`), the warp's
strength ``lambda = f / n - 1`` from the matrices too: ``q = t`` spans ``[n, f]`` over
the slice's vertices (Qhull's).
"""

from __future__ import annotations

import importlib
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import shadowmath as sm
from shadowmath._fits.cascades._lispsm import WARP_CHECK_DEPTH, WARP_MIN_STRENGTH, WARP_RAYS

from .test_lispsm import SIZE, axis_point, body, horizon, scene, texel_size, warped

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))
bench: Any = importlib.import_module("bench_cascades")

PROJECTION = bench.perspective(bench.FOV_Y, bench.ASPECT, bench.NEAR, bench.FAR)


def ground(yaw: float, elevation: float) -> Any:
    """The benchmark's horizon scene's ground and camera (1.7 m, 5 degrees down), turned by
    ``yaw``, under a sun ``elevation`` degrees high in the direction ``yaw = 0``."""
    return bench.Scene(
        "sweep", "", np.array([0.0, 1.7, 0.0]), yaw, -5.0, bench.sun_direction(elevation, 0.0),
        150.0, np.array([[-1000.0, 0.0, -1000.0], [1000.0, 8.0, 1000.0]]), np.zeros((0, 2, 3)),
    )  # fmt: skip


def strength(c: sm.Cascades, view: Any, proj: Any, box: Any, i: int) -> float:
    """``f / n - 1`` of cascade ``i`` (0 unwarped): ``q``'s range over the slice's vertices."""
    v = body(view, proj, box, c.splits[i], c.band_end[i])
    q = np.c_[v, np.ones(len(v))] @ np.asarray(c.world_to_clip[i])[3]
    return float(q.max() / q.min() - 1.0)


def test_the_warp_is_never_coarser_than_no_warp_in_a_sweep_of_headings() -> None:
    """Facing a low sun the unfaded warp was 13x coarser at the median (issue 27)."""
    gains = []
    for elevation in (10.0, 40.0, 70.0):
        for yaw in range(0, 360, 30):
            s = ground(float(yaw), elevation)
            hits = bench.cast(s, PROJECTION, (96, 54))
            flat = bench.ratios(bench.shadowmath_fit(s, PROJECTION, stable=False, splits=None),
                                hits, s.sun)  # fmt: skip
            fit = bench.shadowmath_fit(s, PROJECTION, stable=False, splits=None, warp=True)
            warp = bench.ratios(fit, hits, s.sun)
            assert warp.uncovered == 0
            a, b = bench.stats(flat), bench.stats(warp)
            assert b.median <= a.median * (1 + 1e-9), (elevation, yaw)
            assert b.p90 <= a.p90 * (1 + 1e-9), (elevation, yaw)
            gains.append(b.p90 / a.p90)
    # ... and it still helps: a tenth finer at the 90th percentile in a third of the poses.
    assert np.mean(np.array(gains) < 0.9) > 1 / 3


@pytest.mark.parametrize("seed", range(8))
def test_warped_texels_are_no_larger_up_to_the_check_depth(seed: int) -> None:
    """On the view axis, from the slice's nearest depth ``z_0`` to ``z_0 (z_1 / z_0)^beta``,
    a warped texel's area across the light is at most the orthographic one's, and at
    ``z_0`` smaller (the texel area grows like ``t^3`` along the warp's axis)."""
    light, view, proj, box = scene(seed) if seed < 7 else horizon()
    flat = sm.fit_cascades(light, view, proj, box, SIZE)
    warp = sm.fit_cascades(light, view, proj, box, SIZE, warp="lispsm")
    for i in np.flatnonzero(warped(warp)):
        v = body(view, proj, box, warp.splits[i], warp.band_end[i])
        depth = -(v @ view[2, :3] + view[2, 3])
        z0, z1 = depth.min(), depth.max()
        zs = z0 * (z1 / z0) ** np.linspace(0.0, WARP_CHECK_DEPTH, 12)
        points = np.array([axis_point(view, z) for z in zs])
        ortho = texel_size(np.asarray(flat.world_to_texture[i]), points, light)
        warped_size = texel_size(np.asarray(warp.world_to_texture[i]), points, light)
        assert np.all(warped_size <= ortho * (1 + 1e-6)), (i, warped_size / ortho)
        assert warped_size[0] < ortho[0]


def test_the_strength_fades_to_zero_as_the_view_turns_toward_the_light() -> None:
    """The horizon camera (looking along +x, 5.7 degrees down) and a sun behind it sinking
    toward the view direction: each cascade's strength falls continuously (finer steps,
    proportionally smaller changes) and is 0 before the view and light align."""
    _, view, proj, box = horizon()

    def curve(ys: Any) -> Any:
        fits = [sm.fit_cascades(np.array([-1.0, y, 0.0]), view, proj, box, SIZE, warp="lispsm")
                for y in ys]  # fmt: skip
        return np.array([[strength(c, view, proj, box, i) for i in range(4)] for c in fits])

    coarse = curve(np.linspace(0.4, 0.3, 5))
    fine = curve(np.linspace(0.4, 0.3, 17))
    assert np.all(coarse > WARP_MIN_STRENGTH) and np.all(fine > WARP_MIN_STRENGTH)
    np.testing.assert_allclose(fine[::4], coarse, rtol=1e-12)
    step_coarse = np.abs(np.diff(coarse, axis=0)).max(axis=0)
    step_fine = np.abs(np.diff(fine, axis=0)).max(axis=0)
    assert np.all(step_fine < 0.35 * step_coarse)  # a jump would not shrink with the step
    assert np.all(np.diff(fine, axis=0) < 0)  # weaker as the view turns toward the light
    # Looking along the light (the view's tilt, 0.1): no warp.
    aligned = curve(np.array([0.1, 0.11]))
    assert np.all(aligned == 0.0)


def field(seed: int) -> Any:
    """A random pose over a 200 m ground (casters up to 10 m): camera 1.5-60 m up, pitch 0 to
    80 degrees down, any heading; a sun 10-80 degrees high from any azimuth."""
    rng = np.random.default_rng(seed)
    eye = np.array([rng.uniform(-20, 20), rng.uniform(1.5, 60.0), rng.uniform(-20, 20)])
    sun = bench.sun_direction(rng.uniform(10.0, 80.0), rng.uniform(0.0, 360.0))
    return bench.Scene(
        "random", "", eye, rng.uniform(0.0, 360.0), -rng.uniform(0.0, 80.0), sun, 150.0,
        np.array([[-100.0, 0.0, -100.0], [100.0, 10.0, 100.0]]), np.zeros((0, 2, 3)),
    )  # fmt: skip


@pytest.mark.parametrize("seed", range(24))
def test_no_cascade_is_coarser_at_the_median_or_p90_of_its_receiver_samples(seed: int) -> None:
    """The guarantee made at the fit (``_lispsm._check``): over the receiver samples, the
    rays through the centres of a ``WARP_RAYS``-square grid over the screen (here the
    benchmark's own ray casting of an image of that size onto the ground), each cascade's
    median and 90th percentile of texel area per pixel footprint are no larger warped than
    not: computed here from the matrices (the Jacobian of the warped texture coordinates)."""
    s = field(seed)
    hits = bench.cast(s, PROJECTION, (WARP_RAYS, WARP_RAYS))
    flat_fit = bench.shadowmath_fit(s, PROJECTION, stable=False, splits=None)
    warp_fit = bench.shadowmath_fit(s, PROJECTION, stable=False, splits=None, warp=True)
    flat, warp = (bench.ratios(f, hits, s.sun).ratio for f in (flat_fit, warp_fit))
    index = np.searchsorted(flat_fit.splits, hits.depth, side="right") - 1
    for i in range(4):
        mine = index == i
        if mine.sum() < 8:
            continue
        for q in (50, 90):
            a, b = np.percentile(flat[mine], q), np.percentile(warp[mine], q)
            assert b <= a * (1 + 1e-9), (seed, i, q, b / a)


@pytest.mark.parametrize("key", ["town/h10/p-75/y90/s40", "field/h1.7/p-75/y0/s70"])
def test_the_sweeps_worst_poses_are_no_longer_coarser(key: str) -> None:
    """Where the view-axis cap alone left the warp coarser than no warp in the pose sweep
    (``benchmarks/bench_sweep.py``: 0.34x and 0.56x at p90), on a small image."""
    sweep = importlib.import_module("bench_sweep")
    pose = next(p for p in sweep.poses() if p.key == key)
    s = pose.scene
    hits = bench.cast(s, PROJECTION, (160, 90))
    flat = bench.stats(bench.ratios(bench.shadowmath_fit(s, PROJECTION, stable=False,
                                                         splits=None), hits, s.sun))  # fmt: skip
    fit = bench.shadowmath_fit(s, PROJECTION, stable=False, splits=None, warp=True)
    warp = bench.stats(bench.ratios(fit, hits, s.sun))
    assert warp.median <= flat.median * (1 + 1e-9) and warp.p90 <= flat.p90 * (1 + 1e-9)
    assert warp.median < 0.95 * flat.median  # and the warp still helps


def test_the_strength_is_continuous_as_a_steep_camera_turns_toward_the_sun() -> None:
    """A camera 10 m up looking 75 degrees down (the sweep's town) turns from 55 to 20
    degrees off a 40-degree sun toward it: the first cascade's strength (capped by the
    receiver samples' quantiles) rises from 0 and changes by steps that shrink with the
    turning step (a jump would not); the others stay unwarped."""
    sun = bench.sun_direction(40.0, 0.0)
    box = np.array([[-200.0, 0.0, -400.0], [200.0, 18.0, 200.0]])

    def curve(yaws: Any) -> Any:
        out = []
        for yaw in yaws:
            view = bench.look(np.array([0.0, 10.0, 5.0]), float(yaw), -75.0)
            c = sm.fit_cascades(sun, view, PROJECTION, box, SIZE, max_distance=200.0,
                                warp="lispsm")  # fmt: skip
            out.append([strength(c, view, PROJECTION, box, i) if warped(c)[i] else 0.0
                        for i in range(4)])  # fmt: skip
        return np.array(out)

    coarse = curve(np.linspace(45.0, 20.0, 5))
    fine = curve(np.linspace(45.0, 20.0, 17))
    np.testing.assert_allclose(fine[::4], coarse, rtol=1e-12)
    assert np.all(fine[:, 0] > WARP_MIN_STRENGTH) and np.all(fine[:, 1:] == 0.0)
    step_coarse = np.abs(np.diff(coarse[:, 0])).max()
    step_fine = np.abs(np.diff(fine[:, 0])).max()
    assert step_fine < 0.35 * step_coarse  # a jump would not shrink with the step
    # Where the view turns further across the sun the strength has faded out (to 0 at 55).
    ends = curve(np.array([47.5, 55.0]))[:, 0]
    assert 0 < ends[0] < fine[0, 0] and ends[1] == 0.0
