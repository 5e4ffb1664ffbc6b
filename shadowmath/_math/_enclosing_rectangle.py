r"""The minimum-area rectangle enclosing planar points, in fixed shapes (NumPy and JAX).

A rectangle of least area enclosing a convex polygon has a side collinear with an edge of
the polygon (Freeman and Shapira 1975): among the bounding boxes of the points in frames
turned so that ``u`` runs along an edge of their convex hull, one has the least area. Every
hull edge joins two of the points, so the candidates here are the directions of every pair
of points (a superset of the hull's edges: the least bounding-box area over them is the
minimum), folded into ``[-45°, 45°]`` (a rectangle along ``d`` is the one along ``d``
turned by 90 degrees), and the unturned frame first. A candidate direction ``(c, s)``
(``c = cos θ > 0``, ``|s| <= c``) gives the frame

.. math:: u = c\,x + s\,y, \qquad v = -s\,x + c\,y

and the area ``(max u - min u) (max v - min v)`` over the points; the argmin picks one
(ties keep the first: the unturned frame wins a tie). With ``m`` points the pairs cost
``m (m - 1) / 2`` candidates of ``m`` points each, in chunks of one shape (at most about
:data:`CHUNK_VALUES` values at once; NumPy first drops the points that no row counts).
Differentiable where the argmin is locally constant (a piecewise function of the points).
Trusted inputs: nothing here raises.
"""

from __future__ import annotations

import math
from types import ModuleType
from typing import NamedTuple

import numpy as np

from shadowmath._boundary._shapes import Array, Bool, Float, Int

__all__ = ["Rectangle", "min_area_rectangle"]


class Rectangle(NamedTuple):
    """A rectangle of the turned frame: ``u = c x + s y``, ``v = -s x + c y``.

    Attributes:
        c, s: ``(*b,)`` the turn's cosine and sine (``c > 0``, ``|s| <= c``).
        lo_u, hi_u, lo_v, hi_v: ``(*b,)`` its bounds along ``u`` and ``v``.

    Each a float in the loop form (:func:`._rectangle_loop.rectangle_loop`, one entry).
    """

    c: Float[Array, "*b"] | float
    s: Float[Array, "*b"] | float
    lo_u: Float[Array, "*b"] | float
    hi_u: Float[Array, "*b"] | float
    lo_v: Float[Array, "*b"] | float
    hi_v: Float[Array, "*b"] | float


def min_area_rectangle(
    xp: ModuleType, x: Float[Array, "*b m"], y: Float[Array, "*b m"], ok: Bool[Array, "*b m"]
) -> Rectangle:
    """The least-area rectangle enclosing the points ``(x, y)`` where ``ok``.

    Arguments:
        xp: the array namespace (NumPy or ``jax.numpy``).
        x, y: ``(*b, m)`` the points' coordinates.
        ok: ``(*b, m)`` which points count (at least one per row: else the bounds are
            ``±inf``).

    Returns:
        :class:`Rectangle`, whose area ``(hi_u - lo_u)(hi_v - lo_v)`` is at most the
        axis-aligned bounding box's (the unturned frame is a candidate).

    Example:
        >>> import numpy as np
        >>> t = np.radians(30.0)                    # a 4 x 1 rectangle turned by 30 degrees
        >>> u, v = np.array([0, 4, 4, 0.0]), np.array([0, 0, 1, 1.0])
        >>> x, y = np.cos(t) * u - np.sin(t) * v, np.sin(t) * u + np.cos(t) * v
        >>> r = min_area_rectangle(np, x, y, np.ones(4, bool))
        >>> round(float((r.hi_u - r.lo_u) * (r.hi_v - r.lo_v)), 12), round(float(r.s), 12)
        (4.0, 0.5)
    """
    if xp is np:  # drop the points that no row counts: the same candidates, fewer pairs
        keep = np.any(np.reshape(ok, (-1, ok.shape[-1])), axis=0)
        x, y, ok = x[..., keep], y[..., keep], ok[..., keep]
    one = xp.ones_like(x[..., :1])
    cs = [(one, 0.0 * one)]
    areas = [_areas(xp, (x, y, ok), one, 0.0 * one)[..., None]]
    for i, j in _pairs(x.shape):
        dx, dy = x[..., j] - x[..., i], y[..., j] - y[..., i]
        valid = ok[..., i] & ok[..., j] & ((dx != 0) | (dy != 0))
        wide = xp.abs(dx) >= xp.abs(dy)  # fold into [-45, 45] degrees: c > 0, |s| <= c
        fx, fy = xp.where(wide, dx, dy), xp.where(wide, dy, -dx)
        sign = xp.where(fx < 0, -1.0, 1.0)
        length = xp.sqrt(xp.where(valid, fx * fx + fy * fy, 1.0))
        c, s = sign * xp.where(valid, fx, 1.0) / length, sign * xp.where(valid, fy, 0.0) / length
        pts = (x[..., None, :], y[..., None, :], ok[..., None, :])
        area = _areas(xp, pts, c[..., None], s[..., None])
        cs.append((c, s))
        areas.append(xp.where(valid, area, xp.inf))
    area_all = xp.concat(areas, axis=-1)
    best = xp.argmin(area_all, axis=-1)[..., None]
    c = xp.take_along_axis(xp.concat([v[0] for v in cs], axis=-1), best, axis=-1)
    s = xp.take_along_axis(xp.concat([v[1] for v in cs], axis=-1), best, axis=-1)
    lo_u, hi_u, lo_v, hi_v = _bounds(xp, (x, y, ok), c, s)
    return Rectangle(c[..., 0], s[..., 0], lo_u, hi_u, lo_v, hi_v)


#: The most candidate-point values held at once (a batch's pairs go in chunks of one shape).
CHUNK_VALUES = 1 << 22


def _pairs(shape: tuple[int, ...]) -> list[tuple[Int[Array, " k"], Int[Array, " k"]]]:
    """The index pairs ``i < j`` of ``shape[-1]`` points, in chunks of one length (padded
    with ``(0, 0)``: no direction), so that each chunk holds at most about
    :data:`CHUNK_VALUES` values over the batch (and JAX compiles one shape)."""
    m = shape[-1]
    i, j = np.triu_indices(m, 1)
    if len(i) == 0:
        return []
    chunks = max(1, -(-math.prod(shape) * len(i) // CHUNK_VALUES))
    size = -(-len(i) // chunks)
    pad = np.zeros(chunks * size - len(i), dtype=i.dtype)
    i, j = np.concatenate([i, pad]), np.concatenate([j, pad])
    return [(i[k : k + size], j[k : k + size]) for k in range(0, len(i), size)]


def _bounds(
    xp: ModuleType,
    pts: tuple[Float[Array, "..."], Float[Array, "..."], Bool[Array, "..."]],
    c: Float[Array, "..."],
    s: Float[Array, "..."],
) -> tuple[Float[Array, "..."], Float[Array, "..."], Float[Array, "..."], Float[Array, "..."]]:
    """``(min u, max u, min v, max v)`` over the last axis of the ``ok`` points
    ``pts = (x, y, ok)`` in the frame ``(c, s)``."""
    x, y, ok = pts
    u, v = c * x + s * y, c * y - s * x
    inf = xp.inf
    return (
        xp.min(xp.where(ok, u, inf), axis=-1),
        xp.max(xp.where(ok, u, -inf), axis=-1),
        xp.min(xp.where(ok, v, inf), axis=-1),
        xp.max(xp.where(ok, v, -inf), axis=-1),
    )


def _areas(
    xp: ModuleType,
    pts: tuple[Float[Array, "..."], Float[Array, "..."], Bool[Array, "..."]],
    c: Float[Array, "..."],
    s: Float[Array, "..."],
) -> Float[Array, "..."]:
    """The bounding box's area in the frame ``(c, s)``."""
    lo_u, hi_u, lo_v, hi_v = _bounds(xp, pts, c, s)
    return (hi_u - lo_u) * (hi_v - lo_v)
