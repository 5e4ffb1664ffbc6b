r"""A shadow atlas for many lights: :func:`allocate_atlas`, :func:`fit_atlas`.

One square depth texture holds every light's shadow map as a power-of-two tile (six
face tiles for a point light's cube map). Per frame a renderer calls

1. :func:`allocate_atlas` with each light's screen coverage (and last frame's atlas):
   the tile sizes (Godot's rule, under a budget) and places (a quadtree, kept from
   frame to frame), on host integers (:mod:`shadowmath._math._atlas_tiles`);
2. :func:`fit_atlas` with the lights and their casters: one fit per tile, drawn
   with ``world_to_clip[t]`` inside ``viewports[t]`` and sampled with
   ``world_to_texture[t]``. The 2D lights are grouped by (kind, tile size, border)
   and each group runs :func:`fit_shadow`'s compiled loop once (NumPy with Numba) or
   its array driver (JAX, or NumPy alone); the cube lights' faces are
   :func:`cube_face_views` and :func:`cube_face_projection` with the border ring, on
   whole arrays;
3. :func:`atlas_redraw` with this frame's fit and the last one: the tiles to draw (a
   tile's identity is its key ``(light id, face)``, not its index).

The rule, the borders and the API conventions are written out in ``docs/atlas.md``.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from shadowmath._api._adaptive_frustum import border_margin
from shadowmath._api._api_convention import check_api as _check_api
from shadowmath._api._depth_bias import check_kernel as _check_kernel
from shadowmath._backends import _kernels
from shadowmath._boundary._shapes import ArrayLike, Bool, Float, Int, Real
from shadowmath._boundary._status import WIDE_WARNING, fit_messages
from shadowmath._boundary._validate import (
    RECEIVER_KINDS,
    Array,
    Checks,
    Context,
    convert,
    integer,
    non_finite,
    real,
    real_array,
    require_last,
    shape_error,
)
from shadowmath._math import _atlas_tiles as tiles
from shadowmath._math._bias import PcfFilter
from shadowmath._math._conventions import GraphicsApi
from shadowmath._math._conventions import texture_from_clip as _texture_from_clip
from shadowmath._math._cube import APIS as _APIS
from shadowmath._math._cube import cube_face_views as _cube_face_views
from shadowmath._math._cube import depth_row as _depth_row
from shadowmath._math._frame import stack_matrix
from shadowmath._math._pcf import border_texels as _border_texels
from shadowmath._math._rows import tile_rows
from shadowmath.lights import DirectionalLight, Light, PointLight, SpotLight
from shadowmath.receivers import Mesh, Triangles

from . import _compiled
from ._cube_depth import AT_LIGHT, cube_depth_core
from ._fit_arrays import Inputs, driver, fit_arrays
from ._light_kinds import KIND_OF, POINT, SPOT, SUN, homogeneous, spot_row
from ._setup import _receiver_kind, _receiver_rows, caster_triangles
from ._spec import FitKey, ShadowMapSpec, api_rows, map_spec
from ._spot_select import spot_selection

__all__ = [
    "AtlasFit",
    "ShadowAtlas",
    "allocate_atlas",
    "atlas_tile_transforms",
    "atlas_viewports",
    "fit_atlas",
]

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


class AtlasFit(NamedTuple):
    """Every tile's matrices (the result of :func:`fit_atlas`), in the chosen API's conventions.

    Attributes:
        world_to_clip: ``(T, 4, 4)`` draw tile ``t``'s casters with ``world_to_clip[t]``
            inside ``viewports[t]`` (scissor to it too).
        world_to_texture: ``(T, 4, 4)`` world to the atlas's ``(s q, t q, r q, q)``:
            ``(s, t)`` the atlas texture coordinates, ``r`` the depth stored there.
        viewports: ``(T, 4)`` ``(x, y, width, height)``, :func:`atlas_viewports`.
        tile_clamp: ``(T, 4)`` the atlas's :attr:`ShadowAtlas.tile_clamp`.
        near, far: ``(T,)`` each tile's depth range (light ``z`` for a 2D map, the
            distance along the face's axis for a cube face).
        texture_size: ``(width, height)`` of the depth texture to allocate, in texels:
            ``(atlas_size, atlas_size)``; every viewport lies inside it.
        tile_id, tile_face: ``(T,)`` each tile's key ``(light id, face)``, the
            atlas's :attr:`ShadowAtlas.tile_id` and :attr:`ShadowAtlas.tile_face`:
            cache a tile's depths by key, not by index.
        light_errors: ``(L,)`` per light ``None``, or the message of what was wrong with
            its fit (what :func:`fit_shadow` would raise for it, e.g. a caster within
            rounding of the light). Such a light's tiles get matrices that draw
            nothing and sample lit (OpenGL clip ``z = -2 w``: before the near plane;
            ``s = t = 1/2``) and ``near = far = 0``; every other light is fitted.

    Which tiles to redraw this frame: :func:`atlas_redraw` ``(fit, previous_fit)``,
    True where a tile is new, its viewport moved or resized, its ``world_to_clip``
    changed, or the texture did.
    """

    world_to_clip: Float[Array, "T 4 4"]
    world_to_texture: Float[Array, "T 4 4"]
    viewports: Int[Ints, "T 4"]
    tile_clamp: Float[NDArray[np.float64], "T 4"]
    near: Float[Array, " T"]
    far: Float[Array, " T"]
    texture_size: tuple[int, int]
    tile_id: Int[Ints, " T"]
    tile_face: Int[Ints, " T"]
    light_errors: tuple[str | None, ...] = ()


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
    return _allocate(cov, is_cube, border, ids, previous, options)


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


def _find_tiles(ids: Ints, faces: Ints, old_ids: Ints, old_faces: Ints) -> Ints:
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
    rect, repacked = _layout(side, rank, keep, prev_rect, grid, o.min_tile)
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
    side: Ints, rank: Ints, keep: NDArray[np.bool_], prev_rect: Ints, grid: int, cell: int
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


# ------------------------------------------------------------------ conventions


def atlas_viewports(atlas: ShadowAtlas, *, api: GraphicsApi = "opengl") -> Int[Ints, "T 4"]:
    r"""Each tile's viewport ``(x, y, width, height)`` in ``api``'s viewport convention.

    OpenGL counts viewport ``y`` from the bottom row of the framebuffer, which is
    the texture's first row in memory; Vulkan, Direct3D, Metal and WebGPU count it
    from the top row, which is *their* texture's first row in memory. ``tile_rect``'s
    ``y`` counts rows from the first row in memory, so in every API the viewport is
    ``(x, y, size, size)`` of the rect: the same numbers, each in its own convention
    (``docs/atlas.md`` derives it; the tests rasterize by each API's rules).

    Arguments:
        atlas: a :class:`ShadowAtlas`.
        api: ``"opengl"`` (default), ``"vulkan"``, ``"direct3d"``, ``"metal"`` or ``"webgpu"``.

    Returns:
        ``(T, 4)`` int64.

    Raises:
        ValueError: an unknown ``api``.

    Example:
        >>> a = allocate_atlas([1.0, 0.2], atlas_size=512)
        >>> atlas_viewports(a, api="vulkan").tolist()
        [[0, 0, 256, 256], [256, 0, 64, 64]]
    """
    _check_api(api, False)
    rect = atlas.tile_rect
    return np.concatenate([rect, rect[:, 2:3]], axis=1)


def atlas_tile_transforms(
    atlas: ShadowAtlas, *, api: GraphicsApi = "opengl"
) -> Float[NDArray[np.float64], "T 4 4"]:
    r"""The matrices from each tile's own texture coordinates to the atlas's.

    A tile at ``(x, y, n)`` in an ``A``-texel atlas holds its map's ``s, t in [0, 1]``
    at atlas texels ``x + n s``, ``y + n t`` (``t`` and ``y`` both count from the
    first row in memory, in every API), so

    .. math::

        T_\mathrm{tile} = \begin{bmatrix} n/A & 0 & 0 & x/A \\ 0 & n/A & 0 & y/A \\
        0 & 0 & 1 & 0 \\ 0 & 0 & 0 & 1 \end{bmatrix},
        \qquad M_\mathrm{world \to atlas} = T_\mathrm{tile}\, M_\mathrm{world \to tile}

    acting on homogeneous ``(s q, t q, r q, q)`` (``r`` and ``q`` unchanged).

    Arguments:
        atlas: a :class:`ShadowAtlas`.
        api: as in :func:`atlas_viewports` (the matrices are the same in every API).

    Returns:
        ``(T, 4, 4)`` float64.

    Raises:
        ValueError: an unknown ``api``.

    Example:
        >>> a = allocate_atlas([1.0, 0.2], atlas_size=512)
        >>> atlas_tile_transforms(a)[1] @ [1.0, 1.0, 0.5, 1.0]  # the tile's far corner
        array([0.625, 0.125, 0.5  , 1.   ])
    """
    _check_api(api, False)
    return _tile_transforms(atlas.tile_rect, atlas.atlas_size)


def _tile_transforms(rect: Ints, size: int) -> NDArray[np.float64]:
    """Each tile's matrix: the identity moved into the tile (the cascades' own formula)."""
    x, y, n = (rect[:, k].astype(np.float64) for k in range(3))
    one, zero = np.ones_like(x), np.zeros_like(x)
    identity = tuple(one if i % 5 == 0 else zero for i in range(16))
    rows = tile_rows(identity, (x, y, n, n), (float(size), float(size)))
    return np.stack(np.broadcast_arrays(*rows), axis=-1).reshape(-1, 4, 4)


# ------------------------------------------------------------------ fitting

_POINT, _SPOT, _SUN = POINT, SPOT, SUN


def fit_atlas(
    lights: Sequence[Light] | Real[ArrayLike, "L 4"] | Real[ArrayLike, "L 3"],
    blocker_vertices: Real[ArrayLike, "*#l N 3"] | Triangles | Mesh,
    atlas: ShadowAtlas,
    *,
    receivers: Real[ArrayLike, "M 3"] | Triangles | Mesh | None = None,
    near: Real[ArrayLike, "*#l"] | None = None,
    far: Real[ArrayLike, "*#l"] | None = None,
    api: GraphicsApi = "opengl",
    reversed_z: bool = False,
    pcf_radius: int | None = None,
    pcf_filter: PcfFilter = "box",
    spec: ShadowMapSpec | None = None,
) -> AtlasFit:
    r"""Fit every tile of an atlas: the matrices that draw and sample each light's map.

    * **2D light** (point, spot or directional): :func:`fit_shadow`'s fit with the
      tile's size and border (map ``n``, border ``b``: the casters stay within
      ``|x_ndc|, |y_ndc| <= (n - 2b) / n``), then moved into the tile:
      ``world_to_texture = T_tile @ T C P W`` (:func:`atlas_tile_transforms`).
    * **cube light**: face ``i``'s ``world_to_clip = P V_i`` with ``V_i`` of
      :func:`cube_face_views` and ``P`` of :func:`cube_face_projection` with the
      border ring ``b`` (scale ``k = (n - 2b) / n``); ``world_to_texture =
      T_tile @ T_api @ P V_i`` (``T_api`` the API's ``clip_to_texture``). ``near`` and
      ``far`` are :func:`cube_depth_range`'s: ``near = k D_min (1 - 1/64)`` and
      ``far = D_max (1 + 1/64)`` over the casters (and the receivers for ``far``), ``D``
      the largest absolute coordinate of ``p - light``: every caster drawn in a face,
      ring included, lies at a face depth ``>= k D``. ``D_min`` is over the casters'
      whole triangles when they are given as :class:`Triangles` or a :class:`Mesh` (a
      triangle can pass nearer the light than its corners), over the points otherwise.
      A renderer picks the face with :func:`cube_face`'s rule (the major axis of
      ``p - light``) and samples ``light_tiles[l, face]``.

    Arguments:
        lights: a sequence of ``L`` lights, each a :class:`PointLight`,
            :class:`SpotLight` or :class:`DirectionalLight` (each may hold a batch:
            its entries are consecutive lights); or an ``(L, 4)`` homogeneous array
            (``w = 0`` directional); or an ``(L, 3)`` array of point lights. Cube
            tiles need point lights.
        blocker_vertices: ``(N, 3)`` casters shared by every light, or ``(L, N, 3)``; or
            their surfaces, :class:`Triangles` ``([L,] M, 3, 3)`` or a :class:`Mesh`
            (the 2D fits use the corners; the cube faces' ``near`` the whole triangles).
        atlas: the :class:`ShadowAtlas` of these lights (``L`` entries).
        receivers: what the shadows fall on, shared by every light, as in
            :func:`fit_shadow`: ``(M, 3)`` points, :class:`Triangles` ``(M, 3, 3)`` or a
            :class:`Mesh` (each triangle clipped by a 2D map's sides, so a floor whose
            corners lie outside the map still counts). They only push ``far``.
        near, far: scalars or ``(L,)``: the depth range of the point and spot lights
            (ignored for directional ones, whose range is fitted), instead of the casters'.
        api, reversed_z: the graphics API's conventions (:func:`api_convention`).
        pcf_radius, pcf_filter: the kernel the atlas is sampled with: refused when a
            light's border is narrower than :func:`pcf_border_texels` of it.
        spec: instead of the four options above, the atlas texture's
            :class:`ShadowMapSpec` (size ``atlas.atlas_size``; its ``api``,
            ``reversed_z`` and PCF kernel used as above; its ``border_texels``, if
            given, at most every light's border; no ``margin``, no ``stable``). As in
            :func:`fit_shadow`, an option given both in it and as a keyword is refused.

    A spot light's tiles use the casters that reach into its cone's square pyramid
    (:func:`fit_shadow`'s selection): shared casters given as :class:`Triangles` or a
    :class:`Mesh` are clipped exactly to each spot's pyramid; a spot with nothing left
    gets the empty fit.

    Returns:
        :class:`AtlasFit`, one entry per tile of ``atlas`` (lights without a tile have
        none), with ``light_errors`` per light. NumPy input gives NumPy arrays;
        concrete JAX arrays (not under ``jit``: the atlas is host data) run the array
        driver and give JAX arrays.

    Raises:
        ValueError: what is wrong for the whole call: a light list of the wrong length
            or kind, a cube tile for a spot or directional light, non-finite casters or
            receivers, wrong shapes, an ``atlas`` that is not a :class:`ShadowAtlas`, an
            unknown ``api``, a kernel wider than a border, a ``spec`` that does not
            describe the atlas or beside conflicting keywords. What one light's geometry
            makes unfittable (what :func:`fit_shadow` would raise for it, a caster at a
            cube light's position) is not raised: it is reported in
            :attr:`AtlasFit.light_errors`, and every other light is fitted.

    Example:
        >>> import numpy as np, shadowmath as sm
        >>> box = np.array([[x, y, z] for x in (-1, 1) for y in (0, 2) for z in (-1, 1)], float)
        >>> lights = [sm.SpotLight(np.array([0.0, 6.0, 0.0]), np.array([0.0, -1.0, 0.0]),
        ...                        np.array(0.6)), sm.PointLight(np.array([3.0, 1.0, 0.0]))]
        >>> atlas = allocate_atlas([0.5, 0.25], atlas_size=1024, cube=[False, True])
        >>> fit = fit_atlas(lights, box, atlas, api="vulkan")
        >>> fit.world_to_clip.shape, fit.viewports[0].tolist()
        ((7, 4, 4), [0, 0, 256, 256])
    """
    if not isinstance(atlas, ShadowAtlas):
        raise ValueError(f"atlas: expected a ShadowAtlas (from allocate_atlas), got {atlas!r}")
    if spec is not None:
        options = {"api": api, "reversed_z": reversed_z, "pcf_radius": pcf_radius,
                   "pcf_filter": pcf_filter}  # fmt: skip
        api, reversed_z, pcf_radius, pcf_filter = _atlas_spec(spec, atlas, options)
    _check_api(api, reversed_z)
    count = atlas.light_size.shape[0]
    if pcf_radius is not None:
        need = _border_texels(*_check_kernel(pcf_radius, pcf_filter, ("pcf_radius", "pcf_filter")))
        if count and int(atlas.light_border.min()) < need:
            raise ValueError(
                f"pcf_radius: a {pcf_filter} kernel of radius {pcf_radius} needs borders of "
                f"{need} texels; the atlas has {int(atlas.light_border.min())} (allocate it "
                f"with border_texels=sm.pcf_border_texels({pcf_radius}, {pcf_filter!r}))"
            )
    kinds, data = _read_lights(lights, count)
    c_kind, c_name, c_array = _receiver_kind(blocker_vertices, "blocker_vertices")
    r_kind, r_name, r_array = _receiver_kind(receivers)
    ctx, (data, verts, R, n, f) = convert(
        lights=data, **{c_name: c_array}, **{r_name: r_array}, near=near, far=far
    )
    xp = ctx.xp
    tris = None  # surfaces: a cube face's near counts their insides; the 2D fits, corners
    if c_kind != "points":
        tris = caster_triangles(ctx, c_kind, verts, blocker_vertices, "blocker_vertices")
        verts = xp.reshape(tris, (*tris.shape[:-3], -1, 3))
    if R is not None:
        R = _receiver_rows(ctx, r_kind, R, receivers)
    _check_arrays(verts, R, n, f, count)
    for name, v in (("blocker_vertices", verts), ("receivers", R)):
        if v is not None and not ctx.lazy and not bool(xp.all(xp.isfinite(v))):
            raise ValueError(non_finite(name))
    if bool(np.any(atlas.light_cube & (kinds != _POINT))):
        i = int(np.flatnonzero(atlas.light_cube & (kinds != _POINT))[0])
        raise ValueError(f"lights[{i}]: a cube map needs a point light (atlas cube=True)")
    report = _Report(ctx, api, reversed_z, count)
    parts: list[tuple[Ints, Array, Array, Array, Array]] = []
    flat = _fit_2d(ctx, atlas, kinds, data, verts, R, n, f, tris=tris, report=report)
    parts.extend(flat)
    cubes = np.flatnonzero(atlas.light_cube & (atlas.light_size > 0))
    if cubes.size:
        parts.append(_fit_cubes(ctx, atlas, cubes, data, verts, tris, R, n, f, api, report))
    T = xp.asarray(_tile_transforms(atlas.tile_rect, atlas.atlas_size), dtype=ctx.dtype)
    clip, tex, lo, hi = _gather(ctx, parts, atlas.tile_light.shape[0])
    errors = tuple(report.errors)
    return AtlasFit(
        clip, T @ tex, atlas_viewports(atlas), atlas.tile_clamp, lo, hi,
        texture_size=(atlas.atlas_size, atlas.atlas_size), tile_id=atlas.tile_id,
        tile_face=atlas.tile_face, light_errors=errors,
    )  # fmt: skip


def _atlas_spec(
    spec: Any, atlas: ShadowAtlas, options: dict[str, Any]
) -> tuple[Any, bool, int | None, PcfFilter]:
    """The options of the atlas texture's spec, checked against the atlas and the keywords."""
    if not isinstance(spec, ShadowMapSpec):
        raise ValueError(f"spec: expected a ShadowMapSpec or None, got {type(spec).__name__}")
    map_spec(spec, **options)
    n = atlas.atlas_size
    if spec.size != (n, n):
        raise ValueError(f"spec: its size {spec.size} is not the atlas's ({n}, {n})")
    if spec.stable or spec.margin is not None:
        raise ValueError("spec: an atlas's tiles take no stable or margin option")
    borders = atlas.light_border
    if spec.border_texels is not None and borders.size and borders.min() < spec.border_texels:
        raise ValueError(
            f"spec: border_texels={spec.border_texels}, but the atlas leaves "
            f"{int(borders.min())} (allocate it with border_texels={spec.border_texels})"
        )
    return spec.api, spec.reversed_z, spec.pcf_radius, spec.pcf_filter


class _Report:
    """Each light's error message (None: fitted), and the matrices a failed light's tiles
    get: OpenGL clip ``N`` with rows ``0, 0, (0, 0, 0, -2), (0, 0, 0, 1)`` (every point at
    ``z = -2 w``, before the near plane: clipped, and sampled lit), then ``C N`` and
    ``T C N`` in the API's conventions."""

    def __init__(self, ctx: Context, api: str, reversed_z: bool, count: int) -> None:
        N = np.zeros((4, 4))
        N[2, 3], N[3, 3] = -2.0, 1.0
        self.api = api_rows(api, bool(reversed_z))
        C, TC = (np.array(r).reshape(4, 4) for r in self.api)
        self.clip, self.tex = (ctx.xp.asarray(m, dtype=ctx.dtype) for m in (C @ N, TC @ N))
        self.reversed_z = reversed_z
        self.errors: list[str | None] = [None] * count

    def fail(self, light: int, message: str) -> None:
        if self.errors[light] is None:
            self.errors[light] = message

    def replace(
        self, ctx: Context, failed: Any, values: tuple[Array, Array, Array, Array]
    ) -> tuple[Array, ...]:
        """``(clip, tex, near, far)`` with the ``failed`` ``(K,)`` entries replaced."""
        if not bool(np.any(failed)):
            return values
        xp = ctx.xp
        bad = xp.asarray(failed)
        clip, tex, lo, hi = values
        zero = xp.zeros_like(lo)
        return (
            xp.where(bad[:, None, None], self.clip, clip),
            xp.where(bad[:, None, None], self.tex, tex),
            xp.where(bad, zero, lo),
            xp.where(bad, zero, hi),
        )


def _gather(ctx: Context, parts: list[Any], total: int) -> tuple[Array, ...]:
    """The parts' ``(tiles, clip, texture, near, far)`` in tile order."""
    xp = ctx.xp
    if xp is np:  # scattered into place: no concatenation
        clip, tex = np.empty((2, total, 4, 4), dtype=ctx.dtype)
        lo, hi = np.empty((2, total), dtype=ctx.dtype)
        for tiles_, *values in parts:
            for out, v in zip((clip, tex, lo, hi), values, strict=True):
                out[tiles_] = v
        return clip, tex, lo, hi
    if not parts:
        return xp.zeros((0, 4, 4), ctx.dtype), xp.zeros((0, 4, 4), ctx.dtype), \
            xp.zeros(0, ctx.dtype), xp.zeros(0, ctx.dtype)  # fmt: skip
    back = np.empty(total, dtype=np.int64)
    back[np.concatenate([p[0] for p in parts])] = np.arange(total)
    return tuple(xp.concatenate([p[k] for p in parts])[back] for k in range(1, 5))


def _read_lights(lights: Any, count: int) -> tuple[Ints, Any]:
    """Each light's kind and its ``(L, 8)`` row: position or direction, then a spot's
    axis, ``tan(angle)`` and angle."""
    if isinstance(lights, _TYPED):
        lights = [lights]
    if isinstance(lights, list | tuple) and (not lights or isinstance(lights[0], _TYPED)):
        kinds: list[int] = []
        rows: list[list[float]] = []
        for i, light in enumerate(lights):
            kind = _KINDS.get(type(light))
            if kind is None:
                raise ValueError(
                    f"lights[{i}]: expected sm.PointLight, sm.SpotLight or sm.DirectionalLight, "
                    f"got {type(light).__name__}"
                )
            first = light[0]
            if type(first) is np.ndarray and first.shape == (3,):  # one light: the common case
                if kind != _SPOT:
                    kinds.append(kind)
                    rows.append(first.tolist() + _PAD)
                    continue
                d, a = light[1], light[2]
                if type(d) is np.ndarray and d.shape == (3,) and _scalar(a):
                    kinds.append(_SPOT)
                    rows.append(spot_row(first.tolist(), d.tolist(), float(a)))
                    continue
            _typed_rows(light, kinds, rows)
        kind_arr = np.array(kinds, dtype=np.int64)
        data = np.array(rows, dtype=np.float64).reshape(-1, 8)
    else:
        arr = np.asarray(lights) if not hasattr(lights, "shape") else lights
        if arr.ndim != 2 or arr.shape[-1] not in (3, 4):
            raise shape_error(
                "lights", "a sequence of typed lights, (L, 4) or (L, 3)", tuple(arr.shape),
                "a homogeneous light is (x, y, z, w), w = 0 directional",
            )  # fmt: skip
        arr = np.asarray(arr, dtype=np.float64)
        if arr.shape[-1] == 3:  # positions of point lights
            arr = np.concatenate([arr, np.ones((arr.shape[0], 1))], axis=1)
        with np.errstate(all="ignore"):
            sun, xyz = homogeneous(np, arr)
        kind_arr = np.where(sun, _SUN, _POINT).astype(np.int64)
        data = np.concatenate([xyz, np.zeros((arr.shape[0], 5))], axis=1)
    if kind_arr.shape[0] != count:
        raise ValueError(f"lights: the atlas has {count} lights, got {kind_arr.shape[0]}")
    return kind_arr, data


_TYPED = (PointLight, SpotLight, DirectionalLight)
_KINDS = KIND_OF
_PAD = [0.0] * 5


def _scalar(a: object) -> bool:
    return type(a) is float or (type(a) is np.ndarray and a.shape == ())


def _typed_rows(light: Any, kinds: list[int], rows: list[list[float]]) -> None:
    """Append a typed light's rows (one per batch entry)."""
    spot = isinstance(light, SpotLight)
    first = np.asarray(light[0], dtype=np.float64)
    require_last("light.position" if spot else "light", first, 3)
    if not spot:
        kind = _SUN if isinstance(light, DirectionalLight) else _POINT
        for v in first.reshape(-1, 3).tolist():
            kinds.append(kind)
            rows.append(v + _PAD)
        return
    d = np.asarray(light.direction, dtype=np.float64)
    require_last("light.direction", d, 3)
    p = first.reshape(-1, 3)
    count = p.shape[0]
    d = np.broadcast_to(d.reshape(-1, 3), (count, 3))
    a = np.broadcast_to(np.asarray(light.angle, dtype=np.float64).reshape(-1), (count,))
    for pi, di, ai in zip(p.tolist(), d.tolist(), a.tolist(), strict=True):
        kinds.append(_SPOT)
        rows.append(spot_row(pi, di, ai))


def _check_arrays(
    verts: Array, R: Array | None, n: Array | None, f: Array | None, count: int
) -> None:
    if verts.ndim not in (2, 3) or verts.shape[-1] != 3 or verts.shape[-2] == 0:
        raise shape_error("blocker_vertices", "(N, 3) or (L, N, 3), N >= 1", tuple(verts.shape))
    if verts.ndim == 3 and verts.shape[0] != count:
        raise shape_error("blocker_vertices", f"({count}, N, 3)", tuple(verts.shape),
                          "one caster set per light")  # fmt: skip
    if R is not None and R.ndim != 2:  # rows of 3 (points) or 9 (triangles), checked
        hint = f"one set of receivers shared by every light. {RECEIVER_KINDS}"
        raise shape_error("receivers", "(M, 3) points or M triangles", tuple(R.shape), hint)
    for name, v in (("near", n), ("far", f)):
        if v is not None and (v.ndim > 1 or (v.ndim == 1 and v.shape[0] != count)):
            raise shape_error(name, f"() or ({count},)", tuple(v.shape))


def _fit_2d(
    ctx: Context, atlas: ShadowAtlas, kinds: Ints, data: Array, verts: Array, R: Array | None,
    n: Array | None, f: Array | None, *, tris: Array | None, report: _Report,
) -> list[tuple[Ints, Array, Array, Array, Array]]:  # fmt: skip
    """One fit per group of 2D lights of one (kind, size, border).

    The lights are sorted by group, so each group is a slice; the compiled loop of each
    group writes straight into its slice of one output block. A spot group's casters are
    selected per light first (:func:`spot_selection`: triangles clipped to each cone's
    square pyramid). A light whose fit fails is reported and gets ``report``'s matrices.
    """
    lights = np.flatnonzero((~atlas.light_cube) & (atlas.light_size > 0))
    if lights.size == 0:
        return []
    code = (kinds[lights] << 40) | (atlas.light_size[lights] << 16) | atlas.light_border[lights]
    order = np.argsort(code, kind="stable")
    lights, code = lights[order], code[order]
    starts = [0, *(np.flatnonzero(code[1:] != code[:-1]) + 1).tolist()]
    ends = [*starts[1:], lights.size]
    rows = report.api
    light_rows = data[lights]
    positions = light_rows[:, :3] if ctx.is_jax else np.ascontiguousarray(light_rows[:, :3])
    per_light = verts[lights] if verts.ndim == 3 else None
    near_all = None if n is None else _pick(ctx, n, lights)
    far_all = None if f is None else _pick(ctx, f, lights)
    compiled = not ctx.is_jax and _kernels.available()
    block = _Block(ctx, lights.size) if compiled else None
    out = []
    for start, end, c in zip(starts, ends, code[starts].tolist(), strict=True):
        kind, size, border = c >> 40, (c >> 16) & 0xFFFFFF, c & 0xFFFF
        sun = kind == _SUN
        given = (not sun and n is not None, not sun and f is not None)
        key = _group_key(kind, size, border, rows, _receiver_flags(R), given)
        part = slice(start, end)
        group = verts if per_light is None else per_light[part]
        if kind == _SPOT:
            casters = group if tris is None else tris if tris.ndim == 3 else tris[lights[part]]
            selected = spot_selection(ctx, light_rows[part], None, None, casters, tris is not None)
            group = selected.points
        a = Inputs(
            light_rows[part] if kind == _SPOT else positions[part], group, None, R, None,
            None if near_all is None or sun else near_all[part],
            None if far_all is None or sun else far_all[part],
        )  # fmt: skip
        if block is not None:
            block.run(key, a, part, lights, report)
        else:
            values = _run_arrays(ctx, key, a, lights[part], report)
            out.append((atlas.light_tiles[lights[part], 0], *values))
    if block is not None:
        mats, frusta = block.mats, block.out
        return [
            (atlas.light_tiles[lights, 0], mats[:, 1], mats[:, 2], frusta[:, 14], frusta[:, 15])
        ]
    return out


class _Block:
    """The compiled loop's output for every 2D light, filled group by group."""

    def __init__(self, ctx: Context, count: int) -> None:
        self.ctx = ctx
        self.out = np.empty((count, _compiled.ROW), dtype=ctx.dtype)
        self.mats = np.empty((count, 4, 4, 4), dtype=ctx.dtype)
        self.status = np.empty(count, dtype=np.int32)

    def run(self, key: FitKey, a: Inputs, part: slice, lights: Ints, report: _Report) -> None:
        count = part.stop - part.start
        status = self.status[part]
        operands = _compiled.operands((count,), a, count == 1)
        options, _ = _compiled.options(key, self.ctx.dtype)
        _kernels.loops().fit_loop(operands, options, (self.out[part], self.mats[part], status))
        errors = status & ~WIDE_WARNING
        if errors.any():
            messages = fit_messages(bool(np.isfinite(a.verts).all()))
            for i in np.flatnonzero(errors).tolist():
                report.fail(int(lights[part][i]), next(m for b, m in messages if errors[i] & b))
            failed = errors != 0
            mats, out = self.mats[part], self.out[part]
            mats[failed, 1], mats[failed, 2] = report.clip, report.tex
            out[failed, 14:16] = 0.0


def _pick(ctx: Context, v: Array, idx: Ints) -> Array:
    return ctx.xp.broadcast_to(v, (idx.size,)) if v.ndim == 0 else v[idx]


def _receiver_flags(R: Array | None) -> tuple[bool, bool]:
    """Whether there are receivers, and whether they are triangles (rows of 9)."""
    return R is not None, R is not None and R.shape[-1] == 9


@functools.lru_cache(maxsize=256)
def _group_key(
    kind: int, size: int, border: int, rows: Any, receivers: tuple[bool, bool],
    given: tuple[bool, bool],
) -> FitKey:  # fmt: skip
    margins = border_margin(size, border_texels=border)
    return FitKey(kind == _SUN, kind == _SPOT, False, False, margins, (size, size), rows,
                  False, receivers[0], False, *given, triangles=receivers[1])  # fmt: skip


def _run_arrays(
    ctx: Context, key: FitKey, a: Inputs, idx: Ints, report: _Report
) -> tuple[Array, ...]:
    """``world_to_clip``, the tile's ``world_to_texture``, near and far of one group, on
    whole arrays (JAX, or NumPy without the compiled loops)."""
    count = idx.size
    if ctx.xp is np and count <= _SCALAR_GROUP:
        return _run_scalars(ctx, key, a, idx, report)
    checks = Checks(ctx, mode="record")
    with np.errstate(all="ignore"):
        e = fit_arrays(ctx, checks, key, a, driver(ctx, scalar=False))
    xp = ctx.xp
    clip, tex = (stack_matrix(xp, tuple(xp.broadcast_to(v, (count,)) for v in m))
                 for m in (e.clip, e.tex))  # fmt: skip
    lo, hi = (xp.broadcast_to(v, (count,)) for v in (e.box[2], e.box[3]))
    failed = np.zeros(count, dtype=bool)
    for message, bad in checks.recorded:  # in report order: the first failure is kept
        bad_np = np.broadcast_to(np.asarray(bad), (count,))
        for i in np.flatnonzero(bad_np).tolist():
            report.fail(int(idx[i]), message)
        failed |= bad_np
    return report.replace(ctx, failed, (clip, tex, lo, hi))


#: NumPy without the compiled loops fits groups of at most this many lights one light at a
#: time on Python floats (as fit_shadow does one light): the array driver's hundreds of
#: NumPy calls cost more than that below it.
_SCALAR_GROUP = 8


def _run_scalars(
    ctx: Context, key: FitKey, a: Inputs, idx: Ints, report: _Report
) -> tuple[Array, ...]:
    """:func:`_run_arrays` one light at a time with the per-entry steps on Python floats."""
    d = driver(ctx, scalar=True)
    mats, depth = [], []
    for i, light in enumerate(idx.tolist()):
        one = Inputs(
            a.light[i], a.verts if a.verts.ndim == 2 else a.verts[i], None, a.R, None,
            None if a.near is None else a.near[i], None if a.far is None else a.far[i],
        )  # fmt: skip
        try:
            with np.errstate(all="ignore"):
                e = fit_arrays(ctx, Checks(ctx), key, one, d)
        except ValueError as err:
            report.fail(light, str(err))
            mats.append((*report.clip.reshape(16).tolist(), *report.tex.reshape(16).tolist()))
            depth.append((0.0, 0.0))
            continue
        mats.append((*e.clip, *e.tex))
        depth.append((e.box[2], e.box[3]))
    m = np.array(mats, dtype=ctx.dtype).reshape(-1, 2, 4, 4)
    z = np.array(depth, dtype=ctx.dtype)
    return m[:, 0], m[:, 1], z[:, 0], z[:, 1]


def _fit_cubes(
    ctx: Context, atlas: ShadowAtlas, cubes: Ints, data: Array, verts: Array,
    tris: Array | None, R: Array | None, n: Array | None, f: Array | None, api: str,
    report: _Report,
) -> tuple[Ints, Array, Array, Array, Array]:  # fmt: skip
    """The six faces of every cube light at once: ``(tiles, clip, texture, near, far)``;
    a light with a non-finite position, a caster at it or a bad depth range is reported."""
    xp = ctx.xp
    finite = np.asarray(xp.all(xp.isfinite(data[cubes, :3]), axis=1))
    P = xp.where(xp.asarray(finite)[:, None], data[cubes, :3], 0.0)
    size = atlas.light_size[cubes].astype(np.float64)
    k = xp.asarray((size - 2 * atlas.light_border[cubes]) / size, dtype=ctx.dtype)
    VT = xp.matrix_transpose(verts[None] if verts.ndim == 2 else verts[cubes])
    corners = None if R is None else xp.reshape(R, (-1, 3))[None]
    T = None if tris is None else (tris[None] if tris.ndim == 3 else tris[cubes])
    near, far, clear = cube_depth_core(xp, P, VT, corners, k, ctx.eps, T)
    lo = near if n is None else _pick(ctx, n, cubes)
    hi = far if f is None else _pick(ctx, f, cubes)
    ranged = np.asarray(xp.isfinite(lo) & xp.isfinite(hi) & (lo > 0) & (hi > lo))
    failed = ~(finite & np.asarray(clear) & ranged)
    for i in np.flatnonzero(failed).tolist():
        report.fail(int(cubes[i]), _cube_message(finite[i], bool(np.asarray(clear)[i])))
    bad = xp.asarray(failed)
    lo, hi = xp.where(bad, 1.0, lo), xp.where(bad, 2.0, hi)  # safe: replaced below
    zero_to_one, flip_y = _APIS[api]
    a, b = _depth_row(lo, hi, zero_to_one, bool(report.reversed_z))
    Pm = _face_projections(xp, k, -k if flip_y else k, a, b)
    clip = Pm[:, None] @ _cube_face_views(xp, P)  # (C, 6, 4, 4)
    T = ctx.constant(_texture_from_clip(api, bool(report.reversed_z)))
    tex = T @ clip
    tile = atlas.light_tiles[cubes].reshape(-1)
    values = (clip.reshape(-1, 4, 4), tex.reshape(-1, 4, 4), xp.repeat(lo, 6), xp.repeat(hi, 6))
    return (tile, *report.replace(ctx, np.repeat(failed, 6), values))


def _cube_message(finite: bool, clear: bool) -> str:
    if not finite:
        return non_finite("light")
    if not clear:
        return f"{AT_LIGHT}, or give near="
    return "near and far must be finite with 0 < near < far"


def _face_projections(xp: Any, kx: Array, ky: Array, a: Array, b: Array) -> Array:
    """``(C, 4, 4)`` :func:`cube_face_projection` matrices, one per light (written in place
    for NumPy: sixteen broadcasts cost more than the fit)."""
    if xp is not np:
        zero = xp.zeros_like(kx)
        return stack_matrix(xp, (kx, zero, zero, zero, zero, ky, zero, zero,
                                 zero, zero, a, b, zero, zero, zero - 1, zero))  # fmt: skip
    P = np.zeros((kx.shape[0], 4, 4), dtype=np.result_type(kx, a))
    P[:, 0, 0], P[:, 1, 1], P[:, 2, 2], P[:, 2, 3], P[:, 3, 2] = kx, ky, a, b, -1.0
    return P
