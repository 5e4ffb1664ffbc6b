"""Soft shadows from a rectangular area light: seed 003's averaged depth-map shadows
(method="soft") and Heckbert and Herf's radiance textures (method="radiance",
radiance_texture), against the exact visibility of the light.

The scene is a square occluder parallel to the floor under a rectangular light parallel
to both: from a floor point P the occluder projects onto the light's plane as a rectangle
(scaled by h_light / h_occluder about P), so the blocked fraction of the light is the
area of two rectangles' overlap over the light's area (checked against the ray caster).
The averages converge to it as the samples grow, and the umbra and penumbra lie where
that geometry puts them."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from shadowmath.groundtruth import segment_hits_triangles
from shadowmath.meshes import grid
from shadowmath.render import Body, Light, look_at, perspective, radiance_texture, render_scene

from .scenes import edge_band, place, world_mesh

SIZE = (128, 96)
MAP = 256
FLOOR = Body(*grid((8.0, 8.0)), plane=(0.0, 0.0, 1.0, 0.0), color=(0.8, 0.8, 0.8))
OCC_CENTRE, OCC_HALF, OCC_HEIGHT = np.array([0.2, 0.0]), 0.6, 1.5
OCCLUDER = Body(
    *grid((2 * OCC_HALF, 2 * OCC_HALF)),
    to_world=place(translation=(*OCC_CENTRE, OCC_HEIGHT)),
    color=(0.9, 0.4, 0.2),
)
LIGHT_CENTRE, LIGHT_HALF, LIGHT_HEIGHT = np.array([0.0, 0.0]), np.array([0.8, 0.5]), 4.0
LIGHT = Light(
    (*LIGHT_CENTRE, LIGHT_HEIGHT),
    edge_u=(2 * LIGHT_HALF[0], 0.0, 0.0),
    edge_v=(0.0, 2 * LIGHT_HALF[1], 0.0),
)
CAMERA = perspective(50.0, SIZE[0] / SIZE[1], 0.1, 50.0) @ look_at((0, -5, 6), (0, 0, 0), (0, 0, 1))
COUNTS = (4, 16, 64, 256)


def blocked_fraction(points: np.ndarray) -> np.ndarray:
    """The exact fraction of the light hidden by the occluder from floor points (x, y, 0)."""
    k = LIGHT_HEIGHT / OCC_HEIGHT
    p = points[..., :2]
    lo = p + (OCC_CENTRE - OCC_HALF - p) * k  # the occluder seen from p, on the light's plane
    hi = p + (OCC_CENTRE + OCC_HALF - p) * k
    overlap = np.clip(
        np.minimum(hi, LIGHT_CENTRE + LIGHT_HALF) - np.maximum(lo, LIGHT_CENTRE - LIGHT_HALF),
        0.0,
        None,
    )
    result: np.ndarray = overlap.prod(axis=-1) / (4 * LIGHT_HALF.prod())
    return result


def render(method: str, samples: int, **kwargs):
    return render_scene(
        [FLOOR], [OCCLUDER], [LIGHT], CAMERA, image_size=SIZE, map_size=MAP, method=method,
        samples=samples, **kwargs,
    )  # fmt: skip


def floor_error(frame) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(floor pixels, rendered blocked fraction, exact blocked fraction) on the floor."""
    on = frame.body == 0
    exact = np.zeros(on.shape)
    exact[on] = blocked_fraction(frame.position[on].astype(np.float64))
    return on, frame.shadow[..., 0].astype(np.float64), exact


def test_the_exact_fraction_agrees_with_the_ray_caster():
    """Cast rays from floor points to a 24 x 24 grid of points on the light (the midpoint
    rule's error: at most about one grid cell's share along each edge of the overlap)."""
    rng = np.random.default_rng(1)
    points = np.concatenate([rng.uniform(-2.5, 2.5, (300, 2)), np.zeros((300, 1))], axis=1)
    g = (np.arange(24) + 0.5) / 24 - 0.5
    light = [
        (LIGHT_CENTRE[0] + 2 * LIGHT_HALF[0] * u, LIGHT_CENTRE[1] + 2 * LIGHT_HALF[1] * v,
         LIGHT_HEIGHT)
        for u in g for v in g
    ]  # fmt: skip
    v, t = world_mesh(OCCLUDER)
    hits = np.mean([segment_hits_triangles(points, q, v, t) for q in light], axis=0)
    exact = blocked_fraction(points)
    assert (exact == 1).sum() > 10 and ((exact > 0) & (exact < 1)).sum() > 50
    assert np.abs(hits - exact).max() < 2.5 / 24


@pytest.mark.parametrize("method", ["soft", "radiance"])
def test_averaged_shadow_converges_to_the_visibility_of_the_light(gl, method):
    """The mean absolute error of the blocked fraction over the floor's pixels, and over
    its penumbra's (0 < exact < 1), falls at every step from 4 to 256 samples."""
    errors, penumbra_errors = [], []
    for n in COUNTS:
        on, got, exact = floor_error(render(method, n, ctx=gl))
        penumbra = on & (exact > 0) & (exact < 1)
        errors.append(float(np.abs(got - exact)[on].mean()))
        penumbra_errors.append(float(np.abs(got - exact)[penumbra].mean()))
    rows = zip(COUNTS, errors, penumbra_errors, strict=True)
    table = ", ".join(f"{n}: {e:.4f} ({p:.4f})" for n, e, p in rows)
    print(f"{method}: mean absolute error on the floor (penumbra) {table}")
    for e in (errors, penumbra_errors):
        assert all(b < a for a, b in itertools.pairwise(e)), e
        assert e[-1] < 0.25 * e[0], e
    assert errors[-1] < 0.002 and penumbra_errors[-1] < 0.01, (errors, penumbra_errors)


@pytest.mark.parametrize("method", ["soft", "radiance"])
def test_umbra_and_penumbra_lie_where_geometry_puts_them(gl, method):
    on, got, exact = floor_error(render(method, 64, ctx=gl))
    inner = on & ~edge_band(on, 2)  # away from the floor's own silhouette and the occluder's
    umbra = inner & ~edge_band(exact == 1, 2) & (exact == 1)
    lit = inner & ~edge_band(exact == 0, 2) & (exact == 0)
    penumbra = inner & (exact > 0.1) & (exact < 0.9)
    assert umbra.sum() > 50 and lit.sum() > 1000 and penumbra.sum() > 300
    assert (got[umbra] > 0.999).all(), "fully shadowed in the umbra"
    assert (got[lit] < 0.001).all(), "fully lit outside the penumbra"
    assert ((got[penumbra] > 0) & (got[penumbra] < 1)).all(), "partly shadowed in between"
    assert np.abs(got - exact)[penumbra].max() < 0.2


def test_radiance_texture_matches_the_exact_visibility(gl):
    """The floor's texture itself, texel centres against the exact fraction."""
    size = (64, 48)
    vis = radiance_texture(
        (-4.0, -3.0, 0.0), (8.0, 0.0, 0.0), (0.0, 6.0, 0.0), [OCCLUDER], LIGHT,
        samples=64, size=size, ctx=gl,
    )  # fmt: skip
    assert vis.shape == (48, 64) and vis.dtype == np.float32
    u = (np.arange(64) + 0.5) / 64
    v = (np.arange(48) + 0.5) / 48
    points = np.stack(np.broadcast_arrays(-4 + 8 * u[None, :], -3 + 6 * v[:, None], 0.0), -1)
    exact = 1 - blocked_fraction(points)
    assert np.abs(vis - exact).mean() < 0.02
    assert (vis[exact == 1] == 1).all() and vis.min() == 0


def test_soft_frame_and_options(gl):
    frame = render("soft", 4, ctx=gl)
    assert len(frame.setups[0]) == 4 and frame.shadow_maps == ((),)
    frame = render("radiance", 4, ctx=gl)
    assert frame.setups == ((),) and frame.shadow_maps[0][0].shape == (MAP, MAP)
    # the same seed gives the same picture; the mask is a multiple of 1 / samples
    again = render("radiance", 4, ctx=gl)
    np.testing.assert_array_equal(frame.shadow, again.shadow)


@pytest.mark.parametrize(
    ("method", "kwargs", "lights", "match"),
    [
        ("soft", {"samples": 0}, [LIGHT], "samples"),
        ("radiance", {"samples": 2.5}, [LIGHT], "samples"),
        ("soft", {}, [Light((0, 0, 4))], "area light"),
        ("radiance", {}, [Light((0, 0, 4))], "area light"),
        ("soft", {}, [Light((0, 0, 4), edge_u=(1, 0, 0))], "both"),
        ("soft", {}, [Light((0, 0, 4), edge_u=(1, 0, 0), edge_v=(2, 0, 0))], "parallel"),
    ],
)
def test_soft_bad_options(gl, method, kwargs, lights, match):
    with pytest.raises(ValueError, match=match):
        render_scene([FLOOR], [OCCLUDER], lights, CAMERA, image_size=16, method=method,
                     ctx=gl, **kwargs)  # fmt: skip


def test_radiance_needs_planar_receivers(gl):
    with pytest.raises(ValueError, match="plane"):
        render_scene([FLOOR._replace(plane=None)], [OCCLUDER], [LIGHT], CAMERA, image_size=16,
                     method="radiance", ctx=gl)  # fmt: skip
