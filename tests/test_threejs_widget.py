"""The widget's Python side: each change of its light or meshes refits the shadow."""

from __future__ import annotations

import numpy as np
import pytest

import shadowmath as sm

pytest.importorskip("anywidget", reason="the widget extra: pip install 'shadowmath[widget]'")

from shadowmath.integrations.threejs import point_shadow_data, shadow_data
from shadowmath.integrations.threejs.widget import ShadowWidget

CUBE = np.array([[x, y, z] for x in (0.0, 1.0) for y in (0.0, 1.0) for z in (1.0, 2.0)])
FACES = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1]])
FLOOR = (
    np.array([[-4.0, -4, 0], [4, -4, 0], [4, 4, 0], [-4, 4, 0]]),
    np.array([[0, 1, 2], [0, 2, 3]]),
)


def test_the_widget_refits_when_the_light_moves():
    """Moving the light (as a drag does: the page sets ``light``) sends the fit of the new
    pose: the data equals ``shadow_data`` of ``fit_shadow`` there, not the old one."""
    sun = {"kind": "directional", "position": [2.0, 1.0, 5.0], "target": [0.0, 0.0, 0.0]}
    w = ShadowWidget([sm.Mesh(CUBE, FACES), FLOOR], light=sun, map_size=512)
    before = w.shadow
    w.light = {**sun, "position": [-3.0, 2.0, 4.0]}
    scene = sm.gather_meshes([(sm.Mesh(CUBE, FACES), np.eye(4)), (sm.Mesh(*FLOOR), np.eye(4))])
    fit = sm.fit_shadow(sm.DirectionalLight([-3.0, 2.0, 4.0]), scene, 512, receivers=scene)
    assert w.shadow == shadow_data(fit)
    assert w.shadow != before
    assert w.fit_error == ""


def test_the_widget_refits_a_point_light_and_reports_a_failed_fit():
    light = {"kind": "point", "position": [0.5, 0.5, 4.0]}
    w = ShadowWidget([sm.Mesh(CUBE, FACES)], light=light, map_size=256)
    depth = sm.cube_depth_range(
        [0.5, 0.5, 4.0], sm.Mesh(CUBE, FACES), receivers=sm.Mesh(CUBE, FACES)
    )
    assert w.shadow == point_shadow_data([0.5, 0.5, 4.0], depth, map_size=256)
    w.light = {"kind": "lamp", "position": [0.0, 0.0, 3.0]}
    assert w.shadow == {} and "kind must be" in w.fit_error
