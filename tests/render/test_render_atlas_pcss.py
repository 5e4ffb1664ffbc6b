"""PCSS in the shadow atlas (``render_atlas(..., light_size=)``): a spot light's tile and
a point light's six face tiles in one atlas, each tile's ``K`` from
``pcss_parameters(AtlasFit)`` in atlas texels, taps clamped to the tile, on OpenGL and on WebGPU
(``render_atlas_wgpu``, ``atlas.wgsl`` including ``pcss.wgsl``); each light's
mask against its true soft shadow (tests/render/pcss_scenes.py) with the bounds of
tests/render/test_render_pcss.py's casters with depth (a box on the floor). The point
light's shadow falls on its ``-Z`` face, whose plane the truth's disk faces."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

import shadowmath as sm
from shadowmath.render import render_atlas

from . import pcss_scenes as ps
from .test_render_pcss import MEAN_BOUND, P90_BOUND

LIGHTS = {"spot": ps.spot_light(ps.LIGHTS["spot"]),
          "point": sm.PointLight(np.array(ps.LIGHTS["point"].where))}  # fmt: skip
AXES = {"spot": tuple(ps.light_axis(ps.LIGHTS["spot"])), "point": (0.0, 0.0, -1.0)}


def compare(sizes: list[float], render: Callable[..., Any]) -> dict[str, ps.Comparison]:
    view = ps.VIEWS["top"]
    frame = render(
        [ps.FLOOR, ps.CASTERS["box"]], list(LIGHTS.values()), np.eye(4), view.world_to_clip(),
        casters=[False, True], light_size=sizes, image_size=view.pixels, atlas_size=4096,
    )  # fmt: skip
    assert (np.asarray(frame.atlas.light_tiles) >= 0).sum() == 7  # the spot's, six faces
    floor = frame.body == 0
    out = {}
    for i, name in enumerate(LIGHTS):
        truth = ps.truth_image("box", name, "top", tuple(float(a) for a in AXES[name]))
        pcss = 1.0 - frame.shadow[i].astype(np.float64)
        out[name] = ps.Comparison(floor, pcss, np.where(floor, truth, 1.0))
    return out


def check_near_truth(render: Callable[..., Any]) -> None:
    """Each light's mask near its true soft shadow; the spot's ``K`` halved is not."""
    sizes = [ps.LIGHTS["spot"].size, ps.LIGHTS["point"].size]
    right = compare(sizes, render)
    for name, c in right.items():
        e = ps.errors(c)
        assert e.pixels > 300
        assert e.mean < 1.5 * MEAN_BOUND + 0.01 and e.p90 < 1.5 * P90_BOUND, (name, e)
        assert 0.8 < ps.width_ratio(c) < 1.05, name
    wrong = compare([sizes[0] / 2, sizes[1]], render)["spot"]  # the spot's K halved
    e, e_right = ps.errors(wrong), ps.errors(right["spot"])
    assert e.mean > max(2 * MEAN_BOUND, 4 * e_right.mean), (e_right, e)
    assert not 0.9 < ps.width_ratio(wrong) < 1.1


def test_each_tile_is_near_the_true_soft_shadow_and_the_wrong_size_is_not(gl):
    check_near_truth(lambda *a, **k: render_atlas(*a, **k, ctx=gl))


def test_webgpu_tiles_are_near_the_true_soft_shadow_and_the_wrong_size_is_not(wgpu_device):
    from shadowmath.render.webgpu import render_atlas_wgpu

    check_near_truth(render_atlas_wgpu)


def check_options(render: Callable[..., Any]) -> None:
    args = ([ps.FLOOR, ps.CASTERS["box"]], list(LIGHTS.values()), np.eye(4),
            ps.VIEWS["top"].world_to_clip())  # fmt: skip
    for bad in ([0.3], [0.3, -1.0], [0.3, float("nan")]):
        with pytest.raises(ValueError, match="light_size"):
            render(*args, light_size=bad, atlas_size=256, image_size=16)
    sun = [sm.DirectionalLight(np.array([0.0, 0.0, 1.0]))]
    with pytest.raises(ValueError, match="light_size"):
        render(*args[:1], sun, *args[2:], light_size=[0.01], atlas_size=256)


def test_atlas_pcss_options(gl):
    check_options(lambda *a, **k: render_atlas(*a, **k, ctx=gl))


def test_webgpu_atlas_pcss_options(wgpu_device):
    from shadowmath.render.webgpu import render_atlas_wgpu

    check_options(render_atlas_wgpu)
