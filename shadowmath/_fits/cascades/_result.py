"""What ``fit_cascades`` returns: :class:`Cascades`, and the :class:`CascadeState` for the
next frame; the cascades' tiles in the texture (:func:`_tiles`, :func:`_texture`,
:func:`_grid`).
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np

from shadowmath._boundary._shapes import ArrayLike, Float, Int, Real
from shadowmath._boundary._validate import Array
from shadowmath._math._frustum import OrthographicBox


class CascadeState(NamedTuple):
    """What a :func:`fit_cascades` call used, for the next frame's hysteresis.

    Start with :meth:`initial` (nothing in use yet), then give the last frame's result's
    ``state`` to the next call as ``state=`` (with ``depth_range`` ``"visible"`` or
    measured): the depth range's ends, and with ``stable=True`` each cascade's size,
    are then values of a fixed ladder ``2^(k/4)`` that grow at once and shrink only past
    a margin of one step, so the splits and the stable cascades' sizes change only at
    ladder steps (``docs/cascades.md``).

    Attributes:
        near: ``(*batch,)`` the first split in use (NaN: none yet).
        far: ``(*batch,)`` the last split in use (NaN: none yet).
        half_width: ``(*batch, n)`` each stable cascade's laddered half-width (the
            square uses the lesser of it and the slice's sphere's radius, then adds its
            half texel of snapping room); NaN: none yet; NaN in a result without
            ``stable=True``, the sphere's radius in one without ``state``.

    Example:
        >>> import shadowmath as sm
        >>> sm.CascadeState.initial()
        CascadeState(near=nan, far=nan, half_width=nan)
    """

    near: Real[ArrayLike, "*#batch"]
    far: Real[ArrayLike, "*#batch"]
    half_width: Real[ArrayLike, "*#batch _"] | Real[ArrayLike, ""]

    @classmethod
    def initial(cls) -> CascadeState:
        """The state before the first frame: nothing in use (every value NaN)."""
        return cls(math.nan, math.nan, math.nan)


class Cascades(NamedTuple):
    """Everything a renderer needs to draw and sample a directional light's cascades.

    ``n`` is the number of cascades; every matrix is in the ``api``'s conventions.

    Attributes:
        world_to_light: ``(*batch, n, 4, 4)`` world to each cascade's light
            coordinates (one rotation for all, origins differ along ``Z`` only; with
            ``orientation="fitted"`` each turned about ``Z`` by its own angle).
        frustum: the :class:`OrthographicBox` of each cascade, fields ``(*batch, n)``.
        world_to_clip: ``(*batch, n, 4, 4)`` world to the cascade's clip coordinates:
            draw the casters into cascade ``i`` with ``world_to_clip[i] @ model``.
        world_to_texture: ``(*batch, n, 4, 4)`` world to ``(s, t, r, 1)``: texture
            coordinates in the cascade's layer, or in the atlas (``layout="atlas"``),
            and the stored depth ``r`` to compare with.
        splits: ``(*batch, n + 1)`` the view depths that bound the cascades: cascade
            ``i`` serves view depths ``[splits[i], splits[i + 1])``.
        band_end: ``(*batch, n)`` cascade ``i`` is fitted out to ``band_end[i] >=
            splits[i + 1]``; in ``[splits[i + 1], band_end[i]]`` the shader blends
            cascades ``i`` and ``i + 1`` (weight of ``i + 1``: the fraction of the band
            passed). The last cascade has no band (``band_end = splits[n]``).
        texel_size: ``(*batch, n, 2)`` the world size of one texel along light ``X``
            and ``Y`` (for normal-offset and slope bias).
        viewports: ``(n, 4)`` integers ``(x, y, width, height)`` of each cascade's
            tile in the atlas, in the API's own viewport convention (``(0, 0, W, H)``
            for every cascade with ``layout="layers"``).
        texture_size: ``(width, height)`` in texels of the depth texture to allocate
            (the same for every batch entry): each layer's, ``(W, H)``, with
            ``layout="layers"``; the atlas's, ``(cols W, rows H)`` (``cols =
            ceil(sqrt(n))``, ``rows = ceil(n / cols)``), with ``layout="atlas"``.
            Every viewport lies inside it.
        texture_layers: the texture's layer count: ``n`` with ``layout="layers"``
            (a texture array), 1 with ``layout="atlas"``.
        state: what this fit used (the splits' ends, the stable sizes): the next
            frame's ``state=`` (not needed by a renderer).
    """

    world_to_light: Float[Array, "*batch n 4 4"]
    frustum: OrthographicBox
    world_to_clip: Float[Array, "*batch n 4 4"]
    world_to_texture: Float[Array, "*batch n 4 4"]
    splits: Float[Array, "*batch n+1"]
    band_end: Float[Array, "*batch n"]
    texel_size: Float[Array, "*batch n 2"]
    viewports: Int[Array, "n 4"]
    texture_size: tuple[int, int]
    texture_layers: int

    state: CascadeState


@functools.lru_cache(maxsize=64)
def _tiles(n: int, size: tuple[int, int], layout: str) -> Array:
    """Each cascade's viewport ``(x, y, w, h)`` (read-only: shared by every call)."""
    w, h = size
    if layout == "layers":
        ports = np.tile(np.array([0, 0, w, h]), (n, 1))
    else:
        cols = _grid(n, layout)[0]
        cells = np.array([(i % cols, i // cols) for i in range(n)])
        ports = np.column_stack([cells[:, 0] * w, cells[:, 1] * h, np.full(n, w), np.full(n, h)])
    ports.setflags(write=False)
    return ports


def _texture(n: int, size: tuple[int, int], layout: str) -> tuple[tuple[int, int], int]:
    """The texture holding ``n`` cascades of ``size``: ``texture_size``, ``texture_layers``."""
    w, h = int(size[0]), int(size[1])
    if layout == "layers":
        return (w, h), n
    cols, rows = _grid(n, layout)
    return (cols * w, rows * h), 1


def _grid(n: int, layout: str) -> tuple[int, int]:
    if layout == "layers":
        return 0, 0  # the loop's mark: no tiles
    cols = math.ceil(math.sqrt(n))
    return cols, math.ceil(n / cols)
