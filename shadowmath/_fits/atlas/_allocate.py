r"""A shadow atlas's tiles for many lights: :func:`allocate_atlas`.

Each light's tile size (Godot's rule, under a budget) and place (a quadtree, kept from
frame to frame), on host integers (:mod:`shadowmath._math._atlas_tiles`). The rule and
the borders are written out in ``docs/atlas.md``.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from shadowmath._boundary._shapes import ArrayLike, Bool, Float, Int, Real
from shadowmath._boundary._validate import integer, non_finite, real, real_array, shape_error
from shadowmath._math import _atlas_tiles as tiles

__all__ = ["ShadowAtlas", "allocate_atlas", "find_tiles"]

Ints = NDArray[np.int64]


class ShadowAtlas(NamedTuple):
    """Where every light's shadow map lies in the atlas (the result of :func:`allocate_atlas`).

    ``L`` lights, ``T`` tiles (one per 2D light with a tile, six per cube light).
    Tiles are listed light by light, faces in order. Integer arrays are int64 NumPy.

    Attributes:
        atlas_size: the atlas is ``atlas_size x atlas_size`` texels.
        tile_light: ``(T,)`` the light of each tile.
        tile_face: ``(T,)`` 0 for a 2D map; the cube face ``0..5`` (``+X, -X, +Y, -Y,
            +Z, -Z``, the order of :func:`cube_face`).
        tile_rect: ``(T, 3)`` ``(x, y, size)`` in texels: ``x`` from the left, ``y`` the
            row counted from the atlas's first row in memory.
        light_size: ``(L,)`` each light's tile size (0: no tile, no shadow this frame).
        light_tiles: ``(L, 6)`` the tile of each face (``-1`` unused; a 2D light uses
            column 0).
        moved: ``(T,)`` True unless tile ``t`` of ``previous`` was the same
            ``(light id, face)`` at the same rect: a new tile, one whose rect moved or
            resized, and one whose index now names another light's tile (lights left,
            joined or were reordered before it) all count as moved. False is safe for
            a cache by tile index *and* by key; it does not say that the light's
            matrices are unchanged: :func:`atlas_redraw` is the complete rule.
        used: the fraction of the atlas's area covered by tiles.
        light_wish: ``(L,)`` the size each light asked for (its class, before the
            budget); the hysteresis of the next frame reads it.
        light_ids: ``(L,)`` the lights' identities, matched against ``previous``.
        light_cube: ``(L,)`` whether each light is a cube map.
        light_border: ``(L,)`` each light's border in texels.
        tile_clamp: ``(T, 4)`` float64 ``(s_min, t_min, s_max, t_max)``: the atlas
            texture coordinates of the tile's first and last texel centres. Clamp
            every PCF tap into it: a 2D tile's edge texels are border, always empty,
            so a clamped tap reads "lit", as a single map's clamp-to-border does.
        repacked: True when the tiles kept from ``previous`` left no aligned hole for
            a new one, so every tile was laid out afresh.
        tile_id: ``(T,)`` the id (``light_ids``) of each tile's light: a tile's identity
            across frames is its key ``(tile_id[t], tile_face[t])``, not its index
            ``t`` (which shifts when lights before it leave, join or are reordered).
        previous_index: ``(T,)`` the index in ``previous`` of the tile with the same
            key, ``-1`` for a new one (or without ``previous``): a renderer moves its
            per-tile data (cached depths, uniforms) from ``previous_index[t]`` to ``t``.
    """

    atlas_size: int
    tile_light: Int[Ints, " T"]
    tile_face: Int[Ints, " T"]
    tile_rect: Int[Ints, "T 3"]
    light_size: Int[Ints, " L"]
    light_tiles: Int[Ints, "L 6"]
    moved: Bool[NDArray[np.bool_], " T"]
    used: float
    light_wish: Int[Ints, " L"]
    light_ids: Int[Ints, " L"]
    light_cube: Bool[NDArray[np.bool_], " L"]
    light_border: Int[Ints, " L"]
    tile_clamp: Float[NDArray[np.float64], "T 4"]
    repacked: bool
    tile_id: Int[Ints, " T"]
    previous_index: Int[Ints, " T"]


# ------------------------------------------------------------------ allocation


def allocate_atlas(
    coverage: Real[ArrayLike, " L"],
    *,
    atlas_size: int = 4096,
    cube: bool | Bool[ArrayLike, " L"] = False,
    border_texels: int | Real[ArrayLike, " L"] = 1,
    previous: ShadowAtlas | None = None,
    min_tile: int | None = None,
    max_tile: int | None = None,
    budget: float = 1.0,
    hysteresis: float = 0.1,
    light_ids: Real[ArrayLike, " L"] | None = None,
) -> ShadowAtlas:
    r"""Give each light a power-of-two tile of a shadow atlas, stable from frame to frame.

    **Size.** Godot's rule (``shadow_atlas_update_light``): a light covering the
    fraction ``c`` of the screen wishes ``next_pow2(c * max_tile)`` texels, clamped
    to ``[min_tile, max_tile]`` (``max_tile`` defaults to Godot's quadrant, half the
    atlas); ``c = 0`` wishes nothing. With ``previous``, a light keeps its last wish
    ``p`` while ``p (1 - h) / 2 < c * max_tile <= p (1 + h)`` (``h = hysteresis``).

    **Budget.** Priority is the wished size, then the smaller id (the wish, not the raw
    coverage, so that noise cannot reorder lights of one class). While the wishes'
    area (six faces for a cube) exceeds ``budget`` of the atlas, rounds from the least
    covering light up halve each light's size in turn (one at ``min_tile`` keeps it),
    stopping as soon as it fits; if every light is at ``min_tile`` and it still does
    not, lights drop (size 0), the least covering first.

    **Place.** The atlas is a quadtree of ``min_tile`` cells. A light whose id was in
    ``previous`` with the same size and kind keeps its rect(s). The others go, largest
    first, into the free node of their size whose largest free ancestor is smallest
    (ties: the lowest Morton code), so kept tiles never move. Without ``previous``
    (or if no such node is left: ``repacked``) every tile is laid out afresh along
    the Morton curve, largest first, which always fits what the budget admitted.

    Arguments:
        coverage: ``(L,)`` each light's screen coverage, ``>= 0`` (Godot's: the
            light's range projected on the screen over the viewport's half-extents,
            ``[0, 1]`` on screen; larger values clamp to ``max_tile``).
        atlas_size: the atlas side in texels, a power of two.
        cube: ``bool`` or ``(L,)``: six face tiles (a point light's cube map).
        border_texels: ``int`` or ``(L,)``: each tile's empty border (2D) or ring (cube),
            e.g. :func:`pcf_border_texels` of the PCF kernel.
        previous: the last frame's atlas (same ``atlas_size``), or None.
        min_tile, max_tile: powers of two; defaults ``max(atlas_size / 64, the smallest
            power of two >= 4 max(border))`` and ``atlas_size / 2``.
        budget: the fraction of the atlas's area the tiles may use, in ``(0, 1]``.
        hysteresis: ``h`` above, in ``[0, 1)``; 0 is Godot's rule exactly.
        light_ids: ``(L,)`` distinct integers naming the lights across frames
            (default ``0..L-1``): what ``previous`` is matched by.

    Returns:
        :class:`ShadowAtlas`.

    Raises:
        ValueError: a coverage not numbers (strings, booleans...), not finite or
            negative; a ``budget``, ``hysteresis`` or size that is not a number; an ``atlas_size``,
            ``min_tile`` or ``max_tile`` not a power of two or out of order; a border
            that leaves no inner texel of ``min_tile``; ``cube``, ``border_texels`` or
            ``light_ids`` of the wrong length; repeated ids; a ``budget`` or
            ``hysteresis`` out of range; ``previous`` not a :class:`ShadowAtlas`.

    Example:
        >>> a = allocate_atlas([0.5, 0.1, 0.0], atlas_size=1024, cube=[False, True, False])
        >>> a.light_size.tolist(), len(a.tile_light), a.tile_rect[0].tolist()
        ([256, 64, 0], 7, [0, 0, 256])
        >>> b = allocate_atlas([0.52, 0.1, 0.2], atlas_size=1024, cube=[False, True, False],
        ...                    previous=a)
        >>> int(b.moved.sum()), b.light_size.tolist()  # 0.52: hysteresis keeps 256; one new tile
        (1, [256, 64, 128])
    """
    cov = _coverage(coverage)
    count = cov.shape[0]
    size = _power_of_two("atlas_size", atlas_size)
    is_cube = _per_light("cube", cube, count, np.bool_)
    border = _per_light("border_texels", border_texels, count, np.int64)
    if border.size and border.min() < 0:
        raise ValueError(f"border_texels: must be >= 0, got {int(border.min())}")
    lo, hi = _tile_range(size, min_tile, max_tile, int(border.max(initial=0)))
    if not 0 < real("budget", budget) <= 1:
        raise ValueError(
            f"budget: the fraction of the atlas to use must lie in (0, 1], got {budget!r}"
        )
    if not 0 <= real("hysteresis", hysteresis) < 1:
        raise ValueError(f"hysteresis: must lie in [0, 1), got {hysteresis!r}")
    ids = _ids(light_ids, count)
    if previous is not None and not isinstance(previous, ShadowAtlas):
        raise ValueError(f"previous: expected a ShadowAtlas or None, got {type(previous).__name__}")
    options = _Options(size, lo, hi, float(budget), float(hysteresis))
    return _allocate(cov, is_cube, border, ids, previous=previous, o=options)


class _Options(NamedTuple):
    size: int
    min_tile: int
    max_tile: int
    budget: float
    hysteresis: float


def _coverage(coverage: Any) -> NDArray[np.float64]:
    cov = np.asarray(real_array("coverage", coverage), dtype=np.float64)
    if cov.ndim != 1:
        raise shape_error("coverage", "(L,)", cov.shape, "one screen coverage per light")
    if not np.isfinite(cov).all():
        raise ValueError(non_finite("coverage"))
    if cov.size and cov.min() < 0:
        raise ValueError(f"coverage: must be >= 0 (a fraction of the screen), got {cov.min()}")
    return cov


def _power_of_two(name: str, value: object) -> int:
    n = integer(name, value)
    if n < 1 or n & (n - 1):
        raise ValueError(f"{name}: must be a power of two (1, 2, 4, ...), got {n}")
    return n


def _per_light(name: str, value: Any, count: int, dtype: Any) -> Any:
    what = "booleans" if dtype is np.bool_ else "integers"
    try:
        v = np.asarray(value)
    except ValueError:  # ragged
        v = np.asarray(None)
    if v.dtype.kind not in ("b" if dtype is np.bool_ else "iu"):
        raise ValueError(f"{name}: expected {what} (one, or one per light), got {value!r}")
    if v.ndim > 1 or (v.ndim == 1 and v.shape[0] != count):
        raise shape_error(name, f"() or ({count},)", v.shape, "one value, or one per light")
    return np.broadcast_to(v, (count,)).astype(dtype)


def _tile_range(
    size: int, min_tile: int | None, max_tile: int | None, border: int
) -> tuple[int, int]:
    hi = size // 2 if max_tile is None else _power_of_two("max_tile", max_tile)
    hi = max(hi, 1)
    if min_tile is None:
        lo = min(hi, max(size // 64, 1 << max(4 * border - 1, 0).bit_length()))
    else:
        lo = _power_of_two("min_tile", min_tile)
    if hi > size:
        raise ValueError(f"max_tile: must be <= atlas_size ({size}), got {hi}")
    if lo > hi:
        raise ValueError(f"min_tile: must be <= max_tile ({hi}), got {lo}")
    if lo <= 2 * border:
        raise ValueError(
            f"border_texels: a border of {border} texels on each side leaves no inner texel "
            f"of a {lo}-texel tile (min_tile); need 2 * border_texels < min_tile"
        )
    if size // lo > 1 << 15:
        raise ValueError(f"min_tile: at most 32768 tiles per side, got {size // lo}")
    return lo, hi


def _ids(light_ids: Any, count: int) -> Ints:
    if light_ids is None:
        return np.arange(count, dtype=np.int64)
    ids = _per_light("light_ids", light_ids, count, np.int64)
    if np.unique(ids).size != count:
        raise ValueError("light_ids: must be distinct (one identity per light)")
    return np.asarray(ids)


def _match(ids: Ints, previous: ShadowAtlas | None) -> Ints:
    """Each light's index in ``previous`` (by id), or -1."""
    if previous is None:
        return np.full(ids.shape, -1, dtype=np.int64)
    return _find(ids, previous.light_ids)


def _find(keys: Ints, old: Ints) -> Ints:
    """Each key's index in ``old`` (distinct keys), or -1."""
    if old.shape == keys.shape and np.array_equal(old, keys):
        return np.arange(keys.size, dtype=np.int64)
    if old.size == 0:
        return np.full(keys.shape, -1, dtype=np.int64)
    order = np.argsort(old, kind="stable")
    pos = np.minimum(np.searchsorted(old[order], keys), old.size - 1)
    return np.where(old[order][pos] == keys, order[pos], -1).astype(np.int64)


def find_tiles(ids: Ints, faces: Ints, old_ids: Ints, old_faces: Ints) -> Ints:
    """Each tile's index among the old tiles with the same key ``(id, face)``, or -1."""
    if (
        old_ids.shape == ids.shape
        and np.array_equal(old_ids, ids)
        and np.array_equal(old_faces, faces)
    ):
        return np.arange(ids.size, dtype=np.int64)
    both = np.concatenate([old_ids, ids])
    if both.size and not -(1 << 59) <= both.min() <= both.max() < 1 << 59:  # any int64: ranks
        both = np.unique(both, return_inverse=True)[1].reshape(-1)
    code = both * 8 + np.concatenate([old_faces, faces])
    return _find(code[old_ids.size :], code[: old_ids.size])


def _allocate(
    cov: NDArray[np.float64],
    is_cube: NDArray[np.bool_],
    border: Ints,
    ids: Ints,
    *,
    previous: ShadowAtlas | None,
    o: _Options,
) -> ShadowAtlas:
    """The allocation rule on checked arrays (see :func:`allocate_atlas`)."""
    faces = np.where(is_cube, 6, 1).astype(np.int64)
    prev_at = _match(ids, previous)
    had = prev_at >= 0
    safe = np.where(had, prev_at, 0)
    prev_wish = None
    if previous is not None and previous.light_wish.size:
        prev_wish = np.where(had, previous.light_wish[safe], 0)
    wish = tiles.size_classes(cov, o.max_tile, o.min_tile, prev_wish, o.hysteresis)
    # Priority: the wished class, then the id; not the raw coverage, whose noise would
    # reorder equal classes from frame to frame and move their tiles under the budget.
    order = np.lexsort((ids, -wish))
    grid = o.size // o.min_tile
    sizes = tiles.shrink_to_budget(wish, faces, order, o.min_tile, int(o.budget * grid * grid))
    if _unchanged(previous, o.size, ids, sizes, is_cube):
        assert previous is not None
        count = previous.tile_light.shape[0]
        return previous._replace(
            moved=np.zeros(count, dtype=bool), light_wish=wish, light_border=border,
            repacked=False, previous_index=np.arange(count, dtype=np.int64),
        )  # fmt: skip
    lit = np.flatnonzero(sizes)
    per = faces[lit]
    tile_light = np.repeat(lit, per)
    count = tile_light.size
    tile_face = np.arange(count) - np.repeat(np.cumsum(per) - per, per)
    light_tiles = np.full((cov.size, 6), -1, dtype=np.int64)
    light_tiles[tile_light, tile_face] = np.arange(count)
    side = sizes[tile_light] // o.min_tile
    rank_of = np.empty(cov.size, dtype=np.int64)
    rank_of[order] = np.arange(cov.size)
    rank = rank_of[tile_light] * 6 + tile_face
    prev_rect = np.full((count, 3), -1, dtype=np.int64)
    keep = np.zeros(count, dtype=bool)
    prev_tile = np.full(count, -1, dtype=np.int64)
    if previous is not None and previous.light_size.size:
        prev_tile = np.where(had[tile_light], previous.light_tiles[safe[tile_light], tile_face], -1)
    if previous is not None and previous.atlas_size == o.size and previous.light_size.size:
        exists = prev_tile >= 0
        prev_rect[exists] = previous.tile_rect[prev_tile[exists]]
        same = had & (previous.light_size[safe] == sizes) & (previous.light_cube[safe] == is_cube)
        keep = same[tile_light] & exists
    rect, repacked = _layout(side, rank, keep, prev_rect, grid=grid, cell=o.min_tile)
    # Index-safe: tile t keeps its meaning only if it was tile t, of the same key, there.
    moved = ~np.all(rect == prev_rect, axis=1) | (prev_tile != np.arange(count))
    x, y, s = (rect[:, i].astype(np.float64) for i in range(3))
    clamp = np.stack([x + 0.5, y + 0.5, x + s - 0.5, y + s - 0.5], axis=1) / o.size
    used = float((sizes.astype(np.float64) ** 2 * faces).sum() / float(o.size) ** 2)
    return ShadowAtlas(
        o.size, tile_light, tile_face, rect, sizes, light_tiles, moved, used, wish, ids,
        is_cube, border, clamp, repacked, ids[tile_light], prev_tile,
    )  # fmt: skip


def _unchanged(
    previous: ShadowAtlas | None, size: int, ids: Ints, sizes: Ints, is_cube: NDArray[np.bool_]
) -> bool:
    """The same lights with the same sizes and kinds as ``previous``: every tile stays."""
    return (
        previous is not None
        and previous.atlas_size == size
        and np.array_equal(previous.light_ids, ids)
        and np.array_equal(previous.light_size, sizes)
        and np.array_equal(previous.light_cube, is_cube)
    )


def _layout(
    side: Ints, rank: Ints, keep: NDArray[np.bool_], prev_rect: Ints, *, grid: int, cell: int
) -> tuple[Ints, bool]:
    """Each tile's ``(x, y, size)``: kept ones where they were, the others placed."""
    rect = np.empty((side.size, 3), dtype=np.int64)
    rect[:, 2] = side * cell
    if keep.all():
        return prev_rect.copy(), False
    codes = np.empty(side.size, dtype=np.int64)
    repacked = False
    if keep.any():
        kept = prev_rect[keep] // cell
        codes[keep] = tiles.morton_encode(kept[:, 0], kept[:, 1])
        occupied = tiles.occupancy(grid, codes[keep], side[keep])
        new = np.flatnonzero(~keep)
        for t in new[np.lexsort((rank[new], -side[new]))]:
            codes[t] = tiles.place(occupied, int(side[t]))
            if codes[t] < 0:
                repacked = True
                break
    if not keep.any() or repacked:
        codes = tiles.pack(side, rank)
    cx, cy = tiles.morton_decode(codes)
    rect[:, 0], rect[:, 1] = cx * cell, cy * cell
    return rect, repacked
