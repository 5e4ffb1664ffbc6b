r"""Percentage-closer filtering: a reference lookup of a depth shadow map.

Reeves, Salesin and Cook's percentage-closer filter (seeds 001, 002) compares the
receiver's depth with several stored depths around its texture coordinates and
returns the fraction of comparisons that find it lit, instead of filtering the
depths themselves (an average of depths compared once is not a fraction of
anything). Texel ``(row i, column j)`` of a ``W x H`` map has its centre at
``s = (j + 1/2) / W``, ``t = (i + 1/2) / H``; row ``0`` is the first row in memory
(``t = 0``, as :func:`api_convention` arranges for every API).

* ``"box"`` of radius ``k``: the ``(2k + 1)^2`` texels around the texel that
  contains ``(s, t)``, equally weighted (``textureOffset`` loops with nearest
  sampling).
* ``"bilinear"`` of radius ``k``: ``(2k + 1)^2`` taps at ``(s, t)`` offset by whole
  texels, each the bilinear interpolation of the comparisons at the four texel
  centres around it (a ``sampler2DShadow`` with linear filtering). Summed, texel
  ``(a, b)`` texels from the one below-left of ``(s, t)`` (``a, b in -k..k+1``)
  gets the separable weight ``w(a) w(b) / (2k + 1)^2`` with ``w(-k) = 1 - f``,
  ``w(k + 1) = f`` and ``1`` in between (``f`` the fractional position between
  texel centres); the weights sum to ``1`` and vary continuously with ``(s, t)``.

Trusted cores only: the public functions, which check their arguments and
call these, are in :mod:`shadowmath._geometry._pcf_lookup`.
"""

from __future__ import annotations

import math
from types import ModuleType
from typing import Any

import numpy as np

from shadowmath._boundary._shapes import Float
from shadowmath._boundary._validate import Array

from ._bias import PcfFilter, kernel_reach


def border_texels(radius: int, filter: PcfFilter) -> int:
    return max(1, math.ceil(kernel_reach(radius, filter) - 0.5))


def _compare(
    xp: ModuleType,
    depths: Float[Array, "..."],
    stored: Float[Array, "..."],
    reversed_z: bool,
    softness: float,
) -> Float[Array, "..."]:
    """1 where lit (``depth <= stored``, ``>=`` reversed), a C1 smoothstep of width ``softness``."""
    margin = depths - stored if reversed_z else stored - depths
    if softness == 0:
        return xp.astype(margin >= 0, depths.dtype)
    x = xp.clip(margin / softness + 0.5, 0.0, 1.0)
    return x * x * (3 - 2 * x)


def pcf(
    xp: ModuleType,
    depth_map: Float[Array, "*#map H W"],
    coords: Float[Array, "*#batch 2"],
    depths: Float[Array, "*#batch"],
    *,
    radius: int,
    filter: PcfFilter,
    reversed_z: bool,
    softness: float,
) -> Float[Array, "*batch"]:
    """The lit fraction (trusted inputs; ``shape`` the broadcast batch shape)."""
    H, W = depth_map.shape[-2:]
    map_batch = depth_map.shape[:-2]
    shape = tuple(np.broadcast_shapes(map_batch, coords.shape[:-1], depths.shape))
    dtype = coords.dtype
    if filter == "box":
        col0 = xp.floor(coords[..., 0] * W)
        row0 = xp.floor(coords[..., 1] * H)
        offsets = xp.asarray(list(range(-radius, radius + 1)), dtype=dtype)
    else:
        u = coords[..., 0] * W - 0.5
        v = coords[..., 1] * H - 0.5
        col0, row0 = xp.floor(u), xp.floor(v)
        fx, fy = u - col0, v - row0
        offsets = xp.asarray(list(range(-radius, radius + 2)), dtype=dtype)
    cols = col0[..., None, None] + offsets[None, :]  # (*, 1, A)
    rows = row0[..., None, None] + offsets[:, None]  # (*, A, 1)
    inside = (cols >= 0) & (cols <= W - 1) & (rows >= 0) & (rows <= H - 1)
    col_i = xp.astype(xp.clip(cols, 0, W - 1), xp.int32)
    row_i = xp.astype(xp.clip(rows, 0, H - 1), xp.int32)
    # Integer-array indexing over the map's batch axes (aligned to the right of the
    # result's batch shape), then the row and column of every kernel texel.
    lead = len(shape) - len(map_batch)
    index: list[Any] = []
    for axis, size in enumerate(map_batch):
        at = [1] * (len(shape) + 2)
        at[lead + axis] = size
        index.append(xp.reshape(xp.arange(size), tuple(at)) if size > 1 else 0)
    stored = depth_map[(*index, row_i, col_i)]  # (*shape, A, A)
    lit = _compare(xp, depths[..., None, None], xp.astype(stored, dtype), reversed_z, softness)
    lit = xp.where(inside, lit, xp.ones_like(lit))
    if filter == "box":
        total = xp.sum(lit, axis=(-2, -1))
    else:
        # The tent weights as sums plus one lerp per axis: w(-k) = 1 - f, w(k+1) = f,
        # so sum_a w(a) L(a) = sum_{a<=k} L(a) + f (L(k+1) - L(-k)), exact when L is
        # constant (a constant map gives exactly 0 or 1).
        rows_sum = xp.sum(lit[..., :-1], axis=-1) + fx[..., None] * (lit[..., -1] - lit[..., 0])
        total = xp.sum(rows_sum[..., :-1], axis=-1) + fy * (rows_sum[..., -1] - rows_sum[..., 0])
    fraction = xp.clip(total / (2 * radius + 1) ** 2, 0.0, 1.0)
    on_map = xp.all((coords >= 0) & (coords <= 1), axis=-1)
    return xp.broadcast_to(xp.where(on_map, fraction, xp.ones_like(fraction)), shape)
