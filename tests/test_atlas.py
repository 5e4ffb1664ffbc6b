"""The shadow atlas: allocation rule, tile geometry, borders, APIs, stability, errors.

References are written here from the rules' statements (Godot's next power of two,
each API's viewport and depth-range rules, the cube selection table through
``sm.cube_face``), and the per-tile matrices are compared with independent
``sm.fit_shadow`` / ``sm.cube_face_projection`` calls, never with the atlas's own output.
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

import jax.numpy as jnp
import numpy as np
import pytest

import shadowmath as sm
from shadowmath._backends import _kernels
from shadowmath._fits.atlas._allocate import ShadowAtlas, allocate_atlas
from shadowmath._fits.atlas._door import fit_atlas
from shadowmath._fits.atlas._viewports import atlas_tile_transforms, atlas_viewports

APIS: tuple[Any, ...] = ("opengl", "vulkan", "direct3d", "metal", "webgpu")


# ------------------------------------------------------------------ helpers


def box(centre: Any, half: Any) -> np.ndarray:
    c, h = np.asarray(centre, float), np.asarray(half, float)
    return np.array([c + h * [x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])


def scene(seed: int = 0) -> tuple[np.ndarray, list[Any], np.ndarray]:
    """Casters (boxes near the origin) and 12 lights: cube points, spots, points, suns."""
    rng = np.random.default_rng(seed)
    verts = np.concatenate(
        [box(rng.uniform(-3, 3, 3) * [1, 0.2, 1] + [0, 1, 0], rng.uniform(0.3, 0.8, 3))
         for _ in range(6)]
    )  # fmt: skip
    lights: list[Any] = []
    cube = []
    for i in range(12):
        kind = i % 4
        if kind == 0:  # a cube light among the casters (never at a vertex)
            lights.append(sm.PointLight(rng.uniform(-4, 4, 3) * [1, 0, 1] + [0, 4.5, 0]))
        elif kind == 1:  # a spot whose cone holds every caster
            p = rng.uniform(-2, 2, 3) * [1, 0, 1] + [0, 15, 0]
            lights.append(sm.SpotLight(p, -p, np.array(0.9)))
        elif kind == 2:  # a 2D point light far above
            lights.append(sm.PointLight(rng.uniform(-3, 3, 3) * [1, 0, 1] + [0, 25, 0]))
        else:
            lights.append(sm.DirectionalLight(np.array([rng.uniform(-0.5, 0.5), 1, 0.3])))
        cube.append(kind == 0)
    return verts, lights, np.array(cube)


def tiles_disjoint(a: ShadowAtlas) -> bool:
    x, y, n = a.tile_rect.T
    for i in range(len(x)):
        sep = (x[i] + n[i] <= x) | (x + n <= x[i]) | (y[i] + n[i] <= y) | (y + n <= y[i])
        sep[i] = True
        if not sep.all():
            return False
    return True


def check_layout(a: ShadowAtlas) -> None:
    x, y, n = a.tile_rect.T
    A = a.atlas_size
    assert np.all((n & (n - 1)) == 0) and np.all(n > 0)  # powers of two
    assert np.all(x % n == 0) and np.all(y % n == 0)  # quadtree nodes
    assert np.all((x >= 0) & (y >= 0) & (x + n <= A) & (y + n <= A))
    assert tiles_disjoint(a)
    assert a.used == pytest.approx(float((n.astype(float) ** 2).sum()) / A**2, rel=1e-12)
    for t, (light, face) in enumerate(zip(a.tile_light, a.tile_face, strict=True)):
        assert a.light_tiles[light, face] == t
        assert n[t] == a.light_size[light]
    faces = np.where(a.light_cube, 6, 1) * (a.light_size > 0)
    assert np.array_equal((a.light_tiles >= 0).sum(axis=1), faces)


def godot_class(c: float, max_tile: int, min_tile: int) -> int:
    """Godot's ``next_power_of_2(quad_size * coverage)``, clamped (a power by repeated doubling)."""
    if c == 0:
        return 0
    size = 1
    while size < c * max_tile:
        size *= 2
    return min(max(size, min_tile), max_tile)


def window(api: str, clip: np.ndarray, port: np.ndarray) -> tuple[np.ndarray, ...]:
    """Where each API's rasterizer puts clip coordinates: column, row in memory, depth stored."""
    ndc = clip[:, :3] / clip[:, 3:]
    x0, y0, w, h = (float(v) for v in port)
    col = x0 + (ndc[:, 0] + 1) / 2 * w
    if api in ("opengl", "vulkan"):  # GL: row from the bottom = first row; Vulkan: y down
        row = y0 + (ndc[:, 1] + 1) / 2 * h
    else:  # viewport y from the top (the first row), NDC y = +1 there
        row = y0 + (1 - ndc[:, 1]) / 2 * h
    depth = (ndc[:, 2] + 1) / 2 if api == "opengl" else ndc[:, 2]
    return col, row, depth


def inside_points(verts: np.ndarray, count: int, rng: np.random.Generator) -> np.ndarray:
    """Strictly convex combinations of the casters: inside their hull."""
    w = rng.uniform(0.05, 1.0, (count, len(verts))) ** 4
    return np.asarray((w / w.sum(axis=1, keepdims=True)) @ verts)


def homogeneous(p: np.ndarray) -> np.ndarray:
    return np.asarray(np.c_[p, np.ones(len(p))])


# ------------------------------------------------------------------ allocation


def test_sizes_follow_godots_rule() -> None:
    cov = np.array([1.0, 0.5, 0.26, 0.25, 0.1, 0.01, 0.0, 3.0, 0.126])
    a = allocate_atlas(cov, atlas_size=2048, min_tile=32, hysteresis=0.0)
    expected = [godot_class(c, 1024, 32) for c in cov]
    assert a.light_size.tolist() == expected
    assert expected[:4] == [1024, 512, 512, 256]  # 0.25 * 1024 is a power: its own class
    check_layout(a)


def test_layout_is_a_valid_quadtree_for_random_wishes() -> None:
    rng = np.random.default_rng(4)
    for _ in range(30):
        L = int(rng.integers(1, 60))
        cov = rng.uniform(0, 1, L) ** 3
        cube = rng.uniform(size=L) < 0.3
        border = rng.integers(0, 4, L)
        a = allocate_atlas(cov, atlas_size=2048, cube=cube, border_texels=border, min_tile=16)
        check_layout(a)
        assert a.used <= 1.0


def test_budget_halves_the_least_covering_first() -> None:
    # Four wishes of 512 in a 1024 atlas (the whole atlas) under a budget of 3/4: light 3
    # (least: same class, larger id) halves (13/16 left over budget), then light 2 (10/16).
    a = allocate_atlas([0.9, 0.8, 0.7, 0.6], atlas_size=1024, budget=0.75)
    assert a.light_size.tolist() == [512, 512, 256, 256]
    assert a.used == pytest.approx(0.625)
    # A tighter budget: rounds go on. In cells of 128 the wishes 512, 256, 128, 128 take
    # 16 + 4 + 1 + 1 = 22 of a budget of 4: round 1 halves lights 1 (19) and 0 (7; lights 3
    # and 2 are at min_tile); round 2 light 1 is at min_tile, light 0 halves (4).
    b = allocate_atlas([0.9, 0.5, 0.2, 0.1], atlas_size=1024, min_tile=128, budget=1 / 16)
    assert b.light_size.tolist() == [128, 128, 128, 128]
    # Below one min_tile per light, lights drop, the least covering first: 6 lights at 128
    # in 4 cells; lights 2, 3, 4 wished 128 (the least), 4 and 3 (larger ids) drop.
    c = allocate_atlas([0.9, 0.5, 0.2, 0.1, 0.05, 0.3], atlas_size=1024, min_tile=128,
                       budget=1 / 16)  # fmt: skip
    assert c.light_size.tolist() == [128, 128, 128, 0, 0, 128]
    check_layout(c)


def test_budget_keeps_sizes_monotone_in_priority() -> None:
    rng = np.random.default_rng(7)
    for _ in range(40):
        L = int(rng.integers(2, 40))
        cov = rng.uniform(0, 1, L) ** 2
        cube = rng.uniform(size=L) < 0.25
        budget = float(rng.uniform(0.05, 1.0))
        a = allocate_atlas(cov, atlas_size=1024, cube=cube, min_tile=16, budget=budget)
        area = (a.light_size.astype(float) ** 2 * np.where(cube, 6, 1)).sum() / 1024**2
        assert area <= budget + 1e-12
        wished = (a.light_wish.astype(float) ** 2 * np.where(cube, 6, 1)).sum() / 1024**2
        if wished <= budget:
            assert np.array_equal(a.light_size, a.light_wish)
        for i in range(L):  # a light ahead in priority never gets the smaller tile
            ahead = (a.light_wish > a.light_wish[i]) | (
                (a.light_wish == a.light_wish[i]) & (np.arange(L) < i)
            )
            assert np.all(a.light_size[ahead] >= a.light_size[i])
        check_layout(a)


def test_allocation_is_deterministic() -> None:
    rng = np.random.default_rng(1)
    cov = rng.uniform(0, 1, 40) ** 2
    cube = rng.uniform(size=40) < 0.3
    a = allocate_atlas(cov, atlas_size=4096, cube=cube, border_texels=2, budget=0.6)
    b = allocate_atlas(cov.copy(), atlas_size=4096, cube=cube.copy(), border_texels=2, budget=0.6)
    for x, y in zip(a, b, strict=True):
        assert np.array_equal(np.asarray(x), np.asarray(y))


def frames(seed: int, count: int, top: float = 0.6) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    return rng.uniform(0.02, top, count) ** 1.5, rng.uniform(size=count) < 0.3


def test_small_motion_moves_no_tile() -> None:
    cov, cube = frames(2, 48)
    a = allocate_atlas(cov, atlas_size=4096, cube=cube, budget=0.7)
    rng = np.random.default_rng(3)
    for _ in range(10):  # coverage noise of 3 %, inside the 10 % hysteresis
        b = allocate_atlas(cov * rng.uniform(0.97, 1.03, cov.size), atlas_size=4096, cube=cube,
                           budget=0.7, previous=a)  # fmt: skip
        assert np.array_equal(b.light_size, a.light_size)
        assert not b.moved.any()
        assert np.array_equal(b.tile_rect, a.tile_rect)
        a = b


def test_hysteresis_holds_a_class_boundary() -> None:
    a = allocate_atlas([0.5], atlas_size=1024)  # 256
    assert allocate_atlas([0.54], atlas_size=1024, previous=a).light_size.tolist() == [256]
    assert allocate_atlas([0.56], atlas_size=1024, previous=a).light_size.tolist() == [512]
    assert allocate_atlas([0.23], atlas_size=1024, previous=a).light_size.tolist() == [256]
    assert allocate_atlas([0.22], atlas_size=1024, previous=a).light_size.tolist() == [128]
    assert allocate_atlas([0.54], atlas_size=1024, hysteresis=0.0, previous=a).light_size[0] == 512


def assert_only_moved(a: ShadowAtlas, b: ShadowAtlas, changed: set[int]) -> None:
    """Every light of ``b`` not in ``changed`` kept its rects from ``a`` (matched by id);
    ``moved`` says so unless the tile's index shifted (lights before it left or came)."""
    for light, ident in enumerate(b.light_ids):
        tiles = b.light_tiles[light][b.light_tiles[light] >= 0]
        if int(ident) in changed:
            assert b.moved[tiles].all()
            continue
        old = int(np.flatnonzero(a.light_ids == ident)[0])
        old_tiles = a.light_tiles[old][a.light_tiles[old] >= 0]
        assert np.array_equal(b.previous_index[tiles], old_tiles)
        assert np.array_equal(b.tile_rect[tiles], a.tile_rect[old_tiles])
        assert np.array_equal(b.moved[tiles], old_tiles != tiles)


def test_a_light_changing_class_moves_only_itself() -> None:
    cov, cube = frames(5, 24, top=0.3)
    a = allocate_atlas(cov, atlas_size=4096, cube=cube)
    assert a.used < 0.5
    for i in (0, 3, 7):
        c = cov.copy()
        c[i] = 0.25 if a.light_size[i] != 512 else 0.06  # to 512, or to 128
        b = allocate_atlas(c, atlas_size=4096, cube=cube, previous=a)
        assert b.light_size[i] != a.light_size[i]
        assert not b.repacked
        assert_only_moved(a, b, {i})
        check_layout(b)


def test_lights_appearing_and_disappearing_move_no_other() -> None:
    cov, cube = frames(6, 20, top=0.3)
    ids = np.arange(100, 120)
    a = allocate_atlas(cov, atlas_size=4096, cube=cube, light_ids=ids)
    assert a.used < 0.5
    keep = np.ones(20, dtype=bool)
    keep[[2, 9, 15]] = False  # three lights leave, two new ones come, order shuffled
    new_cov = np.r_[cov[keep], 0.3, 0.05]
    new_ids = np.r_[ids[keep], 7, 8]
    new_cube = np.r_[cube[keep], True, False]
    perm = np.random.default_rng(0).permutation(new_ids.size)
    b = allocate_atlas(new_cov[perm], atlas_size=4096, cube=new_cube[perm],
                       light_ids=new_ids[perm], previous=a)  # fmt: skip
    assert_only_moved(a, b, {7, 8})
    check_layout(b)


def test_new_tiles_take_the_best_fitting_hole() -> None:
    # 4 x 4 cells of 64 texels. Frame 1 (fresh, Morton order, largest first): light 0's
    # 128-tile covers cells (0..1, 0..1), lights 1, 2, 3 the cells (2, 0), (3, 0), (2, 1).
    a = allocate_atlas([1.0, 0.4, 0.4, 0.4], atlas_size=256, min_tile=64, max_tile=128)
    assert a.tile_rect.tolist() == [[0, 0, 128], [128, 0, 64], [192, 0, 64], [128, 64, 64]]
    # Light 0 leaves and a 64-tile comes: the lowest free cell is (0, 0), in a whole free
    # 2 x 2 node; the best fit is the last hole of the used node: cell (3, 1).
    b = allocate_atlas([0.4, 0.4, 0.4, 0.4], atlas_size=256, min_tile=64, max_tile=128,
                       light_ids=[1, 2, 3, 4], previous=a)  # fmt: skip
    assert b.tile_rect[3].tolist() == [192, 64, 64]
    assert b.tile_rect[:3].tolist() == a.tile_rect[1:].tolist()  # kept, one index down
    assert b.previous_index.tolist() == [1, 2, 3, -1]
    assert b.moved.tolist() == [True, True, True, True]  # every index names another tile


def test_fragmentation_falls_back_to_a_repack() -> None:
    # 16 lights of 256 fill a 1024 atlas; the odd ones leave, freeing a checkerboard of
    # 256-tiles that holds no 512: the newcomer needs the repack.
    a = allocate_atlas(np.full(16, 0.5), atlas_size=1024, min_tile=64, max_tile=512)
    assert a.used == 1.0
    cov = np.r_[np.full(8, 0.5), 1.0]
    ids = np.r_[np.arange(0, 16, 2), 99]
    b = allocate_atlas(cov, atlas_size=1024, min_tile=64, max_tile=512, light_ids=ids, previous=a)
    kept = a.tile_rect[::2] // 512  # every 512-node holds a kept tile: no room for a 512
    assert {(int(x), int(y)) for x, y, _ in kept} == {(0, 0), (1, 0), (0, 1), (1, 1)}
    assert b.light_size.tolist() == [256] * 8 + [512]
    assert b.repacked
    check_layout(b)


# ------------------------------------------------------------------ conventions


def test_viewports_and_tile_transforms_are_the_rects() -> None:
    a = allocate_atlas([1.0, 0.3, 0.05], atlas_size=1024, cube=[False, False, True])
    A = 1024
    for api in APIS:
        ports = atlas_viewports(a, api=api)
        assert np.array_equal(ports, np.c_[a.tile_rect, a.tile_rect[:, 2]])
        T = atlas_tile_transforms(a, api=api)
        for t, (x, y, n) in enumerate(a.tile_rect):
            for s, tt in ((0, 0), (1, 1), (0.25, 0.75)):  # a tile coordinate lands at x + n s
                q = 2.5
                out = T[t] @ [s * q, tt * q, 0.3 * q, q]
                assert out[:2] / out[3] == pytest.approx([(x + n * s) / A, (y + n * tt) / A])
                assert out[2:] == pytest.approx([0.3 * q, q])
    clamp = a.tile_clamp * A
    assert np.allclose(clamp[:, :2], a.tile_rect[:, :2] + 0.5)
    assert np.allclose(clamp[:, 2:], a.tile_rect[:, :2] + a.tile_rect[:, 2:] - 0.5)


@pytest.mark.parametrize("api", APIS)
@pytest.mark.parametrize("reversed_z", [False, True])
def test_every_tile_samples_where_it_was_drawn(api: Any, reversed_z: bool) -> None:
    verts, lights, cube = scene(1)
    rng = np.random.default_rng(2)
    cov = rng.uniform(0.05, 0.7, len(lights))
    a = allocate_atlas(cov, atlas_size=4096, cube=cube, border_texels=2)
    fit = fit_atlas(lights, verts, a, api=api, reversed_z=reversed_z)
    assert np.array_equal(fit.viewports, atlas_viewports(a, api=api))
    A = a.atlas_size
    for t in range(len(a.tile_light)):
        light = lights[a.tile_light[t]]
        if a.tile_face[t] == 0 and not cube[a.tile_light[t]]:
            p = inside_points(verts, 50, rng)
        else:  # directions that select this face, at distances between the casters'
            d = rng.normal(size=(400, 3))
            d = d[sm.cube_face(d).face == a.tile_face[t]]
            p = np.asarray(light.position) + d / np.abs(d).max(axis=1, keepdims=True) * 2.0
        clip = (fit.world_to_clip[t] @ homogeneous(p).T).T
        col, row, depth = window(api, clip, fit.viewports[t])
        tex = (fit.world_to_texture[t] @ homogeneous(p).T).T
        st = tex[:, :3] / tex[:, 3:]
        assert np.allclose(st[:, 0] * A, col, atol=1e-7)
        assert np.allclose(st[:, 1] * A, row, atol=1e-7)
        assert np.allclose(st[:, 2], depth, atol=1e-9)
        x, y, n = a.tile_rect[t]
        assert np.all((col >= x) & (col <= x + n) & (row >= y) & (row <= y + n))


def independent_fit(light: Any, verts: np.ndarray, size: int, border: int, **kw: Any) -> Any:
    return sm.fit_shadow(light, verts, size, border_texels=border, **kw)


def tile_matrix(rect: np.ndarray, A: int) -> np.ndarray:
    x, y, n = (float(v) for v in rect)
    return np.array([[n / A, 0, 0, x / A], [0, n / A, 0, y / A], [0, 0, 1, 0], [0, 0, 0, 1]])


@pytest.mark.parametrize("api", APIS)
def test_tiles_equal_independent_per_light_fits(api: Any) -> None:
    verts, lights, cube = scene(3)
    border = np.arange(len(lights)) % 3 + 1
    cov = np.linspace(0.8, 0.1, len(lights))
    a = allocate_atlas(cov, atlas_size=4096, cube=cube, border_texels=border)
    fit = fit_atlas(lights, verts, a, api=api)
    for light_index, light in enumerate(lights):
        n, b = int(a.light_size[light_index]), int(border[light_index])
        if not cube[light_index]:
            t = a.light_tiles[light_index, 0]
            ref = independent_fit(light, verts, n, b, api=api)
            assert np.allclose(fit.world_to_clip[t], ref.blocker_to_clip, rtol=1e-12, atol=1e-12)
            expected = tile_matrix(a.tile_rect[t], a.atlas_size) @ ref.world_to_texture
            assert np.allclose(fit.world_to_texture[t], expected, rtol=1e-12, atol=1e-12)
            continue
        L = np.asarray(light.position)
        D = np.abs(verts - L).max(axis=1)
        k = (n - 2 * b) / n
        near, far = k * D.min() * (1 - 1 / 64), D.max() * (1 + 1 / 64)
        P = sm.cube_face_projection(near, far, map_size=n, border_texels=b, api=api)
        V = sm.cube_face_views(L)
        T_api = sm.api_convention(api=api).clip_to_texture
        for face in range(6):
            t = a.light_tiles[light_index, face]
            assert np.allclose(fit.world_to_clip[t], P @ V[face], rtol=1e-12, atol=1e-12)
            expected = tile_matrix(a.tile_rect[t], a.atlas_size) @ T_api @ P @ V[face]
            assert np.allclose(fit.world_to_texture[t], expected, rtol=1e-12, atol=1e-12)


FLOOR = np.array(
    [[-30.0, -1.0, -30.0], [30.0, -1.0, -30.0], [30.0, -1.0, 30.0], [-30.0, -1.0, 30.0]]
)


@pytest.mark.parametrize("kind", ["triangles", "mesh"])
def test_receiver_triangles_push_far_as_fit_shadow_does(kind: str) -> None:
    """A floor of two triangles whose corners lie outside every 2D map: each tile's depth
    range is fit_shadow's with the same receivers (the triangles clipped by the map's
    sides), and reaches farther than the corners taken as points; a cube face's far is
    the largest D over the corners."""
    verts, lights, cube = scene(5)
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    receivers: Any = sm.Triangles(FLOOR[faces]) if kind == "triangles" else sm.Mesh(FLOOR, faces)
    a = allocate_atlas(np.full(len(lights), 0.2), atlas_size=4096, cube=cube)
    fit = fit_atlas(lights, verts, a, receivers=receivers)
    corners = fit_atlas(lights, verts, a, receivers=FLOOR)
    longer = 0
    for i, light in enumerate(lights):
        t = a.light_tiles[i, 0]
        if cube[i]:
            D = np.abs(np.concatenate([verts, FLOOR]) - np.asarray(light.position)).max(axis=1)
            assert fit.far[t] == pytest.approx(D.max() * (1 + 1 / 64), rel=1e-12)
            continue
        ref = independent_fit(light, verts, int(a.light_size[i]), 1,
                              receivers=sm.Triangles(FLOOR[faces]))  # fmt: skip
        assert fit.near[t] == pytest.approx(float(ref.frustum.near), rel=1e-12)
        assert fit.far[t] == pytest.approx(float(ref.frustum.far), rel=1e-12)
        longer += bool(fit.far[t] > corners.far[t] * (1 + 1e-9))
    assert longer >= 3, "the floor's corners outside the maps must miss part of it"


@pytest.mark.parametrize("case", ["scene", "ring"])
def test_cube_faces_keep_every_caster_within_depth(case: str) -> None:
    verts, lights, cube = scene(4)
    if case == "ring":  # the nearest caster lies just past +X's 45 degrees, in its ring
        verts = np.array([[1.0, 1.02, 0.0], [3.0, -2.0, 1.0], [-2.0, 0.5, 4.0], [0.5, 3.0, -3.0]])
        lights, cube = [sm.PointLight(np.zeros(3))], np.array([True])
    a = allocate_atlas(np.full(len(lights), 0.03), atlas_size=4096, cube=cube, border_texels=2)
    fit = fit_atlas(lights, verts, a)
    for light in np.flatnonzero(cube):
        drawn_somewhere = np.zeros(len(verts), dtype=bool)
        for t in a.light_tiles[light]:
            clip = (fit.world_to_clip[t] @ homogeneous(verts).T).T
            drawn = (clip[:, 3] > 0) & np.all(np.abs(clip[:, :2]) <= clip[:, 3:], axis=1)
            z = clip[drawn, 2] / clip[drawn, 3]
            assert np.all((z > -1) & (z < 1))  # neither near nor far clips a drawn caster
            drawn_somewhere |= drawn
        assert drawn_somewhere.all()  # every caster lies in some face's view


@pytest.mark.parametrize(("radius", "filt"), [(0, "box"), (1, "box"), (3, "box"),
                                             (0, "bilinear"), (2, "bilinear")])  # fmt: skip
def test_pcf_kernels_stay_inside_their_tiles(radius: int, filt: Any) -> None:
    verts, lights, cube = scene(5)
    border = sm.pcf_border_texels(radius, filt)
    rng = np.random.default_rng(radius)
    a = allocate_atlas(rng.uniform(0.02, 0.5, len(lights)), atlas_size=4096, cube=cube,
                       border_texels=border, min_tile=32)  # fmt: skip
    fit = fit_atlas(lights, verts, a, pcf_radius=radius, pcf_filter=filt)
    A = a.atlas_size
    for t in range(len(a.tile_light)):
        light = lights[a.tile_light[t]]
        if cube[a.tile_light[t]]:
            d = rng.normal(size=(3000, 3))
            d = d[sm.cube_face(d).face == a.tile_face[t]]
            p = np.asarray(light.position) + d * rng.uniform(0.5, 5.0, (len(d), 1))
        else:  # inside the casters' hull, and a hair inside each extreme vertex
            near_vertices = verts + 1e-7 * (verts.mean(axis=0) - verts)
            p = np.concatenate([inside_points(verts, 400, rng), near_vertices])
        tex = (fit.world_to_texture[t] @ homogeneous(p).T).T
        u = tex[:, :2] / tex[:, 3:] * A  # atlas texel coordinates
        if filt == "box":  # the texel containing (s, t), +- radius
            lo, hi = np.floor(u) - radius, np.floor(u) + radius
        else:  # taps +- radius, each reading the 2 x 2 texels around it
            lo, hi = np.floor(u - 0.5) - radius, np.floor(u - 0.5) + radius + 1
        x, y, n = a.tile_rect[t]
        assert np.all(lo >= [x, y]) and np.all(hi <= [x + n - 1, y + n - 1])


@pytest.mark.parametrize("receiving", ["points", "triangles"])
def test_numpy_alone_and_jax_give_the_compiled_matrices(receiving: str) -> None:
    verts, lights, cube = scene(6)
    a = allocate_atlas(np.linspace(0.9, 0.2, len(lights)), atlas_size=2048, cube=cube)
    R: Any = verts[:5] * 3
    if receiving == "triangles":
        R = sm.Triangles(FLOOR[np.array([[0, 1, 2], [0, 2, 3]])])
    ref = fit_atlas(lights, verts, a, api="direct3d", receivers=R)
    with _kernels.disabled():
        alone = fit_atlas(lights, verts, a, api="direct3d", receivers=R)
    on_jax = fit_atlas(lights, jnp.asarray(verts), a, api="direct3d", receivers=R)
    for other in (alone, on_jax):
        for name in ("world_to_clip", "world_to_texture", "near", "far"):
            assert np.allclose(np.asarray(getattr(other, name)), getattr(ref, name), rtol=1e-10)
    assert isinstance(on_jax.world_to_clip, type(jnp.zeros(1)))


def test_homogeneous_lights_and_per_light_casters() -> None:
    verts, _, _ = scene(7)
    L = np.array([[0.0, 20.0, 0.0, 1.0], [0.2, 1.0, 0.1, 0.0], [1.0, 4.0, 2.0, 1.0]])
    a = allocate_atlas([0.5, 1.0, 0.2], atlas_size=2048, cube=[False, False, True])
    per_light = np.stack([verts, verts + [0, 0.5, 0], verts])
    fit = fit_atlas(L, per_light, a, near=0.5, far=40.0)
    ref = sm.fit_shadow(L[0, :3], verts, 512, near=0.5, far=40.0)
    t = a.light_tiles[0, 0]
    assert np.allclose(fit.world_to_clip[t], ref.blocker_to_clip)
    sun = sm.fit_shadow(sm.DirectionalLight(L[1, :3]), per_light[1], 1024)  # near/far ignored
    assert np.allclose(fit.world_to_clip[a.light_tiles[1, 0]], sun.blocker_to_clip)
    faces = a.light_tiles[2]
    assert np.allclose(fit.near[faces], 0.5) and np.allclose(fit.far[faces], 40.0)


def test_lights_without_tiles_are_skipped() -> None:
    verts, lights, cube = scene(8)
    cov = np.zeros(len(lights))
    cov[[1, 4]] = 0.4  # one spot, one cube light
    a = allocate_atlas(cov, atlas_size=1024, cube=cube)
    fit = fit_atlas(lights, verts, a)
    assert fit.world_to_clip.shape == (7, 4, 4)
    empty = fit_atlas(lights, verts, allocate_atlas(np.zeros(len(lights)), cube=cube))
    assert empty.world_to_texture.shape == (0, 4, 4)


# ------------------------------------------------------------------ errors


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"coverage": [0.5, -0.1]}, "coverage: must be >= 0"),
        ({"coverage": [0.5, math.nan]}, "coverage"),
        ({"coverage": [[0.5]]}, "coverage"),
        ({"atlas_size": 1000}, "atlas_size: must be a power of two"),
        ({"atlas_size": True}, "atlas_size"),
        ({"cube": [True]}, "cube"),
        ({"border_texels": [1, 2, 3]}, "border_texels"),
        ({"border_texels": -1}, "border_texels: must be >= 0"),
        ({"border_texels": 8, "min_tile": 16}, "border_texels: a border of 8"),
        ({"min_tile": 48}, "min_tile: must be a power of two"),
        ({"min_tile": 1024, "max_tile": 256}, "min_tile: must be <= max_tile"),
        ({"max_tile": 8192}, "max_tile: must be <= atlas_size"),
        ({"budget": 0.0}, "budget"),
        ({"budget": "all"}, "budget: expected a number"),
        ({"hysteresis": 1.0}, "hysteresis"),
        ({"light_ids": [3, 3]}, "light_ids: must be distinct"),
        ({"previous": "frame"}, "previous: expected a ShadowAtlas"),
    ],
)
def test_allocation_errors_name_the_argument(kwargs: dict[str, Any], match: str) -> None:
    args = {"coverage": [0.5, 0.2], "atlas_size": 4096, **kwargs}
    with pytest.raises(ValueError, match=match):
        allocate_atlas(args.pop("coverage"), **args)


def test_fit_errors_name_the_light() -> None:
    verts, lights, cube = scene(9)
    a = allocate_atlas(np.full(len(lights), 0.3), atlas_size=4096, cube=cube)
    with pytest.raises(ValueError, match="lights: the atlas has 12 lights, got 11"):
        fit_atlas(lights[:11], verts, a)
    spot_cube = np.array(cube)
    spot_cube[1] = True
    with pytest.raises(ValueError, match=r"lights\[1\]: a cube map needs a point light"):
        fit_atlas(lights, verts, allocate_atlas(np.full(12, 0.3), cube=spot_cube))
    with pytest.raises(ValueError, match="pcf_radius: a box kernel of radius 2 needs borders"):
        fit_atlas(lights, verts, a, pcf_radius=2)
    with pytest.raises(ValueError, match="api: unknown graphics API"):
        fit_atlas(lights, verts, a, api="glide")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="blocker_vertices"):
        fit_atlas(lights, verts[None, :, :2], a)
    with pytest.raises(ValueError, match="near"):
        fit_atlas(lights, verts, a, near=np.ones(3))
    bad = verts.copy()
    bad[4, 1] = np.inf
    with pytest.raises(ValueError, match="blocker_vertices"):
        fit_atlas(lights, bad, a)
    with pytest.raises(ValueError, match="atlas: expected a ShadowAtlas"):
        fit_atlas(lights, verts, tuple(a))  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"lights\[2\]: expected sm.PointLight"):
        fit_atlas([*lights[:2], np.zeros(3), *lights[3:]], verts, a)


def test_docs_example_runs() -> None:
    """docs/atlas.md's example, executed as written: three frames, no tile moved after
    the first, the cube light's six faces at one size, every tile inside the atlas."""
    page = Path(__file__).resolve().parents[1] / "docs" / "atlas.md"
    code = re.search(r"```python\n(.*?)```", page.read_text(encoding="utf-8"), re.DOTALL)
    assert code is not None
    namespace: dict[str, Any] = {"__name__": "docs_example"}
    exec(compile(code.group(1), str(page), "exec"), namespace)
    atlas, fit = namespace["atlas"], namespace["fit"]
    assert not atlas.moved.any()
    assert list(atlas.tile_light) == [0, 1, 1, 1, 1, 1, 1, 2]
    rect = atlas.tile_rect
    assert (rect[1:7, 2] == rect[1, 2]).all()
    assert ((rect[:, :2] + rect[:, 2:]) <= 4096).all()
    assert fit.world_to_texture.shape == (8, 4, 4)
