"""A cascade's light-space bounds: its slice of the camera frustum intersected with the scene box.

The one step of :mod:`._cascade_steps` with two forms, both over the 24 edges (12 of the
slice, 12 of the box) clipped to the other solid with :func:`._cascade_formulas.clip_plane`
(a vertex of the intersection is a clipped end of one of them):

* :func:`_bounds_loop` (the loop mode: Python or Numba floats), where each corner's outcode
  settles most edges without clipping; :func:`body_loop` is its first half (the fitted
  orientation reuses it), :func:`points_bounds` its second;
* :func:`_bounds_array` (the array mode), every edge of every cascade at once, reductions
  over the last axis; :func:`cascade_body` is its first half (LiSPSM and the fitted
  orientation reuse it), :func:`body_bounds` its second.

``specialize`` binds the name ``cascade_bounds`` to the mode's form (:data:`FORMS`). Both
take the slice's corners in light coordinates (``lc``, 8 x 3) and the box's half-space
values at them (``gs``, 8 x 6), the box's corners in light coordinates and their camera
side values and view depth (``boxp = (bl, bg)``, 8 x 3 and 8 x 5) and the slice's depths
``d = (s0, s1)``; both return :class:`LightBounds`.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from types import ModuleType
from typing import Any, NamedTuple

import numpy as np

from shadowmath._boundary._shapes import Row, Scalar, Truth

# Shared formulas and primitives (the mode's buffer and array namespace), rebound by specialize().
from ._cascade_formulas import (  # noqa: F401
    EDGES,
    alloc,
    array_api,
    clip_plane,
    clip_segment,
    slice_values,
)
from ._formulas import where

_E0 = (0, 2, 4, 6, 0, 1, 4, 5, 0, 1, 2, 3)
_E1 = (1, 3, 5, 7, 2, 3, 6, 7, 4, 5, 6, 7)
_EDGE_0, _EDGE_1 = np.array(_E0), np.array(_E1)


class LightBounds(NamedTuple):
    """A cascade's light-space bounds: the intersection's (the slice's own where it is
    empty; ``z_lo`` lowered to the box's nearest corner) and the scene box's ``z`` range."""

    lo_x: Any
    hi_x: Any
    lo_y: Any
    hi_y: Any
    z_lo: Any
    z_hi: Any
    box_z_lo: Any
    box_z_hi: Any


class CornerRow:
    """The array form's 8 x m corner buffer: ``columns``, ``m`` arrays ``(*b, n, 8)`` (value
    ``c`` of the eight corners), which :func:`cascade_body` reads whole, read per entry as
    the loop form's flat row (entry ``m k + c``: value ``c`` of corner ``k``, ``(*b, n)``).

    The passes over corners compute ``columns`` once on the corners' axis; a step written per
    entry indexes the row as it indexes the loop form's (an entry is sliced when read).
    """

    __slots__ = ("columns",)

    def __init__(self, columns: tuple[Scalar, ...]) -> None:
        self.columns = tuple(columns)

    def __len__(self) -> int:
        return 8 * len(self.columns)

    def __getitem__(self, i: int) -> Scalar:
        m = len(self.columns)
        return self.columns[i % m][..., i // m]

    def __iter__(self) -> Iterator[Scalar]:
        return (self[i] for i in range(len(self)))


def corner_axis(row: Row) -> tuple[Scalar, ...]:
    """Per-entry values ``(*b, 1)`` with a last axis for the corners (``(*b, 1, 1)``);
    Python numbers as they are."""
    return tuple(v[..., None] if hasattr(v, "shape") else v for v in row)


#: The most vertices of a cascade's body: both ends of the 24 edges.
BODY_VERTICES = 48

#: Names bound per mode by specialize(): ``name: (loop form, array form)``.
FORMS = {"cascade_bounds": ("_bounds_loop", "_bounds_array")}


def _bounds_loop(lc: Row, gs: Row, boxp: tuple[Row, Row], d: tuple[Scalar, Scalar]) -> LightBounds:
    """The loop form: :func:`body_loop`'s vertices reduced (:func:`points_bounds`)."""
    pts = alloc(3 * BODY_VERTICES)
    return points_bounds(pts, body_loop(lc, gs, boxp, d, pts)[0], boxp[0])


def body_loop(
    lc: Row, gs: Row, boxp: tuple[Row, Row], d: tuple[Scalar, Scalar], pts: Row
) -> tuple[int, bool]:
    """The loop form's vertices of the intersection: the clipped ends of the edges into
    ``pts`` (``x, y, z`` each, at most :data:`BODY_VERTICES`), or the slice's own corners
    where the intersection is empty or the whole slice; returns their count and whether
    the intersection is not empty.

    Each corner's outcode (bit ``j``: outside half-space ``j``, Cohen and Sutherland)
    settles most edges: a common bit puts the edge outside, no bit at either end inside;
    :func:`clip_segment` gives the same answers, only slower."""
    bl, bg = boxp
    cs, cb = _outcodes(gs, bg, d)
    whole = True  # every slice corner in the (convex) box: the intersection is the slice
    for k in range(8):
        if cs[k] != 0:
            whole = False
    m = 0
    for e in range(0 if whole else 24):
        k0, k1 = _E0[e % 12], _E1[e % 12]
        codes = cs if e < 12 else cb
        c0, c1 = int(codes[k0]), int(codes[k1])
        if c0 & c1:
            continue
        p = lc if e < 12 else bl
        t0, t1, ok = _clip_crossed(gs, bg, d, (e, k0, k1), c0 | c1)
        if ok:
            p0 = (p[3 * k0], p[3 * k0 + 1], p[3 * k0 + 2])
            dx, dy, dz = p[3 * k1] - p0[0], p[3 * k1 + 1] - p0[1], p[3 * k1 + 2] - p0[2]
            for t in (t0, t1):
                pts[3 * m], pts[3 * m + 1] = p0[0] + t * dx, p0[1] + t * dy
                pts[3 * m + 2] = p0[2] + t * dz
                m += 1
    seen = whole or m > 0
    if m == 0:
        for k in range(8):
            pts[3 * k], pts[3 * k + 1], pts[3 * k + 2] = lc[3 * k], lc[3 * k + 1], lc[3 * k + 2]
        m = 8
    return m, seen


def points_bounds(pts: Row, m: int, bl: Row) -> LightBounds:
    """The :class:`LightBounds` of ``m`` vertices ``pts`` (:func:`body_loop`) and the box's
    corners ``bl`` (8 x 3)."""
    inf = math.inf
    lx, hx_, ly, hy_, lz, hz = inf, -inf, inf, -inf, inf, -inf
    for k in range(m):
        x, y, z = pts[3 * k], pts[3 * k + 1], pts[3 * k + 2]
        # Comparisons, not min()/max(): the Python run of this loop calls nothing.
        if x < lx:
            lx = x
        if x > hx_:
            hx_ = x
        if y < ly:
            ly = y
        if y > hy_:
            hy_ = y
        if z < lz:
            lz = z
        if z > hz:
            hz = z
    zb = zt = bl[2]
    for k in range(8):
        zb, zt = min(zb, bl[3 * k + 2]), max(zt, bl[3 * k + 2])
    return LightBounds(lx, hx_, ly, hy_, min(min(zb, lz), hz), hz, zb, zt)


def _outcodes(gs: Row, bg: Row, d: tuple[Scalar, Scalar]) -> tuple[Row, Row]:
    """The slice's corners' outcodes against the box, the box's against the slice."""
    s0, s1 = d
    cs, cb = alloc(8), alloc(8)
    for k in range(8):
        c = 0
        for j in range(6):
            if gs[6 * k + j] < 0:
                c |= 1 << j
        cs[k] = c
        depth = bg[5 * k + 4]
        c = (16 if depth - s0 < 0 else 0) | (32 if s1 - depth < 0 else 0)
        for j in range(4):
            if bg[5 * k + j] < 0:
                c |= 1 << j
        cb[k] = c
    return cs, cb


def _clip_crossed(
    gs: Row, bg: Row, d: tuple[Scalar, Scalar], edge: tuple[int, int, int], crossed: int
) -> tuple[Scalar, Scalar, Truth]:
    """Edge ``edge = (e, k0, k1)`` clipped by the planes an end is outside of (``crossed``;
    the others change nothing): ``(t0, t1, ok)``."""
    e, k0, k1 = edge
    s0, s1 = d
    t0, t1, ok = 0.0, 1.0, True
    if crossed == 0:
        return t0, t1, ok
    for j in range(6):
        if crossed & (1 << j):
            if e < 12:
                a, b = gs[6 * k0 + j], gs[6 * k1 + j]
            elif j < 4:
                a, b = bg[5 * k0 + j], bg[5 * k1 + j]
            elif j == 4:
                a, b = bg[5 * k0 + 4] - s0, bg[5 * k1 + 4] - s0
            else:
                a, b = s1 - bg[5 * k0 + 4], s1 - bg[5 * k1 + 4]
            t0, t1, ok = clip_plane(t0, t1, ok, a, b)
    return t0, t1, ok and t0 <= t1


def cascade_body(
    lc: Row, gs: Row, boxp: tuple[Row, Row], d: tuple[Scalar, Scalar]
) -> tuple[list[Scalar], Truth, tuple[Scalar, ...], tuple[Scalar, ...]]:
    """The array form's vertices: ``(ends, ok, slice_corners, box_corners)``: ``ends`` three
    ``(*b, n, 48)`` arrays (both clipped ends of the 24 edges), ``ok`` ``(*b, n, 48)`` True
    where the edge kept a part; the slices' corners ``(*b, n, 8)`` and the box's
    ``(*b, 1, 8)``, each three arrays in light coordinates."""
    xp = array_api
    bl, bg = boxp
    s0, s1 = d[0][..., None], d[1][..., None]
    sl, bc, g_slice, sides = (_corners(xp, v, m) for v, m in ((lc, 3), (bl, 3), (gs, 6), (bg, 5)))
    g_box = slice_values(sides, sides[4], s0, s1)
    g0, g1 = [], []
    for gsl, gb in zip(g_slice, g_box, strict=True):
        (a0, a1), (b0, b1) = _edge_ends(xp, gsl), _edge_ends(xp, xp.broadcast_to(gb, gsl.shape))
        g0.append(xp.concat([a0, b0], axis=-1))
        g1.append(xp.concat([a1, b1], axis=-1))
    t0, t1, ok = clip_segment(tuple(g0), tuple(g1))
    ends = []
    for p_s, p_b in zip(sl, bc, strict=True):
        # The slice may be one for the batch (a visible range's camera-wide depths) while
        # the box is per camera, or the other way round: both to their common shape.
        shape = xp.broadcast_shapes(p_s.shape, p_b.shape)
        p_s, p_b = xp.broadcast_to(p_s, shape), xp.broadcast_to(p_b, shape)
        (a0, a1), (b0, b1) = _edge_ends(xp, p_s), _edge_ends(xp, p_b)
        p0, p1 = xp.concat([a0, b0], axis=-1), xp.concat([a1, b1], axis=-1)
        ends.append(xp.concat([p0 + t0 * (p1 - p0), p0 + t1 * (p1 - p0)], axis=-1))
    return ends, xp.concat([ok, ok], axis=-1), sl, bc


def _edge_ends(xp: ModuleType, v: Scalar) -> tuple[Scalar, Scalar]:
    """The ends of a box's 12 edges from its corners' values ``v`` ``(..., 8)`` (corner
    ``i + 2 j + 4 k``): two ``(..., 12)``, in the order of ``_E0`` and ``_E1`` (the edges
    along ``i``, then ``j``, then ``k``), by strided slices rather than a gather (whose
    derivative, a scatter, would cost XLA more to compile). NumPy takes them by index arrays:
    one call each instead of ten."""
    if xp is np:
        return v[..., _EDGE_0], v[..., _EDGE_1]
    half = xp.reshape(v, (*v.shape[:-1], 2, 4))  # (k, 2 j + i)
    shape = (*v.shape[:-1], 4)
    along_j = (xp.reshape(half[..., :2], shape), xp.reshape(half[..., 2:], shape))
    return (xp.concat([v[..., 0::2], along_j[0], v[..., :4]], axis=-1),
            xp.concat([v[..., 1::2], along_j[1], v[..., 4:]], axis=-1))  # fmt: skip


def _corners(xp: ModuleType, buffer: Row, m: int) -> tuple[Scalar, ...]:
    """``m`` arrays ``(..., 8)``: value ``c`` of the eight corners of a buffer of 8 x m
    (a :class:`CornerRow`'s columns)."""
    if isinstance(buffer, CornerRow):
        return buffer.columns
    stacked = xp.stack(xp.broadcast_arrays(*buffer), axis=-1)
    stacked = xp.reshape(stacked, (*stacked.shape[:-1], 8, m))
    return tuple(stacked[..., c] for c in range(m))


def _bounds_array(lc: Row, gs: Row, boxp: tuple[Row, Row], d: tuple[Scalar, Scalar]) -> LightBounds:
    """The array form: :func:`cascade_body`'s vertices reduced over the last axis."""
    return body_bounds(cascade_body(lc, gs, boxp, d))


def body_bounds(
    body: tuple[list[Scalar], Truth, tuple[Scalar, ...], tuple[Scalar, ...]],
) -> LightBounds:
    """:func:`cascade_body`'s vertices reduced over the last axis: the array form's
    :class:`LightBounds`."""
    xp = array_api
    ends, ok2, sl, bc = body
    seen = xp.any(ok2, axis=-1)
    # Every bound as one maximum (a minimum is -max(-v), exactly): one reduction, whose
    # derivative meets the bounds' cotangents once, where six would each repeat them.
    hit = xp.max(xp.stack([where(ok2, s * v, -np.inf) for v in ends for s in (-1.0, 1.0)],
                          axis=-3), axis=-1)  # fmt: skip
    own = xp.max(xp.stack([s * f for f in sl for s in (-1.0, 1.0)], axis=-3), axis=-1)
    b6 = where(seen[..., None, :], hit, own)
    low = [-b6[..., 2 * c, :] for c in range(3)]
    high = [b6[..., 2 * c + 1, :] for c in range(3)]
    zb_lo, zb_hi = xp.min(bc[2], axis=-1), xp.max(bc[2], axis=-1)
    z_lo = xp.minimum(xp.minimum(zb_lo, low[2]), high[2])
    return LightBounds(low[0], high[0], low[1], high[1], z_lo, high[2], zb_lo, zb_hi)


FUNCTIONS = (
    "_bounds_loop",
    "body_loop",
    "points_bounds",
    "_outcodes",
    "_clip_crossed",
    "cascade_body",
    "_edge_ends",
    "_corners",
    "_bounds_array",
    "body_bounds",
)
