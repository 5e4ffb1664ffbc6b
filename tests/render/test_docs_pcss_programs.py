"""The programs of docs/pcss.md (docs/examples/), run as they are on a small scene and
held to the true soft shadow (ray cast, tests/render/pcss_scenes.py's disk), with the
bounds tests/render/test_render_pcss.py argues for casters with depth.

A unit box on the floor under a point light of radius 0.25 (the 2D map, moderngl and
WebGPU, standard and reversed Z: the culling rule turns with the depth's direction), and
under a sun of angular radius 3 degrees through PCSS cascades. Per floor pixel: the
hard-shadow core (no sample of the light's disk reaches it) is dark, the fully lit floor
away from a band along the penumbra is lit, and over the shadow's region the errors and
the penumbra's width are those of the reference renderer's PCSS. The docs' two mistakes
are real: a depth texture that compares, or the map's faces culled the other way, gives
a wrong picture.
"""

from __future__ import annotations

import functools
import importlib
import sys
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
import pytest

from shadowmath.groundtruth import segment_hits_triangles

from . import pcss_scenes as ps
from .test_render_pcss import MEAN_BOUND, P90_BOUND

EXAMPLES = Path(__file__).resolve().parents[2] / "docs" / "examples"
#: The top view of the 2D map's scene: the box and its shadow, 96 x 96 pixels.
TOP = ps.View(-0.25, -0.6, 1.25, 96)
#: Floor pixels within this many pixels of a pixel the light partly reaches are left out
#: of the core's and the lit floor's checks (the map places an edge within half a texel).
EDGE_BAND = 2
#: The cascades' picture, square.
CASCADE_PIXELS = 96


def example(name: str) -> Any:
    """The module docs/examples/``name``.py, imported as the page's reader runs it."""
    if str(EXAMPLES) not in sys.path:
        sys.path.insert(0, str(EXAMPLES))
    return importlib.import_module(name)


class Floor(NamedTuple):
    points: np.ndarray  # (H, W, 3) the floor point on each pixel's line of sight
    visible: np.ndarray  # (H, W) the floor is what the pixel sees


def floor_pixels(world_to_clip: np.ndarray, size: int, eye: np.ndarray) -> Floor:
    """Each pixel's line of sight (row 0 at the bottom, OpenGL's) met with the floor
    ``z = 0``; visible where no caster triangle lies between it and ``eye`` (homogeneous:
    ``w = 0`` the direction toward an orthographic camera)."""
    c = (np.arange(size) + 0.5) / size * 2 - 1
    x, y = np.meshgrid(c, c)
    inverse = np.linalg.inv(world_to_clip)
    ends = []
    for z in (-1.0, 1.0):
        h = np.stack([x, y, np.full_like(x, z), np.ones_like(x)], axis=-1) @ inverse.T
        ends.append(h[..., :3] / h[..., 3:])
    a, b = ends
    t = a[..., 2] / (a[..., 2] - b[..., 2])
    points = a + t[..., None] * (b - a)
    caster = example("pcss_scene").CASTER
    hidden = segment_hits_triangles(points, eye, caster, np.arange(len(caster)).reshape(-1, 3))
    inside = np.all(np.abs(points[..., :2]) < 5.0, axis=-1)
    return Floor(points, inside & ~hidden)


def truth(points: np.ndarray, light: ps.LightCase, axis: np.ndarray | None) -> np.ndarray:
    """``(P,)`` the fraction of the light's disk (facing ``axis``; a sun's cone about its
    direction, ``axis`` unused) each of the points ``(P, 3)`` sees, by
    ``ps.TRUTH_SAMPLES`` rays each."""
    caster = example("pcss_scene").CASTER
    triangles = np.arange(len(caster)).reshape(-1, 3)
    centre = np.asarray(light.where, float)
    if light.kind == "sun":
        axis = centre = centre / np.linalg.norm(centre)
    e1 = np.cross(axis, [0.0, 0.0, 1.0] if abs(axis[2]) < 0.9 else [1.0, 0.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(axis, e1)
    radius = np.tan(light.size) if light.kind == "sun" else light.size
    hidden = np.zeros(points.shape[:-1])
    for u, w in ps.disk_samples(ps.TRUTH_SAMPLES) * radius:
        q = centre + u * e1 + w * e2
        at = np.append(q, 0.0) if light.kind == "sun" else q
        hidden += segment_hits_triangles(points, at, caster, triangles)
    result: np.ndarray = 1.0 - hidden / ps.TRUTH_SAMPLES
    return result


def dilate(mask: np.ndarray, pixels: int) -> np.ndarray:
    out = mask.copy()
    for dy in range(-pixels, pixels + 1):
        for dx in range(-pixels, pixels + 1):
            out |= np.roll(np.roll(mask, dy, axis=0), dx, axis=1)
    return out


def check_against_truth(lit: np.ndarray, floor: Floor, true: np.ndarray) -> ps.Comparison:
    """The core is dark, the lit floor lit (off the edge band), and the errors and width
    within test_render_pcss.py's bounds for casters with depth."""
    c = ps.Comparison(floor.visible, lit, np.where(floor.visible, true, 1.0))
    # the band: along the penumbra, and along the caster's outline (at its foot the map
    # cannot tell the floor from the caster's bottom face: a line of partial light)
    band = dilate((floor.visible & (c.truth > 0) & (c.truth < 1)) | ~floor.visible, EDGE_BAND)
    core = floor.visible & (c.truth == 0) & ~band
    full = floor.visible & (c.truth == 1) & ~band
    assert core.sum() > 200 and full.sum() > 1000, (core.sum(), full.sum())
    assert lit[core].max() < 0.05, lit[core].max()
    assert lit[full].min() == 1.0, lit[full].min()
    e = ps.errors(c)
    assert e.mean < 1.5 * MEAN_BOUND + 0.01 and e.p90 < 1.5 * P90_BOUND, e
    assert 0.8 < ps.width_ratio(c) < 1.05
    return c


#: The lights of the programs (their defaults).
POINT = ps.LightCase("point", (-1.6, 1.4, 4.5), 0.25)
SUN = ps.LightCase("sun", (-1.5, 1.0, 1.0), float(np.radians(3.0)))


@functools.cache
def top_view_truth(axis: tuple[float, float, float]) -> tuple[Floor, np.ndarray]:
    """The floor pixels of ``TOP`` and the point light's true visibility (its disk facing
    the map's ``axis``), 1 off the floor."""
    floor = floor_pixels(TOP.world_to_clip(), TOP.pixels, np.array([0.0, 0.0, 1.0, 0.0]))
    true = np.ones(floor.visible.shape)
    true[floor.visible] = truth(floor.points[floor.visible], POINT, np.array(axis))
    return floor, true


def map_axis(fit: Any) -> tuple[float, float, float]:
    axis = np.asarray(fit.frame.z_axis, dtype=float)
    return float(axis[0]), float(axis[1]), float(axis[2])


def check_box_top_is_lit(lit: np.ndarray, floor: Floor) -> None:
    """Seen from above, every pixel off the floor is the box's top, which nothing shadows:
    lit, off the edge band (the wrong culling compares it with itself: acne)."""
    top = ~dilate(floor.visible, EDGE_BAND)
    assert top.sum() > 500 and lit[top].min() == 1.0, (top.sum(), lit[top].min())


@pytest.mark.parametrize("reversed_z", [False, True])
def test_the_moderngl_program_draws_the_true_soft_shadow(gl, reversed_z):
    program = example("pcss_moderngl")
    picture = program.render(gl, TOP.world_to_clip(), size=TOP.pixels, reversed_z=reversed_z)
    floor, true = top_view_truth(map_axis(picture.fit))
    check_against_truth(picture.lit, floor, true)
    check_box_top_is_lit(picture.lit, floor)


@pytest.mark.parametrize("reversed_z", [False, True])
def test_the_wgpu_program_draws_the_true_soft_shadow(wgpu_device, reversed_z):
    program, camera = example("pcss_wgpu"), TOP.world_to_clip()
    picture = program.render(wgpu_device, camera, size=TOP.pixels, reversed_z=reversed_z)
    lit = np.flipud(picture.lit)  # WebGPU's row 0 is the top: as OpenGL's, row 0 the bottom
    floor, true = top_view_truth(map_axis(picture.fit))
    check_against_truth(lit, floor, true)
    check_box_top_is_lit(lit, floor)


def test_a_comparing_depth_texture_shades_everything_as_shadowed(gl):
    """moderngl's depth textures compare by default; read through a sampler2D the result is
    undefined by OpenGL, and Mesa returns the comparison: no floor pixel is lit at all."""
    program = example("pcss_moderngl")
    picture = program.render(gl, TOP.world_to_clip(), size=TOP.pixels, mistake="compare")
    floor, true = top_view_truth(map_axis(picture.fit))
    lit_floor = floor.visible & (true == 1.0)
    assert lit_floor.sum() > 1000 and picture.lit[lit_floor].max() < 0.5
    with pytest.raises(AssertionError):
        check_against_truth(picture.lit, floor, true)


def test_the_map_culled_the_other_way_shadows_the_lit_box_top(gl):
    """The faces toward the light in the map: the box's top compared with itself."""
    program = example("pcss_moderngl")
    picture = program.render(gl, TOP.world_to_clip(), size=TOP.pixels, mistake="cull")
    floor, _ = top_view_truth(map_axis(picture.fit))
    top = ~dilate(floor.visible, EDGE_BAND)
    assert (picture.lit[top] < 0.9).mean() > 0.2


@functools.cache
def cascade_view_truth(size: int) -> tuple[Floor, np.ndarray, np.ndarray]:
    """The floor pixels of the cascades' camera, the sun's true visibility, and each
    pixel's view depth."""
    scene = example("pcss_scene")
    view = scene.CASCADES_VIEW
    eye = np.append(np.linalg.inv(view)[:3, 3], 1.0)
    floor = floor_pixels(scene.CASCADES_PROJECTION @ view, size, eye)
    true = np.ones(floor.visible.shape)
    true[floor.visible] = truth(floor.points[floor.visible], SUN, None)
    depth = -(floor.points @ view[2, :3] + view[2, 3])
    return floor, true, depth


def check_cascades(lit: np.ndarray, splits: Any) -> None:
    floor, true, depth = cascade_view_truth(lit.shape[0])
    c = check_against_truth(lit, floor, true)
    # the penumbra lies in the first two cascades: both are tested
    cascade = np.searchsorted(np.asarray(splits), depth) - 1
    penumbra = c.floor & (c.truth > 0) & (c.truth < 1)
    assert (penumbra & (cascade == 0)).sum() > 100 and (penumbra & (cascade == 1)).sum() > 100


def test_the_moderngl_cascades_program_draws_the_true_soft_shadow(gl):
    scene, program = example("pcss_scene"), example("pcss_cascades_moderngl")
    camera = scene.CASCADES_VIEW, scene.CASCADES_PROJECTION
    picture = program.render(gl, *camera, size=CASCADE_PIXELS)
    check_cascades(picture.lit, picture.cascades.splits)


def test_the_wgpu_cascades_program_draws_the_true_soft_shadow(wgpu_device):
    scene, program = example("pcss_scene"), example("pcss_cascades_wgpu")
    camera = scene.CASCADES_VIEW, scene.CASCADES_PROJECTION
    picture = program.render(wgpu_device, *camera, size=CASCADE_PIXELS)
    check_cascades(np.flipud(picture.lit), picture.cascades.splits)
