"""``fit_atlas``' driver: every tile fitted from the door's trusted arrays.

The 2D lights grouped by (kind, tile size, border), each group through ``fit_shadow``'s
compiled loop or its array driver (:mod:`._fit_2d`); the cube lights' six faces each on
whole arrays (:mod:`._fit_cubes`); the tiles gathered in order and the atlas's tile
transforms applied (:mod:`._report`, :mod:`._viewports`), into the result
(:class:`._result.AtlasFit`).
"""

from __future__ import annotations

import numpy as np

from shadowmath._boundary._validate import Array, Context
from shadowmath._math._vector import matmul

from ._allocate import ShadowAtlas
from ._fit_2d import fit_2d
from ._fit_cubes import fit_cubes
from ._report import AtlasInputs, Report, gather
from ._result import AtlasFit, Ints
from ._viewports import atlas_viewports, tile_transforms


def fit_tiles(
    ctx: Context,
    atlas: ShadowAtlas,
    kinds: Ints,
    inputs: AtlasInputs,
    report: Report,
    *,
    api: str,
) -> AtlasFit:
    """Every tile of ``atlas`` fitted: the lights' ``kinds`` and the checked ``inputs``;
    a light that cannot be fitted goes to ``report`` (its tiles draw nothing)."""
    xp = ctx.xp
    parts: list[tuple[Ints, Array, Array, Array, Array]] = []
    parts.extend(fit_2d(ctx, atlas, kinds, inputs, report))
    cubes = np.flatnonzero(atlas.light_cube & (atlas.light_size > 0))
    if cubes.size:
        parts.append(fit_cubes(ctx, atlas, cubes, inputs, api=api, report=report))
    T = xp.asarray(tile_transforms(atlas.tile_rect, atlas.atlas_size), dtype=ctx.dtype)
    clip, tex, lo, hi = gather(ctx, parts, atlas.tile_light.shape[0])
    errors = tuple(report.errors)
    return AtlasFit(
        clip, matmul(xp, T, tex), atlas_viewports(atlas), atlas.tile_clamp, lo, hi,
        texture_size=(atlas.atlas_size, atlas.atlas_size), tile_id=atlas.tile_id,
        tile_face=atlas.tile_face, light_errors=errors,
    )  # fmt: skip
