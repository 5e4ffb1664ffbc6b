r"""Where a shadow atlas's tiles lie in each API's conventions: :func:`atlas_viewports`,
:func:`atlas_tile_transforms`.

The conventions are derived in ``docs/atlas.md``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from shadowmath._boundary._shapes import Float, Int
from shadowmath._geometry._api_convention import check_api as _check_api
from shadowmath._math._conventions import GraphicsApi
from shadowmath._math._rows import tile_rows

from ._allocate import ShadowAtlas

__all__ = ["atlas_tile_transforms", "atlas_viewports", "tile_transforms"]

Ints = NDArray[np.int64]


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
        >>> import shadowmath as sm
        >>> a = sm.allocate_atlas([1.0, 0.2], atlas_size=512)
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
        >>> import shadowmath as sm
        >>> a = sm.allocate_atlas([1.0, 0.2], atlas_size=512)
        >>> atlas_tile_transforms(a)[1] @ [1.0, 1.0, 0.5, 1.0]  # the tile's far corner
        array([0.625, 0.125, 0.5  , 1.   ])
    """
    _check_api(api, False)
    return tile_transforms(atlas.tile_rect, atlas.atlas_size)


def tile_transforms(rect: Ints, size: int) -> NDArray[np.float64]:
    """Each tile's matrix: the identity moved into the tile (the cascades' own formula)."""
    x, y, n = (rect[:, k].astype(np.float64) for k in range(3))
    one, zero = np.ones_like(x), np.zeros_like(x)
    identity = tuple(one if i % 5 == 0 else zero for i in range(16))
    rows = tile_rows(identity, (x, y, n, n), (float(size), float(size)))
    return np.stack(np.broadcast_arrays(*rows), axis=-1).reshape(-1, 4, 4)
