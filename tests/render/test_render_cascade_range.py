"""Cascades with ``fit_cascades``'s default split rule and depth ranges, rendered, against the
ray caster.

The scene, cameras and comparison of ``test_render_cascades`` (among them a camera 2.5 high
at the horizon and one 70 high looking down, as in the pose sweep); ``sm.fit_cascades`` is
called by ``render_cascades`` with its own default splits (``scheme="auto"``: ``lam = 0.75``
over the camera's range, 0.5 with each band ending at its split for stable cascades there, the
log scheme over a visible or measured one), over the camera's
range (tight and stable), with ``depth_range="visible"`` (alone, stable with the slice's
sphere, and with stable squares on the ladder from ``CascadeState.initial()``) or with the
range measured on a first frame (the view depths of its visible points). Off the edge band
no pixel may differ from the ray caster (OpenGL and WebGPU).
The band also holds the lit pixels whose lookup reaches texels of another surface than
their own plane (``reach_off_plane``: a face's foot on the ground), where the bias, derived
for planar receivers, guarantees nothing.
"""

from __future__ import annotations

import numpy as np
import pytest

import shadowmath as sm

from .depth_scenes import compare
from .test_render_cascades import CAMERAS, NEAR, reach_off_plane, render, shadows

__all__ = ["render"]  # the fixture: render_cascades (OpenGL) or render_cascades_wgpu

VARIANTS = {
    "default": {},
    "stable": {"stable": True},
    "visible": {"depth_range": "visible"},
    "visible, stable": {"depth_range": "visible", "stable": True},
    "visible, stable, state": {"depth_range": "visible", "stable": True, "state": True},
    "measured": {"depth_range": "measured"},
    "measured, stable, state": {"depth_range": "measured", "stable": True, "state": True},
}


@pytest.mark.parametrize("variant", list(VARIANTS))
@pytest.mark.parametrize("camera", list(CAMERAS))
def test_the_visible_range_agrees_with_the_ray_caster(render, monkeypatch, camera, variant):
    options = dict(VARIANTS[variant])
    stable = options.pop("stable", False)
    if options.pop("state", False):
        options["state"] = sm.CascadeState.initial()
    if options.get("depth_range") == "measured":  # the view depths a first frame saw
        frame, _, _ = shadows(camera, render)
        p = frame.position[frame.body >= 0].astype(np.float64)
        depth = -(p @ CAMERAS[camera][2, :3] + CAMERAS[camera][2, 3])
        options["depth_range"] = np.array([depth.min(), depth.max()])
    fit, fits = sm.fit_cascades, []

    def fit_range(*args, **kwargs):
        fits.append(fit(*args, **kwargs, **options))
        return fits[-1]

    monkeypatch.setattr(sm, "fit_cascades", fit_range)
    frame, truth, _ = shadows(camera, render, stable=stable, scheme="auto", lam=None)
    off_plane = reach_off_plane(frame, truth, CAMERAS[camera])
    count = compare(frame.shadow > 0.5, truth._replace(band=truth.band | off_plane))
    splits = np.asarray(fits[-1].splits)
    near, far = splits[0], splits[-1]  # the default rule: lam = 0.75 over the camera's range
    lam = 0.75 if "depth_range" not in options else 1.0  # the log scheme over a fitted one
    ends = splits  # stable over the camera's range: lam = 0.5, each band ending at its split
    if stable and "depth_range" not in options:
        lam, ends = 0.5, np.r_[near, np.asarray(fits[-1].band_end)]
    i = np.arange(5) / 4
    want = lam * near * (far / near) ** i + (1 - lam) * (near + (far - near) * i)
    np.testing.assert_allclose(ends, want, rtol=1e-9)
    print(f"{camera} {variant}: {count}, off plane {off_plane.sum()}, splits {splits.round(2)}")
    assert count.shadowed > 1500
    # The scene's box holds the high cameras (the tower behind them is 75 high): their
    # visible range starts at the near plane, and the log scheme leaves their view (from
    # 40 m on) to the last cascade alone (docs/cascades.md).
    used = np.unique(frame.cascade[frame.body >= 0])
    if camera != "horizon" and variant.startswith("visible"):
        assert splits[0] == pytest.approx(NEAR) and list(used) == [3]
    else:
        assert len(used) >= 2
    assert count.differ_off_band == 0, count
    if "measured" in variant:  # the range holds the measured one
        assert splits[0] <= options["depth_range"][0] and splits[-1] >= options["depth_range"][1]
        assert camera == "horizon" or splits[0] > 10 * NEAR  # nothing near the high camera
