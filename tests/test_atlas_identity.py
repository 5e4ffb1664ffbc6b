"""Atlas identity across frames and the textures to allocate.

A tile's identity is its key ``(light id, face)``: ``ShadowAtlas.previous_index`` maps
last frame's tiles to this frame's, ``moved`` is index-safe, and ``sm.atlas_redraw`` is
the complete redraw rule. The renderer simulations draw each tile as a rasterizer does
(every caster vertex at the texel the API's viewport rule puts it in, the nearest depth
kept), keep tiles from frame to frame by the rule under test, and check that every tile
sampled holds exactly what a fresh draw of this frame's fit gives: the light's depths,
not a neighbour's nor last frame's. The index-based cache that the issue describes
fails the same check. ``texture_size`` (``AtlasFit`` and ``Cascades``) is checked
against the viewports and the texture coordinates.
"""

from __future__ import annotations

import contextlib
import re
import warnings
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
import pytest

import shadowmath as sm
from shadowmath._backends import _kernels

from .test_atlas import check_layout, homogeneous, scene, window
from .test_cascades import scene as cascade_scene

# ------------------------------------------------------------------ renderers


def draw(fit: sm.AtlasFit, t: int, verts: np.ndarray) -> np.ndarray:
    """Tile ``t``'s ``(h, w)`` depths as OpenGL draws the casters' vertices with
    ``world_to_clip[t]`` into a viewport of its size: the nearest depth per texel, 1
    (cleared) elsewhere."""
    _, _, w, h = (int(v) for v in fit.viewports[t])
    clip = homogeneous(verts) @ np.asarray(fit.world_to_clip[t]).T
    clip = clip[clip[:, 3] > 0]
    col, row, depth = window("opengl", clip, np.array([0, 0, w, h]))
    ndc = clip[:, :3] / clip[:, 3:]
    inside = np.all(np.abs(ndc) <= 1, axis=1)
    image = np.ones((h, w))
    at = (np.minimum(row[inside], h - 1).astype(int), np.minimum(col[inside], w - 1).astype(int))
    np.minimum.at(image, at, depth[inside])
    return image


class AtlasTexture:
    """One atlas texture kept from frame to frame: ``atlas_redraw``'s tiles are cleared
    and drawn in their viewports, the others left as they are."""

    def __init__(self) -> None:
        self.texture = np.zeros((0, 0))
        self.fit: sm.AtlasFit | None = None

    def frame(self, atlas: sm.ShadowAtlas, fit: sm.AtlasFit, verts: np.ndarray) -> list[Any]:
        redraw = sm.atlas_redraw(fit, self.fit)
        w, h = fit.texture_size
        if self.texture.shape != (h, w):
            self.texture = np.full((h, w), np.nan)  # a new texture holds nothing yet
        for t in np.flatnonzero(redraw):
            x, y, tw, th = fit.viewports[t]
            self.texture[y : y + th, x : x + tw] = draw(fit, int(t), verts)
        self.fit = fit
        return [self.texture[y : y + th, x : x + tw] for x, y, tw, th in fit.viewports]


class KeyCache:
    """Each tile's depths cached by ``(light id, face)``, redrawn by ``atlas_redraw``."""

    def __init__(self) -> None:
        self.cache: dict[tuple[int, int], np.ndarray] = {}
        self.fit: sm.AtlasFit | None = None

    def frame(self, atlas: sm.ShadowAtlas, fit: sm.AtlasFit, verts: np.ndarray) -> list[Any]:
        keys = list(zip(fit.tile_id.tolist(), fit.tile_face.tolist(), strict=True))
        for t in np.flatnonzero(sm.atlas_redraw(fit, self.fit)):
            self.cache[keys[t]] = draw(fit, int(t), verts)
        self.fit = fit
        return [self.cache[k] for k in keys]


class IndexCache:
    """Each tile's depths cached by tile index, redrawn where ``atlas.moved`` says (or
    its matrices at that index changed); ``old_moved`` replays the flag before keys: a
    rect changed for that light and face, whatever the index."""

    def __init__(self, *, old_moved: bool = False) -> None:
        self.cache: list[np.ndarray] = []
        self.clip = np.zeros((0, 4, 4))
        self.old_moved = old_moved
        self.previous: sm.ShadowAtlas | None = None

    def frame(self, atlas: sm.ShadowAtlas, fit: sm.AtlasFit, verts: np.ndarray) -> list[Any]:
        moved = atlas.moved
        if self.old_moved and self.previous is not None:
            back = np.where(atlas.previous_index >= 0, atlas.previous_index, 0)
            kept = np.all(atlas.tile_rect == self.previous.tile_rect[back], axis=1)
            moved = (atlas.previous_index < 0) | ~kept
        clip = np.asarray(fit.world_to_clip)
        count = len(clip)
        self.cache = (self.cache + [np.zeros(0)] * count)[:count]
        for t in range(count):
            same = t < len(self.clip) and np.array_equal(self.clip[t], clip[t])
            if moved[t] or (not same and not self.old_moved):
                self.cache[t] = draw(fit, t, verts)
        self.clip, self.previous = clip, atlas
        return self.cache


# ------------------------------------------------------------------ frames


class Frame(NamedTuple):
    ids: list[int]
    coverage: dict[int, float]  # by id; 0.1 otherwise
    offset: dict[int, float]  # by id: a light moved along x
    atlas_size: int = 1024


VERTS, POOL, CUBE = scene(3)  # 12 lights: cube points, spots, 2D points, suns
FIRST = 100  # the lights' ids: 100 + their index in POOL

FRAMES = [
    Frame(list(range(100, 108)), {}, {}),
    Frame([100, *range(102, 108)], {}, {}),  # 101 (a spot) leaves: the 6 + 1 after shift
    Frame(list(range(102, 108)), {}, {}),  # 100 (a cube light) leaves: its 6 tiles
    Frame(list(range(107, 101, -1)), {}, {}),  # reordered
    Frame([108, 109, 100, *range(107, 101, -1)], {}, {}),  # 108 (cube) and 109 join, 100 back
    Frame([108, 109, 100, *range(107, 101, -1)], {}, {102: 0.5}),  # 102 moved
    Frame([108, 109, 100, *range(107, 101, -1)], {103: 0.3}, {102: 0.5}),  # 103 resized
    Frame([108, 109, 100, *range(107, 101, -1)], {103: 0.3}, {102: 0.5}),  # nothing changed
    Frame([108, 109, 100, *range(107, 101, -1)], {103: 0.3}, {102: 0.5}, 2048),  # new texture
    Frame([108, 109, 100, *range(107, 101, -1)], {103: 0.3}, {102: 0.5}),  # same rects, new texture
]


def light(ident: int, offset: float) -> Any:
    base = POOL[ident - FIRST]
    if isinstance(base, sm.DirectionalLight) or offset == 0:
        return base
    return base._replace(position=np.asarray(base.position) + [offset, 0.0, 0.0])


def run_frames() -> list[tuple[sm.ShadowAtlas, sm.AtlasFit]]:
    out: list[tuple[sm.ShadowAtlas, sm.AtlasFit]] = []
    previous = None
    for f in FRAMES:
        coverage = [f.coverage.get(i, 0.1) for i in f.ids]
        cube = CUBE[np.array(f.ids) - FIRST]
        atlas = sm.allocate_atlas(coverage, atlas_size=f.atlas_size, cube=cube, max_tile=512,
                                  light_ids=f.ids, previous=previous)  # fmt: skip
        lights = [light(i, f.offset.get(i, 0.0)) for i in f.ids]
        out.append((atlas, sm.fit_atlas(lights, VERTS, atlas)))
        previous = atlas
    return out


def tiles_of(atlas: sm.ShadowAtlas, ids: set[int]) -> set[int]:
    return {t for t, i in enumerate(atlas.tile_id.tolist()) if i in ids}


# ------------------------------------------------------------------ tests


@pytest.mark.parametrize("compiled", [True, False])
def test_renderers_caching_by_key_sample_every_lights_own_depths(compiled: bool) -> None:
    """Over lights leaving, joining, reordered, moved and resized, cube lights among
    them, a texture kept by ``atlas_redraw`` and a cache by key (and by index with the
    index-safe ``moved``) sample exactly this frame's depths in every tile; each frame
    redraws exactly the tiles whose key, rect or matrices are new."""
    if compiled and not _kernels.available():
        pytest.skip("the compiled loops need the fast extra")
    with contextlib.nullcontext() if compiled else _kernels.disabled():
        frames = run_frames()
    renderers = [AtlasTexture(), KeyCache(), IndexCache()]
    expected: list[set[int] | None] = [None, set(), set(), set(), {108, 109, 100}, {102},
                                       {103}, set(), None, None]  # None: all  # fmt: skip
    previous = None
    for (atlas, fit), redrawn in zip(frames, expected, strict=True):
        check_layout(atlas)
        truth = [draw(fit, t, VERTS) for t in range(len(fit.viewports))]
        for renderer in renderers:
            sampled = renderer.frame(atlas, fit, VERTS)
            for t, image in enumerate(truth):
                assert np.array_equal(sampled[t], image), (type(renderer).__name__, t)
        redraw = sm.atlas_redraw(fit, previous)
        if redrawn is None:
            assert redraw.all()
        else:
            assert set(np.flatnonzero(redraw).tolist()) == tiles_of(atlas, redrawn)
        previous = fit
    (_, last), (_, before) = frames[-1], frames[-2]  # only the texture changed: its rule
    assert np.array_equal(last.viewports, before.viewports)
    assert np.array_equal(last.world_to_clip, before.world_to_clip)


def test_the_index_cache_of_the_issue_samples_the_wrong_light() -> None:
    """The same frames through a cache by tile index redrawn where a light's rect
    changed (the flag before keys): when light 101 leaves, tile 6 (after light 100's six
    faces) is light 102's but still holds light 101's depths."""
    frames = run_frames()
    renderer = IndexCache(old_moved=True)
    renderer.frame(*frames[0], VERTS)
    atlas, fit = frames[1]
    sampled = renderer.frame(atlas, fit, VERTS)
    assert atlas.tile_id[6] == 102 and frames[0][0].tile_id[6] == 101
    assert not np.array_equal(sampled[6], draw(fit, 6, VERTS))
    assert np.array_equal(sampled[6], draw(frames[0][1], 6, VERTS))  # light 101's depths


def run_renderers(
    atlases: list[sm.ShadowAtlas], lights: list[list[Any]], verts: np.ndarray = VERTS
) -> list[Any]:
    """Each frame through the renderers that cache by key or index; each tile sampled
    checked against a fresh draw. Returns each frame's ``atlas_redraw``."""
    renderers, flags, previous = [AtlasTexture(), KeyCache(), IndexCache()], [], None
    for atlas, frame_lights in zip(atlases, lights, strict=True):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", sm.ShadowFitWarning)
            fit = sm.fit_atlas(frame_lights, verts, atlas)
        for renderer in renderers:
            sampled = renderer.frame(atlas, fit, verts)
            for t in range(len(fit.viewports)):
                assert np.array_equal(sampled[t], draw(fit, t, verts)), (renderer, t)
        flags.append(sm.atlas_redraw(fit, previous))
        previous = fit
    return flags


def check_identity(a: sm.ShadowAtlas, b: sm.ShadowAtlas) -> None:
    """``b.previous_index`` maps each tile to ``a``'s tile of its key (-1: none), and a
    tile not ``moved`` was tile ``t`` of ``a``, same key, same rect."""
    pairs = zip(a.tile_id.tolist(), a.tile_face.tolist(), strict=True)
    old = {key: t for t, key in enumerate(pairs)}
    keys = zip(b.tile_id.tolist(), b.tile_face.tolist(), strict=True)
    assert b.previous_index.tolist() == [old.get(k, -1) for k in keys]
    assert np.array_equal(b.tile_id, b.light_ids[b.tile_light])
    for t in np.flatnonzero(~b.moved):
        assert b.previous_index[t] == t and a.atlas_size == b.atlas_size
        assert np.array_equal(a.tile_rect[t], b.tile_rect[t])


def test_a_repack_moves_kept_tiles_and_they_are_redrawn() -> None:
    """16 tiles of 256 fill the atlas; the odd lights leave and a 512 comes: no aligned
    hole, so every tile is laid out afresh, and the kept lights whose rect moved (same
    size, same matrices) are redrawn there."""
    flat = [light for light, c in zip(POOL, CUBE, strict=True) if not c]
    lights = [flat[i % len(flat)] for i in range(16)]
    options: dict[str, Any] = {"atlas_size": 1024, "min_tile": 64, "max_tile": 512}
    a = sm.allocate_atlas(np.full(16, 0.5), **options)
    ids = [*range(0, 16, 2), 99]
    b = sm.allocate_atlas(np.r_[np.full(8, 0.5), 1.0], light_ids=ids, previous=a, **options)
    assert b.repacked
    lights_b = [lights[i] for i in range(0, 16, 2)] + [flat[0]]
    _, redraw = run_renderers([a, b], [lights, lights_b])
    moved_rect = np.any(b.tile_rect[:8] != a.tile_rect[b.previous_index[:8]], axis=1)
    assert moved_rect.any() and not moved_rect.all()
    assert redraw.tolist() == [*moved_rect.tolist(), True]


def test_a_renamed_light_is_a_new_tile() -> None:
    """The same light at the same rect under another id: a cache by key has nothing
    for the new key, so the tile is redrawn."""
    a = sm.allocate_atlas([0.3], atlas_size=1024, light_ids=[7])
    b = sm.allocate_atlas([0.3], atlas_size=1024, light_ids=[8], previous=a)
    assert np.array_equal(a.tile_rect, b.tile_rect) and b.previous_index.tolist() == [-1]
    assert [r.tolist() for r in run_renderers([a, b], [[POOL[1]], [POOL[1]]])] == [[True], [True]]


def test_a_light_leaving_shifts_indices_and_moved_says_so() -> None:
    """ids [7, 8, 9] -> [7, 9]: light 9's tile keeps its rect but its index 2 -> 1."""
    a = sm.allocate_atlas([0.3, 0.3, 0.3], atlas_size=1024, light_ids=[7, 8, 9])
    b = sm.allocate_atlas([0.3, 0.3], atlas_size=1024, light_ids=[7, 9], previous=a)
    assert b.tile_id.tolist() == [7, 9] and b.previous_index.tolist() == [0, 2]
    assert np.array_equal(b.tile_rect[1], a.tile_rect[2])
    assert b.moved.tolist() == [False, True]


def test_joining_reordering_and_cube_faces_map_by_key() -> None:
    """A cube light's faces map face to face; a light joining in front and a reorder
    shift every index after them; previous_index is -1 for new tiles only."""
    a = sm.allocate_atlas([0.3, 0.2, 0.3], atlas_size=2048, cube=[False, True, False],
                          light_ids=[7, 8, 9])  # fmt: skip
    assert a.tile_id.tolist() == [7, *[8] * 6, 9]
    assert a.previous_index.tolist() == [-1] * 8 and a.moved.all()
    b = sm.allocate_atlas([0.1, 0.3, 0.2, 0.3], atlas_size=2048, cube=[False, False, True, False],
                          light_ids=[5, 9, 8, 7], previous=a)  # fmt: skip
    assert b.tile_id.tolist() == [5, 9, *[8] * 6, 7]
    assert b.tile_face.tolist() == [0, 0, 0, 1, 2, 3, 4, 5, 0]
    assert b.previous_index.tolist() == [-1, 7, 1, 2, 3, 4, 5, 6, 0]
    assert np.array_equal(b.tile_rect[1:], a.tile_rect[b.previous_index[1:]])
    assert b.moved.all()  # no index names the tile it named
    c = sm.allocate_atlas([0.1, 0.3, 0.2, 0.3], atlas_size=2048, cube=[False, False, True, False],
                          light_ids=[5, 9, 8, 7], previous=b)  # fmt: skip
    assert c.previous_index.tolist() == list(range(9)) and not c.moved.any()


def test_a_resized_light_keeps_its_key_and_moves() -> None:
    a = sm.allocate_atlas([0.3, 0.05, 0.3], atlas_size=2048, cube=[False, True, False])
    b = sm.allocate_atlas([0.3, 0.2, 0.3], atlas_size=2048, cube=[False, True, False],
                          previous=a)  # fmt: skip
    assert (a.light_size[1], b.light_size[1]) == (64, 256) and not b.repacked
    assert b.previous_index.tolist() == list(range(8))
    assert b.moved.tolist() == [False, *[True] * 6, False]
    redraw = sm.atlas_redraw(*fits(b, a))
    assert redraw.tolist() == [False, *[True] * 6, False]


def fits(*atlases: sm.ShadowAtlas) -> list[sm.AtlasFit]:
    lights = [POOL[1], POOL[0], POOL[3]]  # a spot, a cube point light, a sun
    return [sm.fit_atlas(lights, VERTS, a) for a in atlases]


def test_atlas_redraw_compares_matrices_exactly_and_refuses_other_types() -> None:
    a = sm.allocate_atlas([0.3, 0.2, 0.3], atlas_size=2048, cube=[False, True, False])
    fit = fits(a)[0]
    assert sm.atlas_redraw(fit, None).all()
    assert not sm.atlas_redraw(fit, fit).any()
    nudged = np.array(fit.world_to_clip)
    nudged[3, 2, 3] = np.nextafter(nudged[3, 2, 3], np.inf)  # one face's depth row, one ulp
    changed = sm.atlas_redraw(fit, fit._replace(world_to_clip=nudged))
    assert changed.tolist() == [t == 3 for t in range(8)]
    with pytest.raises(ValueError, match=r"^fit: expected an AtlasFit"):
        sm.atlas_redraw(tuple(fit), None)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"^previous: expected an AtlasFit"):
        sm.atlas_redraw(fit, a)  # type: ignore[arg-type]


# ------------------------------------------------------------------ texture sizes


def corner_texels(clip: Any, texture: Any, size: tuple[int, int]) -> np.ndarray:
    """Where the corners ``(x, y) = (-1 or 1, -1 or 1)`` of clip space land in the
    texture, in texels: ``(s W, t H)``."""
    ndc = np.array([[u, v, 0.0, 1.0] for u in (-1, 1) for v in (-1, 1)])
    world = ndc @ np.linalg.inv(np.asarray(clip, float)).T
    stq = world @ np.asarray(texture, float).T
    return np.asarray(stq[:, :2] / stq[:, 3:] * size)


def assert_viewports_in_texture(fit: Any, size: tuple[int, int]) -> None:
    """Every viewport inside the ``size`` texture, and the corners of each tile's clip
    space sampled at its viewport's corners (OpenGL: ``x = -1`` at the left column,
    ``y = -1`` at the first row): ``texture_size`` is what ``world_to_texture``
    divides by."""
    w, h = size
    x, y, vw, vh = np.asarray(fit.viewports).T
    assert np.all((x >= 0) & (y >= 0) & (x + vw <= w) & (y + vh <= h))
    for i in range(len(x)):
        expected = [[x[i] + a * vw[i], y[i] + b * vh[i]] for a in (0, 1) for b in (0, 1)]
        got = corner_texels(fit.world_to_clip[i], fit.world_to_texture[i], size)
        np.testing.assert_allclose(got, expected, rtol=0, atol=1e-9 * max(w, h))


def test_atlas_fit_texture_is_the_atlas_and_holds_every_viewport() -> None:
    a = sm.allocate_atlas(np.linspace(1.0, 0.05, 12), atlas_size=2048, cube=CUBE)
    fit = sm.fit_atlas(POOL, VERTS, a)
    assert fit.texture_size == (2048, 2048)
    assert_viewports_in_texture(fit, fit.texture_size)
    _, _, vw, vh = np.asarray(fit.viewports).T
    assert (vw * vh).sum() / 2048**2 == pytest.approx(a.used, rel=1e-15)  # tiles, no overlap


@pytest.mark.parametrize("count", [1, 2, 3, 4, 5, 7])
@pytest.mark.parametrize("layout", ["layers", "atlas"])
def test_cascades_texture_holds_every_viewport(count: int, layout: Any) -> None:
    """layers: a ``(W, H)`` layer per cascade; atlas: the grid's ``(cols W, rows H)``
    exactly (no empty column or row), ``ceil(sqrt(n))`` columns, one cell each."""
    sun, view, proj, box = cascade_scene(0)
    c = sm.fit_cascades(sun, view, proj, box, (256, 128), count=count, layout=layout)
    w, h = c.texture_size
    x, y, vw, vh = np.asarray(c.viewports).T
    assert np.all((vw == 256) & (vh == 128))
    assert_viewports_in_texture(c, c.texture_size)
    if layout == "layers":
        assert (w, h, c.texture_layers) == (256, 128, count)
        return
    assert c.texture_layers == 1
    assert (w, h) == ((x + vw).max(), (y + vh).max())
    cols = w // 256
    assert cols * cols >= count > (cols - 1) * (cols - 1)
    assert len({(int(a), int(b)) for a, b in zip(x, y, strict=True)}) == count


def test_docs_cache_example_runs(capsys: pytest.CaptureFixture[str]) -> None:
    """docs/atlas.md's per-frame example with a cache by key, executed as written: the
    first frame draws every tile, the later ones none (light 8 leaves, the order
    changes; nothing else does), and every tile of the last frame holds what this
    frame's fit draws there."""
    page = Path(__file__).resolve().parents[1] / "docs" / "atlas.md"
    blocks = re.findall(r"```python\n(.*?)```", page.read_text(encoding="utf-8"), re.DOTALL)
    code = next(b for b in blocks if "atlas_redraw" in b)
    namespace: dict[str, Any] = {"__name__": "docs_example"}
    exec(compile(code, str(page), "exec"), namespace)
    lines = capsys.readouterr().out.splitlines()
    assert [line.split(" redrawn: ")[1] for line in lines] == [
        "8 of 8 moved: 8", "0 of 8 moved: 0", "0 of 2 moved: 1", "0 of 2 moved: 2",
    ]  # fmt: skip
    fit, tiles = namespace["fit"], namespace["tiles"]
    assert fit.tile_id.tolist() == [9, 7]
    for t, key in enumerate(zip(fit.tile_id.tolist(), fit.tile_face.tolist(), strict=True)):
        clip, port = tiles[key]
        assert np.array_equal(clip, fit.world_to_clip[t]) and port == tuple(fit.viewports[t])


def test_keys_of_any_int64_id() -> None:
    """Ids at both ends of int64 (no room to pack the face beside them) still match."""
    big = [2**63 - 1, -(2**63), 5]
    a = sm.allocate_atlas([0.3, 0.2, 0.3], atlas_size=2048, cube=[False, True, False],
                          light_ids=big)  # fmt: skip
    b = sm.allocate_atlas([0.3, 0.3, 0.2], atlas_size=2048, cube=[False, False, True],
                          light_ids=[5, 2**63 - 1, -(2**63)], previous=a)  # fmt: skip
    assert b.previous_index.tolist() == [7, 0, 1, 2, 3, 4, 5, 6]
    lights = [POOL[1], POOL[0], POOL[3]]
    fit_a = sm.fit_atlas(lights, VERTS, a)
    fit_b = sm.fit_atlas([lights[2], lights[0], lights[1]], VERTS, b)
    assert not sm.atlas_redraw(fit_b, fit_a).any()
    assert sm.atlas_redraw(fit_b, fit_a._replace(tile_face=(fit_a.tile_face + 1) % 6)).any()
    # 2**61 * 8 and -(2**63) * 8 wrap to 0 in int64: a key packed naively would take
    # id 0 for them.
    for old_id in (2**61, -(2**63)):
        c = sm.allocate_atlas([0.3], atlas_size=1024, light_ids=[old_id])
        d = sm.allocate_atlas([0.3], atlas_size=1024, light_ids=[0], previous=c)
        assert np.array_equal(c.tile_rect, d.tile_rect) and d.previous_index.tolist() == [-1]
        fit_c, fit_d = (sm.fit_atlas([POOL[1]], VERTS, x) for x in (c, d))
        assert sm.atlas_redraw(fit_d, fit_c).tolist() == [True]
