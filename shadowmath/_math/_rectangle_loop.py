r"""The minimum-area rectangle enclosing planar points, per entry (Python or Numba floats).

The loop form of :func:`._enclosing_rectangle.min_area_rectangle` (the array form): the
same candidates' rule (Freeman and Shapira 1975: a least-area rectangle has a side along
an edge of the points' convex hull) on the hull's edges only, found by Andrew's monotone
chain, instead of every pair of points. Each edge's direction is folded into
``[-45°, 45°]`` exactly as the array form folds a pair's, giving the frame

.. math:: u = c\,x + s\,y, \qquad v = -s\,x + c\,y

(``c > 0``, ``|s| <= c``); the unturned frame comes first and keeps a tie. The two forms
agree to rounding (an exact tie between two different directions may pick either).
Trusted inputs: nothing here raises.
"""

from __future__ import annotations

from shadowmath._boundary._shapes import Row, Scalar, Truth

from ._cascade_formulas import alloc
from ._enclosing_rectangle import Rectangle
from ._formulas import sqrt


def rectangle_loop(pts: Row, m: int) -> Rectangle:
    """The least-area :class:`._enclosing_rectangle.Rectangle` enclosing the first ``m``
    points of ``pts`` (rows ``x, y, z``: ``z`` is ignored; ``m >= 1``)."""
    hull = alloc(2 * m + 1)
    h = _hull_loop(pts, m, hull)
    best_c, best_s = 1.0, 0.0
    best = _frame_area(pts, (hull, h), best_c, best_s)
    for k in range(h if h > 1 else 0):
        i, j = int(hull[k]), int(hull[(k + 1) % h])
        dx, dy = pts[3 * j] - pts[3 * i], pts[3 * j + 1] - pts[3 * i + 1]
        if dx != 0 or dy != 0:
            c, s = _folded(dx, dy)
            area = _frame_area(pts, (hull, h), c, s)
            if area < best:
                best, best_c, best_s = area, c, s
    lo_u, hi_u, lo_v, hi_v = _frame_bounds(pts, m, best_c, best_s)
    return Rectangle(best_c, best_s, lo_u, hi_u, lo_v, hi_v)


def _folded(dx: Scalar, dy: Scalar) -> tuple[Scalar, Scalar]:
    """The direction ``(dx, dy)`` as ``(c, s)``, folded into ``[-45°, 45°]`` (``c > 0``,
    ``|s| <= c``; a quarter turn gives the same rectangle): the array form's rule."""
    if abs(dx) >= abs(dy):
        fx, fy = dx, dy
    else:
        fx, fy = dy, -dx
    sign = -1.0 if fx < 0 else 1.0
    length = sqrt(fx * fx + fy * fy)
    return sign * fx / length, sign * fy / length


def _frame_area(pts: Row, hull: tuple[Row, int], c: Scalar, s: Scalar) -> Scalar:
    """The bounding box's area of the hull's vertices (``hull = (indices, count)``) in the
    frame ``(c, s)``."""
    idx, h = hull
    k = int(idx[0])
    u = c * pts[3 * k] + s * pts[3 * k + 1]
    v = c * pts[3 * k + 1] - s * pts[3 * k]
    lo_u, hi_u, lo_v, hi_v = u, u, v, v
    for q in range(1, h):
        k = int(idx[q])
        u = c * pts[3 * k] + s * pts[3 * k + 1]
        v = c * pts[3 * k + 1] - s * pts[3 * k]
        lo_u, hi_u = min(lo_u, u), max(hi_u, u)
        lo_v, hi_v = min(lo_v, v), max(hi_v, v)
    return (hi_u - lo_u) * (hi_v - lo_v)


def _frame_bounds(pts: Row, m: int, c: Scalar, s: Scalar) -> tuple[Scalar, Scalar, Scalar, Scalar]:
    """``(min u, max u, min v, max v)`` over the first ``m`` points in the frame ``(c, s)``."""
    u = c * pts[0] + s * pts[1]
    v = c * pts[1] - s * pts[0]
    lo_u, hi_u, lo_v, hi_v = u, u, v, v
    for k in range(1, m):
        u = c * pts[3 * k] + s * pts[3 * k + 1]
        v = c * pts[3 * k + 1] - s * pts[3 * k]
        lo_u, hi_u = min(lo_u, u), max(hi_u, u)
        lo_v, hi_v = min(lo_v, v), max(hi_v, v)
    return lo_u, hi_u, lo_v, hi_v


def _hull_loop(pts: Row, m: int, hull: Row) -> int:
    """Andrew's monotone chain: the indices of the convex hull's vertices of the first
    ``m`` points (counter-clockwise, collinear ones dropped) into ``hull`` (``2 m + 1``
    entries); returns their count (1 where every point is the same)."""
    order = alloc(m)
    for k in range(m):  # insertion sort by (x, y): m is at most a few dozen
        x, y = pts[3 * k], pts[3 * k + 1]
        i = k - 1
        while i >= 0 and _after(pts, int(order[i]), x, y):
            order[i + 1] = order[i]
            i -= 1
        order[i + 1] = k
    h, t = 0, 0
    for q in range(2 * m - 1):  # the lower chain, then the upper one back
        k = int(order[q] if q < m else order[2 * m - 2 - q])
        floor = 2 if q < m else t
        while h >= floor and _turn(pts, int(hull[h - 2]), int(hull[h - 1]), k) <= 0:
            h -= 1
        hull[h] = k
        h += 1
        if q == m - 1:
            t = h + 1
    return h - 1 if h > 1 else 1


def _after(pts: Row, i: int, x: Scalar, y: Scalar) -> Truth:
    """Point ``i`` sorts after ``(x, y)`` (by ``x``, then ``y``)."""
    return pts[3 * i] > x or (pts[3 * i] == x and pts[3 * i + 1] > y)


def _turn(pts: Row, i: int, j: int, k: int) -> Scalar:
    """The cross product ``(p_j - p_i) x (p_k - p_i)``: positive for a left turn."""
    ax, ay = pts[3 * j] - pts[3 * i], pts[3 * j + 1] - pts[3 * i + 1]
    bx, by = pts[3 * k] - pts[3 * i], pts[3 * k + 1] - pts[3 * i + 1]
    return ax * by - ay * bx


FUNCTIONS = (
    "rectangle_loop",
    "_folded",
    "_frame_area",
    "_frame_bounds",
    "_hull_loop",
    "_after",
    "_turn",
)
