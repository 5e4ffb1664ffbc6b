"""What ``fit_atlas`` returns: :class:`AtlasFit`, every tile's matrices."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from shadowmath._boundary._shapes import Float, Int
from shadowmath._boundary._validate import Array

Ints = NDArray[np.int64]


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
