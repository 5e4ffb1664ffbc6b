r"""The shadow atlas's allocation rule, on integer arrays (trusted inputs).

Everything here counts in *cells* of ``min_tile x min_tile`` texels: the atlas is a
``G x G`` grid of cells, ``G = atlas_size / min_tile``, and a tile of ``size`` texels is
an aligned square of ``c = size / min_tile`` cells (``c`` a power of two).

**The quadtree as a line.** Number the cells along the Morton (Z-order) curve: the
code of cell ``(cx, cy)`` interleaves the bits of ``cx`` (even bits) and ``cy`` (odd
bits). Every node of the atlas's quadtree of side ``c`` cells is then the contiguous,
aligned range ``[k c^2, (k + 1) c^2)`` of codes, so the quadtree allocator is a
one-dimensional buddy allocator: a tile is a code range, free space is a boolean
array, and a node is free when its range is.

* :func:`size_classes`: each light's wish, Godot's rule with hysteresis.
* :func:`shrink_to_budget`: the wishes halved, least-covering light first, until
  their area fits the budget.
* :func:`pack`: a fresh layout: tiles sorted by size (largest first) laid one after
  another along the curve. Since every area is a power of four no smaller than
  those after it, each tile starts at a multiple of its own area: aligned,
  disjoint, and with no hole before the last tile, so it always succeeds when the
  total area fits.
* :func:`place`: a tile added to an atlas in use, in the free node of its size
  whose largest free ancestor is smallest (best fit: the buddy allocator's rule,
  which keeps large free nodes whole), ties to the lowest code.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

Ints = NDArray[np.int64]
Bools = NDArray[np.bool_]


def morton_encode(cx: Ints, cy: Ints) -> Ints:
    """The Morton code of cells ``(cx, cy)``: ``cx``'s bits at even, ``cy``'s at odd places."""
    return _spread(cx) | (_spread(cy) << 1)


def morton_decode(code: Ints) -> tuple[Ints, Ints]:
    """The cells ``(cx, cy)`` of Morton codes (the inverse of :func:`morton_encode`)."""
    return _compact(code), _compact(code >> 1)


def _spread(v: Ints) -> Ints:
    """Bits ``b_i`` of ``v`` (< 2^16) moved to places ``2 i``."""
    v = v.astype(np.int64) & 0xFFFF
    v = (v | (v << 8)) & 0x00FF00FF
    v = (v | (v << 4)) & 0x0F0F0F0F
    v = (v | (v << 2)) & 0x33333333
    return (v | (v << 1)) & 0x55555555


def _compact(v: Ints) -> Ints:
    """Bits at places ``2 i`` of ``v`` moved to places ``i`` (the inverse of :func:`_spread`)."""
    v = v & 0x55555555
    v = (v | (v >> 1)) & 0x33333333
    v = (v | (v >> 2)) & 0x0F0F0F0F
    v = (v | (v >> 4)) & 0x00FF00FF
    return (v | (v >> 8)) & 0xFFFF


def size_classes(
    coverage: NDArray[np.float64],
    max_tile: int,
    min_tile: int,
    previous: Ints | None,
    hysteresis: float,
) -> Ints:
    r"""Each light's wished tile size: Godot's rule, clamped, with hysteresis.

    Godot (``shadow_atlas_update_light``) asks for ``next_power_of_2(quad_size *
    coverage)`` with ``quad_size`` half the atlas; here ``raw = coverage * max_tile``
    (``max_tile`` defaults to that half) and the class is the smallest power of two
    ``>= raw``, clamped to ``[min_tile, max_tile]``; ``coverage = 0`` asks for nothing.
    A light whose previous wish ``p`` is given keeps it while
    ``p (1 - h) / 2 < raw <= p (1 + h)``: a light on a class boundary does not flip
    between two sizes (and two places) from frame to frame.
    """
    raw = coverage * max_tile
    mantissa, exponent = np.frexp(raw)  # raw = mantissa 2^exponent, mantissa in [0.5, 1)
    exponent -= mantissa == 0.5  # an exact power of two is its own class
    lo, hi = min_tile.bit_length() - 1, max_tile.bit_length() - 1
    fresh = np.left_shift(1, np.minimum(np.maximum(exponent, lo), hi), dtype=np.int64)
    if previous is not None:
        keep = (previous >= min_tile) & (previous <= max_tile)
        keep &= (raw > previous * ((1 - hysteresis) / 2)) & (raw <= previous * (1 + hysteresis))
        fresh = np.where(keep, previous, fresh)
    return np.where(raw > 0, fresh, 0)


def cells(sizes: Ints, min_tile: int, faces: Ints) -> Ints:
    """The area of each light's tiles in cells (0 for size 0)."""
    side = sizes // min_tile
    return side * side * faces


def shrink_to_budget(
    wish: Ints, faces: Ints, order: Ints, min_tile: int, budget_cells: int
) -> Ints:
    r"""The sizes actually given: the wishes, halved in rounds until their area fits.

    ``order`` lists the lights first to last in priority. While the area exceeds the
    budget, rounds go through the lights from the *last* up, halving each light's size
    in turn (a light at ``min_tile`` keeps it) and stopping as soon as the total fits;
    when every light is at ``min_tile`` and the total still exceeds the budget, lights
    drop (size 0: no shadow this frame), again from the last up. So every light loses
    resolution before any loses its shadow, the last in priority pay first, and a light
    ahead never ends with the smaller tile. Each round is computed at once: the running
    sum of the savings, cut where it covers the excess.
    """
    total = int(cells(wish, min_tile, faces).sum())
    if total <= budget_cells:
        return wish
    last_first = order[::-1]
    cur = wish[last_first].copy()
    f = faces[last_first]
    while True:
        half = np.where(cur > min_tile, cur // 2, cur)
        saving = np.cumsum(cells(cur, min_tile, f) - cells(half, min_tile, f))
        if saving[-1] == 0:  # all at min_tile: drop lights, the last first
            saving = np.cumsum(cells(cur, min_tile, f))
            half = np.zeros_like(cur)
        j = int(np.searchsorted(saving, total - budget_cells))
        if j < len(saving):
            cur[: j + 1] = half[: j + 1]
            break
        cur, total = half, total - int(saving[-1])
    sizes = np.empty_like(wish)
    sizes[last_first] = cur
    return sizes


def pack(side: Ints, rank: Ints) -> Ints:
    """A fresh layout: the Morton code of each tile's first cell.

    ``side`` is each tile's side in cells, ``rank`` its order among equal sides
    (priority, then face). Larger tiles first, then by rank.
    """
    order = np.lexsort((rank, -side))
    area = side[order] * side[order]
    start = np.empty_like(area)
    start[0:1] = 0
    np.cumsum(area[:-1], out=start[1:])
    codes = np.empty_like(start)
    codes[order] = start
    return codes


def occupancy(grid: int, codes: Ints, side: Ints) -> Bools:
    """``(grid^2,)`` True on the cells (Morton order) covered by the tiles."""
    diff = np.zeros(grid * grid + 1, dtype=np.int64)
    np.add.at(diff, codes, 1)
    np.add.at(diff, codes + side * side, -1)
    return np.cumsum(diff[:-1]) > 0


def place(occupied: Bools, side: int) -> int:
    """The first cell's code of a free node of ``side`` cells (best fit), or -1 if none.

    Marks the node occupied. Best fit: among the free nodes of that side, the one
    whose largest entirely free ancestor is smallest, then the lowest code.
    """
    n = side * side
    free: Bools = np.logical_not(occupied.reshape(-1, n).any(axis=1))
    candidates = np.flatnonzero(free)
    if candidates.size == 0:
        return -1
    rank = np.zeros(candidates.size, dtype=np.int64)
    level, span = 1, n * 4
    while span <= occupied.size:
        parent_free: Bools = np.logical_not(occupied.reshape(-1, span).any(axis=1))
        inside = parent_free[candidates >> (2 * level)]
        if not inside.any():
            break
        rank += inside
        level, span = level + 1, span * 4
    k = int(candidates[np.argmin(rank)])  # argmin: the first (lowest code) of the least rank
    occupied[k * n : (k + 1) * n] = True
    return k * n
