"""A spot light's casters selected per light: clipped to the cone's square pyramid, exactly.

References computed here, independently of the package: a polygon clipped plane by plane
(Sutherland-Hodgman), segments against triangles (Moller-Trumbore), the pyramid from the
returned frame.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import shadowmath as sm
from shadowmath._boundary._validate import convert
from shadowmath._fits.shadow._spot_select import _frame
from shadowmath._math import _spot_casters as sc
from shadowmath.meshes import box

from .test_spot import PATHS

AXIS = np.array([0.0, 0.0, 1.0])


def _clip(poly: list[np.ndarray], planes: np.ndarray) -> list[np.ndarray]:
    """Sutherland-Hodgman: a convex polygon clipped by planes ``(n, d)``, ``n . p + d >= 0``."""
    for plane in planes:
        out = []
        for i, p in enumerate(poly):
            q = poly[(i + 1) % len(poly)]
            gp, gq = plane[:3] @ p + plane[3], plane[:3] @ q + plane[3]
            if gp >= 0:
                out.append(p)
            if (gp >= 0) != (gq >= 0):
                out.append(p + gp / (gp - gq) * (q - p))
        poly = out
        if not poly:
            break
    return poly


def _pyramid(light: np.ndarray, frame: sm.LightFrame) -> np.ndarray:
    """The four side planes ``|x|, |y| <= t z`` from a returned frame (world space)."""
    X, Y, Z = (np.asarray(v, dtype=np.float64) for v in (frame.x_axis, frame.y_axis, frame.z_axis))
    t = np.tan(light[7])
    n = np.array([t * Z - X, t * Z + X, t * Z - Y, t * Z + Y])
    return np.c_[n, -n @ light[:3]]


def _extremes(points: np.ndarray, light: np.ndarray, frame: sm.LightFrame) -> np.ndarray:
    axes = np.stack([frame.x_axis, frame.y_axis, frame.z_axis])
    p = (points - light[:3]) @ axes.T
    u, v = p[:, 0] / p[:, 2], p[:, 1] / p[:, 2]
    return np.array([u.max(), u.min(), v.max(), v.min(), p[:, 2].max(), p[:, 2].min()])


def _spot_row(rng: np.random.Generator) -> np.ndarray:
    angle = rng.uniform(0.1, 1.3)
    return np.r_[rng.normal(size=3), rng.normal(size=3), np.tan(angle), angle]


def test_clipped_candidates_have_the_clipped_polygons_extremes() -> None:
    """2000 random triangles against random pyramids: the valid candidates' ratio and depth
    extremes are the Sutherland-Hodgman polygon's, and a triangle is kept exactly when the
    polygon is not empty."""
    rng = np.random.default_rng(7)
    compared = 0
    for _ in range(2000):
        light = _spot_row(rng)
        ctx, _ = convert(light=light)
        position, axes, t = _frame(ctx, light, None)
        frame = sm.LightFrame(position, *axes)
        planes = sc.pyramid_planes(np, position, axes, t)
        tri = rng.normal(size=(1, 3, 3)) * 2
        got = sc.clip_triangles(np, planes, tri, np.zeros((4, 3)), ctx.eps)
        poly = _clip(list(tri[0]), _pyramid(light, frame))
        area = len(poly) >= 3 and np.linalg.norm(np.cross(poly[1] - poly[0], poly[2] - poly[0]))
        if not area or area < 1e-9:  # empty, or a sliver within rounding of a plane
            continue
        assert int(got.kept) == 1
        np.testing.assert_allclose(
            _extremes(got.points[:-4], light, frame),
            _extremes(np.array(poly), light, frame),
            rtol=1e-10,
            atol=1e-10,
        )
        compared += 1
    assert compared > 500


@pytest.mark.parametrize("path", PATHS)
def test_a_triangle_crossing_the_lights_plane_fits_as_its_part_in_front(path: str) -> None:
    spot = sm.SpotLight(np.array([0.3, -0.2, 0.0]), np.array([0.1, 0.0, 1.0]), np.array(0.5))
    tri = np.array([[[-1.0, -1.0, -2.0], [1.0, -0.5, 3.0], [0.2, 1.0, 4.0]]])
    with PATHS[path]():
        s = sm.fit_shadow(spot, sm.Triangles(tri), 64)
        light = np.r_[spot.position, spot.direction, np.tan(0.5), 0.5]
        part = np.array(_clip(list(tri[0]), _pyramid(light, s.frame)))
        by_hand = sm.fit_shadow(spot, part, 64)
    assert int(s.casters_used) == 1
    assert float(s.frustum.near) > 0
    for a, b in zip(s[2:6], by_hand[2:6], strict=True):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-13)
    # The whole part in front lies in the map; the corner behind the light is clipped (w < 0).
    clip = np.c_[part, np.ones(len(part))] @ s.blocker_to_clip.T
    assert np.all(np.abs(clip[:, :3]) <= clip[:, 3:] * (1 + 1e-12))
    behind = s.blocker_to_clip @ np.append(tri[0, 0], 1.0)
    assert behind[3] < 0


def test_a_placement_gives_the_world_fit() -> None:
    """Planes act on local points through B^T: the same world casters, placed, fit alike."""
    spot = sm.SpotLight(np.zeros(3), AXIS, np.array(0.5))
    tri = np.array([[[-1.0, -1.0, -2.0], [1.0, -0.5, 3.0], [0.2, 1.0, 4.0]]])
    B = np.array([[2, 0.1, 0, 1], [0, 1.5, 0.2, -0.5], [0.1, 0, 1, 0.3], [0, 0, 0, 1.0]])
    local = np.linalg.solve(B[:3, :3], (tri[0] - B[:3, 3]).T).T[None]
    world = sm.fit_shadow(spot, sm.Triangles(tri), 64)
    placed = sm.fit_shadow(spot, sm.Triangles(local), 64, blocker_to_world=B)
    np.testing.assert_allclose(placed.world_to_texture, world.world_to_texture, atol=1e-13)
    np.testing.assert_allclose(placed.blocker_to_clip, world.blocker_to_clip @ B, atol=1e-13)


BOX = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (4, 6)], dtype=float)
CUBE = box((2.0, 2.0, 2.0))  # BOX's surface, about the origin


@pytest.mark.parametrize(
    "spot",
    [
        sm.SpotLight(np.zeros(3), np.array([0.0, 0.0, -1.0]), np.array(0.3)),  # all behind
        sm.SpotLight(np.array([9.0, 0, 0]), AXIS, np.array(0.1)),  # beside, outside the cone
        sm.SpotLight(np.array([0.0, 0, 8]), AXIS, np.array(1.5)),  # wide, all behind
    ],
)
@pytest.mark.parametrize("path", PATHS)
def test_the_old_refusals_give_the_empty_fit(spot: Any, path: str) -> None:
    """Formerly BEHIND_LIGHT / OUTSIDE_CONE: now a finite fit with nothing in its frustum."""
    with PATHS[path]():
        for casters in (BOX, sm.Mesh(CUBE.vertices + [0.0, 0.0, 5.0], CUBE.faces)):
            s = sm.fit_shadow(spot, casters, 64)
            assert int(s.casters_used) == 0
            assert all(np.isfinite(np.asarray(m)).all() for m in s[2:6])
            clip = np.c_[BOX, np.ones(8)] @ s.blocker_to_clip.T
            inside = np.all(np.abs(clip[:, :3]) <= clip[:, 3:], axis=1) & (clip[:, 3] > 0)
            assert not inside.any()
            assert float(s.frustum.near) > 0


def test_the_empty_fit_still_reaches_the_receivers() -> None:
    spot = sm.SpotLight(np.zeros(3), np.array([0.0, 0.0, -1.0]), np.array(0.3))
    floor = np.array([[0.0, 0.0, -20.0], [0.5, 0.5, -30.0]])
    s = sm.fit_shadow(spot, BOX, 64, receivers=floor)
    assert int(s.casters_used) == 0
    assert float(s.frustum.far) >= 30.0


def test_points_keep_a_blocker_that_straddles_the_cone() -> None:
    """Vertices are kept as the fit always read them (their box clipped to the cone's square):
    a box whose corners all lie outside the square, but whose body crosses it, is fitted."""
    spot = sm.SpotLight(np.array([0.5, 0.0, 0.0]), AXIS, np.array(np.arctan(0.2)))
    s = sm.fit_shadow(spot, BOX, 100)
    assert int(s.casters_used) == 8
    # A caster behind the light is dropped from a vertex set, and the rest fits as alone.
    behind = np.concatenate([BOX, [[0.0, 0.0, -3.0]]])
    t = sm.fit_shadow(spot, behind, 100)
    assert int(t.casters_used) == 8
    np.testing.assert_allclose(t.blocker_to_clip, s.blocker_to_clip, rtol=0, atol=0)


def test_a_caster_at_the_light_is_still_refused() -> None:
    spot = sm.SpotLight(BOX[0].copy(), AXIS, np.array(0.3))
    with pytest.raises(ValueError, match="not strictly in front"):
        sm.fit_shadow(spot, BOX, 64)
    bad = BOX.copy()
    bad[3, 2] = np.nan  # a non-finite caster is never dropped silently, even behind the light
    behind = sm.SpotLight(np.zeros(3), -AXIS, np.array(0.3))
    with pytest.raises(ValueError, match="blocker_vertices: contains non-finite"):
        sm.fit_shadow(behind, sm.Triangles(bad[:6].reshape(2, 3, 3)), 64)


def test_jax_jit_and_vmap_equal_numpy() -> None:
    rng = np.random.default_rng(3)
    tris = rng.normal(size=(6, 3, 3)) * 2 + [0, 0, 2]
    positions = rng.normal(size=(5, 3))
    positions[0] = [0.0, 0.0, 9.0]  # everything behind: the empty fit
    spot_axis, angle = np.array([0.1, 0.2, 1.0]), np.array(0.6)

    def fit(p: Any) -> Any:
        light = sm.SpotLight(p, jnp.asarray(spot_axis), jnp.asarray(angle))
        s = sm.fit_shadow(light, sm.Triangles(jnp.asarray(tris)), 64)
        return s.blocker_to_clip, s.casters_used

    clip, used = jax.jit(jax.vmap(fit))(jnp.asarray(positions))  # float64: see conftest
    grads = jax.grad(lambda p: jnp.sum(fit(p)[0]))(jnp.asarray(positions[1]))
    assert bool(jnp.all(jnp.isfinite(grads)))
    for i, p in enumerate(positions):
        ref = sm.fit_shadow(sm.SpotLight(p, spot_axis, angle), sm.Triangles(tris), 64)
        np.testing.assert_allclose(np.asarray(clip[i]), ref.blocker_to_clip, rtol=1e-12, atol=1e-12)
        assert int(used[i]) == int(ref.casters_used)
    assert int(used[0]) == 0


def _hits(origin: np.ndarray, ends: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Moller-Trumbore: the segments ``origin -> ends`` that cross the triangle."""
    e1, e2 = tri[1] - tri[0], tri[2] - tri[0]
    d = ends - origin
    h = np.cross(d, e2)
    a = h @ e1
    ok = np.abs(a) > 1e-14
    f = 1.0 / np.where(ok, a, 1.0)
    s = origin - tri[0]
    u = f * (h @ s)
    q = np.cross(s, e1)
    v = f * (d @ q)
    t = f * (q @ e2)
    return ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t >= 0) & (t <= 1)


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), angle=st.floats(0.05, 1.4))
def test_fuzz_no_dropped_triangle_shadows_a_lit_point(seed: int, angle: float) -> None:
    """Every triangle the selection drops is tested against lit receiver points (inside the
    cone) by segments from the light: none of them is shadowed by it."""
    rng = np.random.default_rng(seed)
    position, direction = rng.normal(size=3), rng.normal(size=3)
    spot = sm.SpotLight(position, direction, np.array(angle))
    tris = position + rng.normal(size=(40, 3, 3)) * rng.uniform(0.2, 3.0)
    light = np.r_[position, direction, np.tan(angle), angle]
    ctx, _ = convert(light=light)
    p, axes, t = _frame(ctx, light, None)
    planes = sc.pyramid_planes(np, p, axes, t)
    kept = [int(sc.clip_triangles(np, planes, tr[None], np.zeros((4, 3)), ctx.eps).kept)
            for tr in tris]  # fmt: skip
    dropped = tris[np.array(kept) == 0]
    # Lit points: directions inside the cone, at distances beyond the triangles.
    u = direction / np.linalg.norm(direction)
    w = rng.normal(size=(2000, 3))
    w -= np.outer(w @ u, u)
    w /= np.linalg.norm(w, axis=1, keepdims=True)
    theta = angle * np.sqrt(rng.uniform(0, 1, size=(2000, 1)))
    rays = np.cos(theta) * u + np.sin(theta) * w
    ends = position + rays * rng.uniform(0.1, 20.0, size=(2000, 1))
    for tri in dropped:
        assert not _hits(position, ends, tri).any()
    s = sm.fit_shadow(spot, sm.Triangles(tris), 64)
    assert int(s.casters_used) == sum(kept)


def test_fit_atlas_fits_every_other_light_and_reports_the_failed_one() -> None:
    """A shared caster set behind one spot gives it the empty fit (no error); a cube light at
    a caster's corner is reported and its tiles draw nothing and sample lit, while every
    other light's tiles are those of the atlas without it."""
    tris = np.array([CUBE.vertices[CUBE.faces] + [0.0, 0.0, 5.0]])[0]
    casters = sm.Triangles(tris)
    good = [
        sm.SpotLight(np.zeros(3), AXIS, np.array(0.4)),
        sm.SpotLight(np.zeros(3), -AXIS, np.array(0.4)),  # every caster behind it
        sm.PointLight(np.array([3.0, 0.0, 5.0])),
        sm.DirectionalLight(np.array([0.2, 0.1, -1.0])),
    ]
    cube = [False, False, True, False]
    atlas = sm.allocate_atlas([0.5] * 4, atlas_size=2048, cube=cube)
    ref = sm.fit_atlas(good, casters, atlas)
    assert ref.light_errors == (None,) * 4
    bad = [*good[:2], sm.PointLight(tris[0, 0].copy()), good[3]]
    got = sm.fit_atlas(bad, casters, atlas)
    assert got.light_errors[:2] == (None, None) and got.light_errors[3] is None
    assert (
        got.light_errors[2] is not None and "caster lies at the cube light" in got.light_errors[2]
    )
    mine = atlas.tile_light == 2
    np.testing.assert_array_equal(got.world_to_clip[~mine], ref.world_to_clip[~mine])
    np.testing.assert_array_equal(got.world_to_texture[~mine], ref.world_to_texture[~mine])
    points = np.c_[np.random.default_rng(0).normal(size=(50, 3)) * 5, np.ones(50)]
    clip = points @ got.world_to_clip[mine].transpose(0, 2, 1)
    assert np.all(clip[..., 2] < -clip[..., 3])  # before the near plane: nothing drawn
    tex = points @ got.world_to_texture[mine].transpose(0, 2, 1)
    assert np.all(tex[..., 2] / tex[..., 3] < 0)  # sampled depth below 0: lit
    assert np.all(got.near[mine] == 0) and np.all(got.far[mine] == 0)
    # The spot with everything behind it: a finite fit whose frustum holds no caster.
    tile = int(atlas.light_tiles[1, 0])
    c = np.c_[tris.reshape(-1, 3), np.ones(tris.size // 3)] @ got.world_to_clip[tile].T
    assert np.isfinite(got.world_to_clip[tile]).all()
    assert not np.any(np.all(np.abs(c[:, :3]) <= c[:, 3:], axis=1) & (c[:, 3] > 0))


@pytest.mark.parametrize("path", PATHS)
def test_fit_atlas_reports_on_every_path(path: str) -> None:
    lights = [sm.PointLight(BOX[0].copy()), sm.SpotLight(np.zeros(3), AXIS, np.array(0.3))]
    atlas = sm.allocate_atlas([0.5, 0.5], atlas_size=1024)
    with PATHS[path]():
        fit = sm.fit_atlas(lights, BOX, atlas)
    assert fit.light_errors[1] is None
    assert fit.light_errors[0] is not None and "not strictly in front" in fit.light_errors[0]
    assert np.isfinite(fit.world_to_clip).all()


def test_a_non_finite_frame_drops_nothing_so_the_fit_names_the_cause() -> None:
    spot = sm.SpotLight(np.zeros(3), -AXIS, np.array(0.3))  # every caster behind it
    for casters in (BOX, sm.Triangles(BOX[:6].reshape(2, 3, 3))):
        with pytest.raises(ValueError, match=r"^up: contains non-finite"):
            sm.fit_shadow(spot, casters, 64, up=np.array([np.nan, 1.0, 0.0]))
        with pytest.raises(ValueError, match=r"^light: contains non-finite"):
            sm.fit_shadow(spot._replace(position=np.array([0.0, np.inf, 0.0])), casters, 64)
        B = np.eye(4)
        B[0, 3] = np.nan
        with pytest.raises(ValueError, match=r"^blocker_to_world: contains non-finite"):
            sm.fit_shadow(spot, casters, 64, blocker_to_world=B)


def test_points_rounding_cannot_tell_are_kept_as_the_fit_read_them():
    """A tiny float32 spot scene placed 2 units from its local origin (found by the fuzz
    on a fresh clone): the planes in local coordinates carry rounding larger than the
    points' distances from them, so no point is dropped on that noise; the float32 fit
    keeps all 15 points and agrees with float64 to the scene's float32 conditioning."""
    a, b = -3.44418295e-07, 4.82185613e-06
    z = [-1.99999966, -2.00000999, -1.99999449]
    local = np.array([[a, a, z[0]]] * 11 + [[a, a, z[1]], [b, a, z[0]], [a, b, z[0]], [a, a, z[2]]])
    B = np.eye(4)
    B[2, 3] = 2.0
    fits = {}
    for dtype in (np.float32, np.float64):
        light = sm.SpotLight(
            np.full(3, -1.15470054e-05, dtype), np.full(3, 1.15470054e-05, dtype),
            dtype(np.pi / 12),
        )  # fmt: skip
        fits[dtype] = sm.fit_shadow(
            light, local.astype(dtype), 16, blocker_to_world=B.astype(dtype)
        )
    assert int(fits[np.float32].casters_used) == int(fits[np.float64].casters_used) == 15
    f32, f64 = fits[np.float32].frustum, fits[np.float64].frustum
    for name in ("rx_max", "ry_max", "near", "far"):
        assert np.isclose(float(getattr(f32, name)), float(getattr(f64, name)), rtol=0.05), name
