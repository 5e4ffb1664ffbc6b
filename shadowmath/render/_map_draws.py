"""What a pass draws into its shadow maps, once for both graphics APIs: per map (a tile, a
cascade's layer or tile), its layer, its viewport and the bodies of its draw list with
their ``body_to_clip`` matrices (:func:`map_draws`)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
from jaxtyping import Float, Int
from numpy.typing import NDArray

#: Body indices, one integer array per map (a tile, a cascade).
DrawLists = tuple[NDArray[np.int64], ...]


class MapDraw(NamedTuple):
    """One map's draws.

    Attributes:
        layer: the texture layer drawn into (0 for an atlas).
        viewport: ``(x, y, w, h)`` texels, also the scissor rectangle.
        bodies: the body indices of the map's draw list, in body order.
        body_to_clip: ``(len(bodies), 4, 4)`` each body's ``world_to_clip @ to_world``.
    """

    layer: int
    viewport: tuple[int, int, int, int]
    bodies: tuple[int, ...]
    body_to_clip: NDArray[np.float64]


def map_draws(
    world_to_clip: Float[NDArray[np.float64], "n 4 4"],
    viewports: Int[NDArray[np.int64], "n 4"],
    draws: DrawLists,
    to_world: Sequence[NDArray[np.float64]],
    *,
    layered: bool,
) -> tuple[MapDraw, ...]:
    """Map ``i``'s :class:`MapDraw`: layer ``i`` when ``layered`` (else 0), viewport
    ``viewports[i]``, the bodies ``draws[i]`` with ``body_to_clip = world_to_clip[i] @
    to_world[b]``.

    Example:
        >>> one = map_draws(np.eye(4)[None], np.array([[0, 0, 8, 8]]), (np.array([0]),),
        ...                 [2 * np.eye(4)], layered=True)
        >>> one[0].viewport, one[0].bodies, float(one[0].body_to_clip[0, 0, 0])
        ((0, 0, 8, 8), (0,), 2.0)
    """
    clip = np.asarray(world_to_clip, dtype=np.float64)
    ports = np.asarray(viewports, dtype=np.int64)
    maps = []
    for i, port in enumerate(ports):
        bodies = tuple(int(b) for b in draws[i])
        x, y, w, h = (int(c) for c in port)
        matrices = np.array([clip[i] @ to_world[b] for b in bodies]).reshape(-1, 4, 4)
        maps.append(MapDraw(i if layered else 0, (x, y, w, h), bodies, matrices))
    return tuple(maps)
