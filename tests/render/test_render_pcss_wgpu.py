"""PCSS on WebGPU (``render_pcss_wgpu``: ``pcss.wgsl``, pcss.glsl in WGSL) against the
true soft shadow (tests/render/pcss_scenes.py), with the bounds of
tests/render/test_render_pcss.py: a flat blocker parallel to the light's plane within
the sampling's error, the light's size doubled clearly worse, a box within the
flat-blocker assumption's error."""

from __future__ import annotations

import numpy as np
import pytest

from shadowmath.render import Light

from . import pcss_scenes as ps
from .test_render_pcss import MEAN_BOUND, P90_BOUND


def compare(scene: str, light: str, factor: float = 1.0) -> ps.Comparison:
    from shadowmath.render.webgpu import render_pcss_wgpu

    case, view = ps.LIGHTS[light], ps.VIEWS["top"]
    lamp = Light(direction=case.where) if case.kind == "sun" else Light(case.where)
    frame = render_pcss_wgpu(
        [ps.FLOOR], [ps.caster(scene, light)], lamp, view.world_to_clip(),
        light_size=ps.scaled_size(light, factor), image_size=view.pixels, map_size=ps.MAP,
    )  # fmt: skip
    floor = frame.body == 0
    axis = tuple(float(a) for a in np.asarray(frame.setup.frame.z_axis))
    truth = ps.truth_image(scene, light, "top", axis)
    return ps.Comparison(floor, 1.0 - frame.shadow.astype(np.float64), np.where(floor, truth, 1.0))


@pytest.mark.parametrize("light", ["point", "sun 2.0°"])
def test_a_flat_blocker_matches_the_true_soft_shadow(wgpu_device, light):
    c = compare("plate", light)
    e = ps.errors(c)
    assert e.pixels > 300
    assert e.mean < MEAN_BOUND and e.p90 < P90_BOUND, e
    assert 0.9 < ps.width_ratio(c) < 1.1


def test_the_wrong_light_size_is_clearly_worse(wgpu_device):
    right = ps.errors(compare("plate", "point"))
    c = compare("plate", "point", 2.0)
    wrong = ps.errors(c)
    assert wrong.mean > max(2 * MEAN_BOUND, 4 * right.mean), (right, wrong)
    assert not 0.9 < ps.width_ratio(c) < 1.1


@pytest.mark.parametrize("light", ["point", "sun 5.0°"])
def test_a_box_stays_near_the_truth(wgpu_device, light):
    """The flat-blocker assumption: narrower penumbrae than the truth's, by up to 20%."""
    c = compare("box", light)
    e = ps.errors(c)
    assert e.mean < 1.5 * MEAN_BOUND + 0.01 and e.p90 < 1.5 * P90_BOUND, e
    assert 0.8 < ps.width_ratio(c) < 1.05


def test_the_cascades_penumbra_does_not_jump_at_a_split(wgpu_device, monkeypatch):
    """``render_cascades_wgpu(light_size=)``: tests/render/test_render_pcss.py's wall
    under a 2° sun, its penumbra's width on either side of the first split within 15%,
    Babylon.js's constant ratio a jump of over 25%."""
    import shadowmath.render._cascade_pass as cascade_pass
    from shadowmath.render.webgpu import render_cascades_wgpu

    from .test_render_pcss import babylon_parameters, penumbra_widths, wall_scene

    before, after = penumbra_widths(*wall_scene(None, render_cascades_wgpu))
    assert before > 0.1 and abs(np.log(after / before)) < np.log(1.15), (before, after)
    monkeypatch.setattr(cascade_pass, "cascade_pcss_parameters", babylon_parameters)
    jump_before, jump_after = penumbra_widths(*wall_scene(None, render_cascades_wgpu))
    assert abs(np.log(jump_after / jump_before)) > np.log(1.25), (jump_before, jump_after)
