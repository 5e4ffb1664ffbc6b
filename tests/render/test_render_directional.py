"""Directional lights (``Light(direction=...)``, the homogeneous ``(x, y, z, 0)``) in the
reference render, against the ray caster's unbounded rays toward the light:

* Blinn's planar shadows (``planar_projection(plane, (x, y, z, 0))``) on a floor;
* Williams' depth maps (an orthographic ``fit_shadow((x, y, z, 0), ...)``), whose receivers
  also cast and shadow themselves (a torus above a floor, a box on a floor), beside the same
  scenes under point lights, at several map sizes and PCF radii: no pixel differs outside a
  band of BAND pixels around the edges of the shadow and of the lit region (no acne at the
  documented default bias);
* stable maps (``stable=True``): along a path of small steps of a turning, drifting blocker,
  the texel grid moves by whole texels and its scale stays fixed, and the shadow changes
  only where the blocker's shadow moved; ``stable=False`` shimmers.
"""

from __future__ import annotations

import itertools
from functools import cache

import numpy as np
import pytest

import shadowmath as sm
from shadowmath.meshes import box, torus
from shadowmath.render import Body, Light, render_scene, render_shadow_map
from shadowmath.render._pass_depth import fit_depth
from shadowmath.render._resources import prepare_body

from .depth_scenes import SCENES, DepthScene, compare, homogeneous, ray_cast
from .scenes import edge_band, place, rotation, world_mesh

SIZE = (128, 96)  # the depth scenes' cameras have this aspect (4:3)
CASES = [(128, 0), (256, 1), (512, 2)]  # (map size, PCF radius)
MAX_ALL = 0.01  # edges included, at most 1 % of the visible pixels differ

#: Each depth scene's light as a directional light along the same direction from the origin.
DIRECTIONS = {"torus": (5.0, 1.0, 2.5), "box": (-3.0, -1.5, 3.5)}


def scene_with(name: str, kind: str) -> DepthScene:
    scene = SCENES[name]
    if kind == "point":
        return scene
    return scene._replace(light=Light(direction=DIRECTIONS[name]))


def render(scene: DepthScene, ctx, **kwargs):
    *receivers, blocker = scene.bodies
    return render_scene(
        receivers, [blocker], [scene.light], scene.world_to_clip, image_size=SIZE,
        method="depth", ctx=ctx, **kwargs,
    )  # fmt: skip


@cache
def truth_of(name: str, kind: str, ctx):
    """The ray-cast truth of a scene's per-pixel record (the same for every map and PCF)."""
    scene = scene_with(name, kind)
    frame = render(scene, ctx, map_size=64)
    return ray_cast(frame.body, frame.position, frame.normal, scene)


@pytest.mark.parametrize(("map_size", "pcf"), CASES)
@pytest.mark.parametrize("kind", ["directional", "point"])
@pytest.mark.parametrize("name", list(SCENES))
def test_depth_map_agrees_with_ray_caster(gl, name, kind, map_size, pcf):
    scene = scene_with(name, kind)
    frame = render(scene, gl, map_size=map_size, pcf_radius=pcf)
    truth = truth_of(name, kind, gl)
    count = compare(frame.shadow[..., 0] > 0.5, truth)
    print(f"{name} {kind} map {map_size} pcf {pcf}: {count}")
    assert count.shadowed > 150, "the scene must show a sizeable shadow to test anything"
    if name == "torus":
        assert (truth.shadow & (frame.body == 1)).sum() > 10, "the torus must shadow itself"
    assert count.differ_off_band == 0, count
    assert count.differ <= MAX_ALL * truth.on.sum(), count


def test_directional_depth_map_is_orthographic(gl):
    """The map's clip matrix is affine (no perspective divide), and the depth range holds
    every body (the floor is inside it, nearer than the far plane)."""
    frame = render(scene_with("box", "directional"), gl, map_size=(96, 64))
    (setup,) = frame.setups[0]
    m = np.asarray(setup.blocker_to_clip)
    assert np.allclose(m[3], [0, 0, 0, 1])
    depth = frame.shadow_maps[0][0]
    assert depth.shape == (64, 96)
    assert depth.min() > 0.0 and depth.max() < 1.0


def test_directional_depth_bias_is_what_prevents_acne(gl):
    scene = scene_with("torus", "directional")
    frame = render(scene, gl, map_size=256, depth_bias=(0.0, 0.0))
    count = compare(frame.shadow[..., 0] > 0.5, truth_of("torus", "directional", gl))
    print(f"torus directional, no bias: {count}")
    assert count.acne > 30


# --- Blinn's planar shadows ------------------------------------------------------------

FLOOR = SCENES["torus"].bodies[0]._replace(plane=(0.0, 0.0, 1.0, 0.0))


@pytest.mark.parametrize("name", list(SCENES))
def test_directional_planar_shadow_agrees_with_ray_caster(gl, name):
    scene = scene_with(name, "directional")
    blocker = scene.bodies[-1]
    frame = render_scene(
        [FLOOR], [blocker], [scene.light], scene.world_to_clip, image_size=SIZE,
        method="planar", ctx=gl,
    )  # fmt: skip
    on = frame.body == 0
    p = frame.position[on].astype(np.float64)
    light = homogeneous(scene.light)
    truth = np.zeros(on.shape, dtype=bool)
    truth[on] = sm.groundtruth.segment_hits_triangles(p, light, *world_mesh(blocker))
    shadowed = frame.shadow[..., 0] > 0.5
    wrong = (shadowed != truth) & on
    band = edge_band(truth, 2) | edge_band(on, 2)
    print(f"planar {name} directional: {truth.sum()} shadowed, {wrong.sum()} differ, "
          f"{(wrong & ~band).sum()} off the band")  # fmt: skip
    assert truth.sum() > 150
    assert (wrong & ~band).sum() == 0
    assert wrong.sum() <= MAX_ALL * on.sum()
    assert not shadowed[~on].any(), "the shadow stays on the receiver"


def test_directional_planar_matches_a_far_point_light(gl):
    """A point light far along the direction gives nearly the same planar shadow."""
    scene = scene_with("box", "directional")
    far = Light(1e5 * np.asarray(DIRECTIONS["box"]))
    frames = [
        render_scene(
            [FLOOR], [scene.bodies[-1]], [light], scene.world_to_clip, image_size=SIZE,
            method="planar", ctx=gl,
        ).shadow[..., 0] > 0.5
        for light in (scene.light, far)
    ]  # fmt: skip
    assert frames[0].sum() > 150
    assert (frames[0] != frames[1]).sum() <= 2


# --- errors ----------------------------------------------------------------------------


@pytest.mark.parametrize("method", ["texture", "omni", "soft", "radiance"])
def test_other_methods_refuse_directional_lights(gl, method):
    scene = scene_with("box", "directional")
    with pytest.raises(ValueError, match=r"lights\[0\]\.direction.*'planar' and 'depth'"):
        render_scene(
            [FLOOR], [scene.bodies[-1]], [scene.light], scene.world_to_clip, image_size=32,
            method=method, ctx=gl,
        )  # fmt: skip


@pytest.mark.parametrize(
    ("light", "match"),
    [
        (Light((0, 0, 5), direction=(0, 0, 1)), "not both"),
        (Light(direction=(0, 0, 0)), r"direction: expected finite non-zero"),
        (Light(direction=(0, 0, np.nan)), "direction"),
        (Light(direction=(0, 0, 1), edge_u=(1, 0, 0), edge_v=(0, 1, 0)), "no area"),
        (Light(), "a position .* or a direction"),
    ],
)
def test_bad_directional_lights(gl, light, match):
    scene = SCENES["box"]
    with pytest.raises(ValueError, match=match):
        render_scene([FLOOR], [scene.bodies[-1]], [light], scene.world_to_clip, ctx=gl)


# --- stable maps -----------------------------------------------------------------------

STEPS = 6
MAP = 96
SUN = np.array([0.6, -0.35, 1.0, 0.0])
RING = torus(1.0, 0.35, segments=24, sides=12)
TILT = rotation((1.0, 0.0, 0.0), 35.0)


def drifting_torus(k: int) -> Body:
    """Step k of the path: the torus turns about its own axis (3 degrees a step) and drifts
    (0.011, 0.004) a step; its shape, and so its bounding sphere, does not change."""
    turn = TILT @ rotation((0.0, 0.0, 1.0), 3.0 * k)
    return Body(*RING, to_world=place(turn, (0.011 * k, 0.004 * k, 1.4)), color=(0.9, 0.4, 0.2))


def stable_setup(blockers: list[Body], stable: bool) -> sm.ShadowSetup:
    """The depth pass's fit (receivers clipped to the map's sides), ``stable`` or not."""
    bodies = [prepare_body("body", b) for b in (FLOOR, *blockers)]
    return fit_depth(bodies[:1], bodies[1:], SUN, (MAP, MAP), stable=stable)


def texel_coordinates(setup: sm.ShadowSetup, points: np.ndarray) -> np.ndarray:
    """Map texel coordinates ``(s W, t H)`` of world points (orthographic: q = 1)."""
    stq = np.c_[points, np.ones(len(points))] @ np.asarray(setup.world_to_texture).T
    return stq[:, :2] / stq[:, 3:] * MAP


def test_stable_map_moves_by_whole_texels_and_keeps_its_scale():
    setups = [stable_setup([drifting_torus(k)], True) for k in range(STEPS)]
    probes = np.array([[0.0, 0.0, 0.0], [3.0, -2.0, 0.5], [-1.0, 4.0, 2.0]])
    linear = [np.asarray(s.world_to_texture)[:2, :3] for s in setups]
    for a, b in itertools.pairwise(setups):
        la, lb = np.asarray(a.world_to_texture)[:2, :3], np.asarray(b.world_to_texture)[:2, :3]
        assert np.allclose(la, lb, rtol=0, atol=1e-12 * np.abs(la).max()), "scale fixed"
        shift = texel_coordinates(b, probes) - texel_coordinates(a, probes)
        assert np.allclose(shift, shift[0], atol=1e-9), "a translation of the grid"
        assert np.allclose(shift, np.round(shift), atol=1e-6), f"whole texels: {shift[0]}"
    moved = texel_coordinates(setups[-1], probes[:1]) - texel_coordinates(setups[0], probes[:1])
    print(f"stable: grid moved {moved[0]} texels over the path; scale {linear[0][0]}")
    # without stable=True the extent follows the turning tessellation: the scale changes
    loose = [stable_setup([drifting_torus(k)], False) for k in range(STEPS)]
    scales = [np.linalg.norm(np.asarray(s.world_to_texture)[0, :3]) for s in loose]
    print(f"stable=False: texel scale varies by {np.ptp(scales) / np.mean(scales):.2e}")
    assert np.ptp(scales) > 1e-4 * np.mean(scales)


#: The render path: a torus lying still and a long bar above its centre turning about the
#: vertical through both (2 degrees a step). The vertices' mean and their distances from it
#: do not change, so the stable map does not either, and the torus's shadow must not move;
#: an unstable fit follows the turning bar's extent and rescales the whole map.
STILL = Body(*torus(1.0, 0.35, segments=48, sides=24), to_world=place(None, (0.0, 0.0, 1.0)))
BAR = box((3.6, 0.15, 0.15))


def turning_bar(k: int) -> Body:
    return Body(*BAR, to_world=place(rotation((0.0, 0.0, 1.0), 20.0 + 2.0 * k), (0, 0, 2.0)))


def _bar_texels(gl, frame, k: int) -> np.ndarray:
    """Per pixel: whether its texel, or one next to it, lies under the bar's silhouette in
    the frame's map (the only texels where the bar can change the map)."""
    (setup,) = frame.setups[0]
    v, t = world_mesh(turning_bar(k))
    m = np.asarray(setup.blocker_to_clip) @ np.linalg.inv(np.asarray(setup.blocker_to_world))
    silhouette = render_shadow_map(v, t, m, MAP, ctx=gl) > 0
    silhouette = edge_band(silhouette, 1) | silhouette  # a texel either side
    on = frame.body >= 0
    p = frame.position[on].astype(np.float64)
    stq = np.c_[p, np.ones(len(p))] @ np.asarray(setup.world_to_texture).T
    texel = np.clip(np.floor(stq[:, :2] / stq[:, 3:] * MAP).astype(int), 0, MAP - 1)
    under = np.zeros(on.shape, dtype=bool)
    under[on] = silhouette[texel[:, 1], texel[:, 0]]
    return under


def _changes(gl, stable: bool) -> tuple[int, int]:
    """(pixels changed between consecutive frames, of them outside the swept band: the
    pixels whose texel is under the bar's silhouette in either frame, or that show it)."""
    camera = SCENES["torus"].world_to_clip
    light = Light(direction=SUN[:3])
    frames = [
        render_scene(
            [FLOOR, STILL], [turning_bar(k)], [light], camera, image_size=SIZE, map_size=MAP,
            method="depth", setups=[[stable_setup([STILL, turning_bar(k)], stable)]], ctx=gl,
        )
        for k in range(STEPS)
    ]  # fmt: skip
    total = outside = 0
    for k in range(STEPS - 1):
        fa, fb = frames[k], frames[k + 1]
        changed = (fa.shadow[..., 0] > 0.5) != (fb.shadow[..., 0] > 0.5)
        swept = _bar_texels(gl, fa, k) | _bar_texels(gl, fb, k + 1)
        swept |= (fa.body != fb.body) | (fa.body == 2) | (fb.body == 2)
        total += int(changed.sum())
        outside += int((changed & ~swept).sum())
    return total, outside


def test_stable_path_keeps_the_texel_grid():
    """Along the turning path the stable map's texel grid (its s and t rows) does not
    change at all; only its depth range follows the bar's depth extent."""
    setups = [stable_setup([STILL, turning_bar(k)], True) for k in range(STEPS)]
    first = np.asarray(setups[0].world_to_texture)[:2]
    for s in setups[1:]:
        assert np.allclose(np.asarray(s.world_to_texture)[:2], first, rtol=0, atol=1e-12)
    loose = [stable_setup([STILL, turning_bar(k)], False) for k in range(STEPS)]
    scales = [np.linalg.norm(np.asarray(s.world_to_texture)[0, :3]) for s in loose]
    spread = np.ptp(scales) / np.mean(scales)
    print(f"turning bar, stable=False: texel scale varies by {spread:.2e}")
    assert np.ptp(scales) > 1e-3 * np.mean(scales)


def test_stable_shadow_changes_only_where_the_blocker_moved(gl):
    total, outside = _changes(gl, stable=True)
    loose_total, loose_outside = _changes(gl, stable=False)
    print(
        f"{STEPS - 1} steps, {SIZE[0]}x{SIZE[1]} px, map {MAP}: changed pixels "
        f"stable {total} ({outside} outside the swept band), "
        f"stable=False {loose_total} ({loose_outside} outside)"
    )
    assert outside == 0
    assert loose_outside > 20 and loose_total > total
