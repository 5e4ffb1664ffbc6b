"""Cascades turned to their bodies' least-area rectangles (``orientation="fitted"``), rendered.

The scene, cameras and comparison of ``test_render_cascades``: off the edge band no pixel may
differ from the ray caster (OpenGL and WebGPU), with the maps turned about the light's axis
(by 25 degrees from the camera above the ground's edge, their texels 0.64 to 0.77 of the
unturned maps' area).
"""

from __future__ import annotations

import numpy as np

import shadowmath as sm

from .test_render_cascades import MAX_ALL, render, shadows

__all__ = ["render"]  # the fixture: render_cascades (OpenGL) or render_cascades_wgpu


def test_turned_cascades_agree_with_the_ray_caster(render, monkeypatch):
    fit, plain = sm.fit_cascades, []

    def fit_both(*args, **kwargs):  # the renderer's fit, and the same one unturned
        plain.append(fit(*args, **{**kwargs, "orientation": "light"}))
        return fit(*args, **kwargs)

    monkeypatch.setattr(sm, "fit_cascades", fit_both)
    frame, truth, count = shadows("oblique", render, orientation="fitted", pcf_radius=1)
    turned = np.asarray(frame.cascades.world_to_light)[:, :3, :3]
    cos = np.einsum("nj,nj->n", turned[:, 0], np.asarray(plain[-1].world_to_light)[:, 0, :3])
    print(f"oblique fitted: {count}, turns {np.degrees(np.arccos(cos))}")
    assert np.all(cos < np.cos(np.radians(10))), "every map must be turned"
    assert count.shadowed > 1500, "the view must show sizeable shadows to test anything"
    assert len(np.unique(frame.cascade[frame.body >= 0])) >= 3
    assert count.differ_off_band == 0, count
    assert count.differ <= MAX_ALL * truth.on.sum(), count
