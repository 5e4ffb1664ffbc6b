"""PCSS through a point light's cube map (``method="omni"`` with ``light_size``) against
the true soft shadow of a light disk of that radius (tests/render/pcss_scenes.py), seen
from straight above.

The floor's shadows here fall on the cube's ``-Z`` face, whose plane is the light disk's
(the truth's disk faces ``-Z``). The sampling bounds are those of
tests/render/test_render_pcss.py (64 filter taps of a Vogel disk rotated per pixel, a
256-sample truth, an edge within half a texel): a horizontal slab is PCSS's exact case,
mean error below 0.015, 90th percentile below 0.05, the penumbra's width within 10%;
with the radius doubled or halved (``K`` scaled) both fail clearly. A box and a tall
pillar add the flat-blocker assumption's error.
"""

from __future__ import annotations

import numpy as np
import pytest

from shadowmath.render import Light, render_scene

from . import pcss_scenes as ps
from .test_render_pcss import MEAN_BOUND, P90_BOUND

POINT = ps.LIGHTS["point"]
FACE_AXIS = (0.0, 0.0, -1.0)


def compare(scene: str, radius: float, gl) -> ps.Comparison:
    frame = render_scene(
        [ps.FLOOR], [ps.CASTERS[scene]], [Light(POINT.where)], ps.VIEWS["top"].world_to_clip(),
        image_size=ps.VIEWS["top"].pixels, map_size=ps.MAP, method="omni",
        light_size=radius, ctx=gl,
    )  # fmt: skip
    floor = frame.body == 0
    truth = ps.truth_image(scene, "point", "top", FACE_AXIS)
    return ps.Comparison(
        floor, 1.0 - frame.shadow[..., 0].astype(np.float64), np.where(floor, truth, 1.0)
    )


def test_a_flat_blocker_matches_the_true_soft_shadow(gl):
    c = compare("slab", POINT.size, gl)
    e = ps.errors(c)
    assert e.pixels > 300
    assert e.mean < MEAN_BOUND and e.p90 < P90_BOUND, e
    assert 0.9 < ps.width_ratio(c) < 1.1


@pytest.mark.parametrize("factor", [2.0, 0.5])
def test_the_wrong_light_size_is_clearly_worse(gl, factor):
    right = ps.errors(compare("slab", POINT.size, gl))
    c = compare("slab", factor * POINT.size, gl)
    wrong = ps.errors(c)
    assert wrong.mean > max(2 * MEAN_BOUND, 2 * right.mean), (right, wrong)
    assert not 0.9 < ps.width_ratio(c) < 1.1


@pytest.mark.parametrize("scene", ["box", "pillar"])
def test_casters_with_depth_stay_near_the_truth(gl, scene):
    """As with a 2D map: the search averages every blocker it finds, so the penumbrae
    come out narrower than the truth's, by up to 20%."""
    c = compare(scene, POINT.size, gl)
    e = ps.errors(c)
    assert e.mean < 1.5 * MEAN_BOUND + 0.01 and e.p90 < 1.5 * P90_BOUND, e
    assert 0.8 < ps.width_ratio(c) < 1.05


def test_omni_pcss_options(gl):
    """``light_size=0`` is the hard cube-map shadow; a bad size is refused."""
    hard = compare("box", 0.0, gl)
    assert set(np.unique(hard.pcss[hard.floor])) == {0.0, 1.0}
    for bad in (-0.1, float("nan"), "big"):
        with pytest.raises(ValueError, match="light_size"):
            render_scene([ps.FLOOR], [ps.CASTERS["box"]], [Light(POINT.where)], np.eye(4),
                         method="omni", light_size=bad, ctx=gl)  # fmt: skip


def near_an_edge(mask: np.ndarray, pixels: int = 2) -> np.ndarray:
    """Where ``mask`` differs from a pixel within ``pixels`` rows and columns of it."""
    band = np.zeros_like(mask)
    for dy in range(-pixels, pixels + 1):
        for dx in range(-pixels, pixels + 1):
            band |= mask != np.roll(mask, (dy, dx), axis=(0, 1))
    return band


def test_every_face_agrees_with_the_hard_cube_map(gl):
    """A light of radius 1e-3 (a search under a texel) shadows what the hard cube pass
    shadows, on every face that sees the floor (the lights low beside the casters cast
    onto the +X, -X, +Y, -Y and -Z faces), but for the pixels beside the shadow's edge
    (the maps hold different faces of the casters)."""
    seen = set()
    for where in [(-1.6, 1.4, 1.5), (0.9, -1.2, 1.3), (-0.5, -0.3, 1.6)]:
        for scene in ("box", "pillar"):
            args = ([ps.FLOOR], [ps.CASTERS[scene]], [Light(where)])
            kw = {"image_size": 160, "map_size": 256, "method": "omni", "ctx": gl}
            camera = ps.VIEWS["top"].world_to_clip()
            hard = render_scene(*args, camera, **kw)
            soft = render_scene(*args, camera, light_size=1e-3, **kw).shadow[..., 0] > 0.5
            shadowed, floor = hard.shadow[..., 0] > 0.5, hard.body == 0
            assert not ((soft != shadowed) & floor & ~near_an_edge(shadowed)).any(), (where, scene)
            r = ps.VIEWS["top"].floor_points()[shadowed & floor] - where
            axis = np.abs(r).argmax(axis=-1)
            seen |= set(2 * axis + (r[np.arange(len(r)), axis] < 0))
    assert seen == {0, 1, 2, 3, 5}
