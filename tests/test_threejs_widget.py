"""The widget's Python side: each change of its light or meshes refits the shadow."""

from __future__ import annotations

import numpy as np
import pytest

import shadowmath as sm

pytest.importorskip("anywidget", reason="the widget extra: pip install 'shadowmath[widget]'")

from shadowmath.integrations.threejs import cascade_shadow_data, point_shadow_data, shadow_data
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


def test_the_widget_refits_its_cascades_when_the_camera_moves():
    """In cascades mode a new camera (as an orbit's end sends it) refits: the data equals
    ``cascade_shadow_data`` of ``fit_cascades`` from that camera (its lookAt with z up and
    three.js's perspective, written here from their definitions), over the meshes' bounds."""
    sun = {"kind": "directional", "position": [2.0, 1.0, 5.0], "target": [0.0, 0.0, 0.0]}
    view = {"position": [0.0, -8.0, 4.0], "target": [0.0, 0.0, 0.0], "fov": 60.0}
    view |= {"aspect": 1.5, "near": 1.0, "far": 20.0}
    w = ShadowWidget([sm.Mesh(CUBE, FACES), FLOOR], light=sun, camera=view, cascades=3)
    before = w.shadow
    moved = {**view, "position": [6.0, -3.0, 3.0]}
    w.camera = moved
    eye = np.array(moved["position"])
    back = eye / np.linalg.norm(eye)  # the target is the origin
    right = np.cross([0.0, 0.0, 1.0], back)
    right /= np.linalg.norm(right)
    world_to_eye = np.eye(4)
    world_to_eye[:3, :3] = np.stack([right, np.cross(back, right), back])
    world_to_eye[:3, 3] = -world_to_eye[:3, :3] @ eye
    t = np.tan(np.radians(30.0))  # half of fov 60
    projection = np.array(
        [
            [1 / (1.5 * t), 0, 0, 0],
            [0, 1 / t, 0, 0],
            [0, 0, -21 / 19, -40 / 19],
            [0, 0, -1, 0],
        ]
    )
    bounds = np.array([[-4.0, -4.0, 0.0], [4.0, 4.0, 2.0]])
    fit = sm.fit_cascades([2.0, 1.0, 5.0], world_to_eye, projection, bounds, 1024, count=3)
    assert w.fit_error == "" and w.shadow != before
    got, expected = w.shadow, cascade_shadow_data(fit)
    assert got["splits"] == pytest.approx(expected["splits"], rel=1e-12)
    for a, b in zip(got["cascades"], expected["cascades"], strict=True):
        assert np.allclose(a["matrixWorld"], b["matrixWorld"], rtol=1e-9, atol=1e-9)
        for key in ("left", "right", "top", "bottom", "near", "far"):
            assert a[key] == pytest.approx(b[key], rel=1e-9, abs=1e-9)


def test_the_widget_without_cascades_keeps_its_fit_when_the_camera_moves():
    sun = {"kind": "directional", "position": [2.0, 1.0, 5.0], "target": [0.0, 0.0, 0.0]}
    w = ShadowWidget([sm.Mesh(CUBE, FACES), FLOOR], light=sun)
    before = w.shadow
    w.camera = {"position": [6.0, -3.0, 3.0], "target": [0.0, 0.0, 0.0]}
    assert w.shadow == before
    w.light = {"kind": "spot", "position": [0.0, 0.0, 5.0], "target": [0, 0, 0], "angle": 0.5}
    w.cascades = 2
    assert w.shadow == {} and "only a directional light" in w.fit_error
