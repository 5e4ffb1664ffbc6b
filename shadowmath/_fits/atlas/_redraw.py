r"""Which tiles of a shadow atlas to draw this frame: :func:`atlas_redraw`.

A tile's depths are a function of what is drawn into it and how: its key ``(light id,
face)`` says whose casters, its viewport where and how large, its ``world_to_clip``
with which matrices. The allocator (:func:`allocate_atlas`) knows the first two; only
the fits (:func:`fit_atlas`) know the matrices, so the rule compares two fits.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from shadowmath._boundary._shapes import ArrayLike, Bool, Integer

from ._allocate import find_tiles
from ._result import AtlasFit

__all__ = ["atlas_redraw"]


def atlas_redraw(
    fit: AtlasFit,
    previous: AtlasFit | None,
    *,
    draws: Sequence[Integer[ArrayLike, " _"]] | None = None,
    previous_draws: Sequence[Integer[ArrayLike, " _"]] | None = None,
    moved: Integer[ArrayLike, " K"] | None = None,
) -> Bool[NDArray[np.bool_], " T"]:
    r"""Which tiles of ``fit`` to draw this frame; the others already hold their depths.

    ``previous`` is the fit whose tiles the atlas texture holds (last frame's, every
    tile it flagged drawn). Tile ``t``'s key is ``k = (tile_id[t], tile_face[t])``, and

    .. math::

        \mathrm{redraw}[t] = \lnot\bigl(\exists\, u:\ \mathrm{key}'[u] = k
        \ \wedge\ \mathrm{viewport}'[u] = \mathrm{viewport}[t]
        \ \wedge\ W'_u = W_t\bigr)

    over the tiles ``u`` of ``previous`` (primed), ``W`` the ``world_to_clip``
    matrices compared entry by entry, exactly; everything is redrawn without
    ``previous`` or when the ``texture_size`` changed (a new texture). So a tile is
    redrawn when it is new, when its rect moved or resized, or when its light's
    matrices changed (the light moved or turned, its fit followed the casters, its
    border, depth range or API changed); a tile whose *index* changed (lights before it
    left, joined or were reordered) but whose key, rect and matrices did not is not:
    its depths are still in its rect. Only the matrices are seen: when casters move
    inside a light's fitted frustum without changing its matrices, the caller redraws
    that light's tiles too (``|`` its own mask), or gives the objects:

    **Objects.** With ``draws`` (this frame's draw list per tile: object indices, as
    :meth:`ShadowScene.fit_atlas` gives), ``previous_draws`` (the previous fit's, per
    tile of ``previous``) and ``moved`` (the objects whose geometry or placement changed
    since the previous fit: :attr:`SceneAtlas.moved`), a tile kept by the rule above is
    redrawn too when its draw list differs from its previous one (as sets) or holds an
    object of ``moved``: its depths are those of what it draws. A static scene under
    static lights redraws nothing.

    A renderer that keeps the atlas from frame to frame clears (scissored) and draws
    exactly the flagged tiles' viewports, and samples every tile with this frame's
    ``world_to_texture``. One that keeps its depths elsewhere caches them by key.

    Arguments:
        fit: this frame's :class:`AtlasFit`.
        previous: the :class:`AtlasFit` the texture was drawn with, or None.
        draws, previous_draws, moved: the objects (see above); give all three or none.

    Returns:
        ``(T,)`` bool NumPy array, one per tile of ``fit``.

    Raises:
        ValueError: ``fit`` not an :class:`AtlasFit`, ``previous`` neither one nor None;
            ``draws``, ``previous_draws`` and ``moved`` not all given or all None, or a
            draw list count that is not the fit's (the previous fit's) tile count.

    Example:
        >>> import numpy as np, shadowmath as sm
        >>> box = np.array([[x, y, z] for x in (-1, 1) for y in (0, 2) for z in (-1, 1)], float)
        >>> spot = lambda x: sm.SpotLight(np.array([x, 6.0, 0.0]), np.array([0.0, -1.0, 0.0]),
        ...                               np.array(0.6))
        >>> a = sm.allocate_atlas([0.5, 0.5, 0.5], atlas_size=1024, light_ids=[7, 8, 9])
        >>> fit_a = sm.fit_atlas([spot(0.0), spot(1.0), spot(2.0)], box, a)
        >>> b = sm.allocate_atlas([0.5, 0.5], atlas_size=1024, light_ids=[7, 9], previous=a)
        >>> fit_b = sm.fit_atlas([spot(0.0), spot(2.0)], box, b)  # light 8 left
        >>> b.previous_index.tolist(), b.moved.tolist()  # light 9's tile: index 2 -> 1
        ([0, 2], [False, True])
        >>> sm.atlas_redraw(fit_b, fit_a).tolist()  # same key, rect and matrices: kept
        [False, False]
        >>> sm.atlas_redraw(sm.fit_atlas([spot(0.0), spot(2.5)], box, b), fit_a).tolist()
        [False, True]
    """
    if not isinstance(fit, AtlasFit):
        raise ValueError(f"fit: expected an AtlasFit (from fit_atlas), got {type(fit).__name__}")
    if previous is not None and not isinstance(previous, AtlasFit):
        raise ValueError(
            f"previous: expected an AtlasFit (last frame's fit) or None, got "
            f"{type(previous).__name__}"
        )
    count = fit.tile_id.shape[0]
    objects = _objects(fit, previous, draws, previous_draws, moved)
    if previous is None or previous.tile_id.size == 0:
        return np.ones(count, dtype=bool)
    if tuple(previous.texture_size) != tuple(fit.texture_size):
        return np.ones(count, dtype=bool)
    at = find_tiles(fit.tile_id, fit.tile_face, previous.tile_id, previous.tile_face)
    had = at >= 0
    old = np.where(had, at, 0)
    same_port = np.all(np.asarray(previous.viewports)[old] == np.asarray(fit.viewports), axis=1)
    old_clip = np.asarray(previous.world_to_clip)[old]
    same_clip = np.all(old_clip == np.asarray(fit.world_to_clip), axis=(1, 2))
    keep = had & same_port & same_clip
    if objects is not None:
        now, before, changed = objects
        for t in np.flatnonzero(keep):
            drawn, was = now[t], before[int(old[t])]
            if set(drawn.tolist()) != set(was.tolist()) or changed[drawn].any():
                keep[t] = False
    return np.asarray(~keep)


def _objects(
    fit: AtlasFit, previous: AtlasFit | None, draws: Any, previous_draws: Any, moved: Any
) -> tuple[list[np.ndarray], list[np.ndarray], np.ndarray] | None:
    """The draw lists and a mask of the moved objects, checked; None without them."""
    given = [x is not None for x in (draws, previous_draws, moved)]
    if not any(given):
        return None
    if not all(given):
        raise ValueError(
            "draws, previous_draws, moved: give all three (this and the previous fit's "
            "draw lists per tile, the objects that moved) or none"
        )
    lists = []
    for name, value, ref in (("draws", draws, fit), ("previous_draws", previous_draws, previous)):
        tiles = 0 if ref is None else ref.tile_id.shape[0]
        rows = [np.asarray(d, dtype=np.int64).reshape(-1) for d in value]
        if len(rows) != tiles:
            raise ValueError(f"{name}: expected one draw list per tile ({tiles}), got {len(rows)}")
        lists.append(rows)
    moved_ids = np.asarray(moved, dtype=np.int64).reshape(-1)
    if np.any(moved_ids < 0) or any(np.any(r < 0) for rows in lists for r in rows):
        raise ValueError("draws, previous_draws, moved: object indices must be >= 0")
    size = 1 + max([int(moved_ids.max(initial=-1))] + [int(r.max(initial=-1)) for r in lists[0]])
    changed = np.zeros(size, dtype=bool)
    changed[moved_ids] = True
    return lists[0], lists[1], changed
