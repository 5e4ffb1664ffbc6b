r"""What :func:`fit_atlas` reports per light, and its tiles' matrices put in tile order.

A light that cannot be fitted gets an error message and matrices that clip everything
(:class:`Report`); every group's ``(tiles, clip, texture, near, far)`` is gathered in
tile order (:func:`gather`).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from shadowmath._boundary._validate import Array, Context
from shadowmath._fits._spec import api_rows

__all__ = ["AtlasInputs", "Report", "gather", "pick"]

Ints = NDArray[np.int64]


class AtlasInputs(NamedTuple):
    """What the atlas's lights are fitted to, checked at the door: ``data`` the lights'
    rows ``(count, 8)``, the casters' points ``verts`` (``(N, 3)`` shared or
    ``(count, N, 3)``) and triangles ``tris`` (or None), the receivers' rows ``R`` and the
    given ``near``, ``far`` per light (or None)."""

    data: Array
    verts: Array
    tris: Array | None
    R: Array | None
    n: Array | None
    f: Array | None


class Report:
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


def gather(ctx: Context, parts: list[Any], total: int) -> tuple[Array, ...]:
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


def pick(ctx: Context, v: Array, idx: Ints) -> Array:
    return ctx.xp.broadcast_to(v, (idx.size,)) if v.ndim == 0 else v[idx]
