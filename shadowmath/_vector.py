"""Small vector helpers on ``(..., 3)`` arrays, written with the array API only."""

from __future__ import annotations

from types import ModuleType

import numpy as np

from ._validate import Array


def dot(xp: ModuleType, a: Array, b: Array) -> Array:
    """``sum(a * b, axis=-1)`` with broadcasting."""
    return xp.sum(a * b, axis=-1)


def _two_sum(a: Array, b: Array) -> tuple[Array, Array]:
    """Knuth's error-free sum: ``s + e == a + b`` exactly, ``s = fl(a + b)``."""
    s = a + b
    bb = s - a
    return s, (a - (s - bb)) + (b - bb)


def _two_product(a: Array, b: Array, splitter: float) -> tuple[Array, Array]:
    """Dekker's error-free product ``p + e == a * b`` (no FMA needed).

    Veltkamp's split cuts each factor into halves whose products are exact. A
    compiler that fuses ``ah * bh - p`` into an FMA still gets the exact value.
    """
    ca, cb = splitter * a, splitter * b
    ah = ca - (ca - a)
    bh = cb - (cb - b)
    al, bl = a - ah, b - bh
    p = a * b
    return p, ((ah * bh - p) + ah * bl + al * bh) + al * bl


def accurate_dot(xp: ModuleType, a: Array, b: Array) -> Array:
    """``sum(a * b, axis=-1)`` as if computed in twice the working precision.

    Ogita, Rump and Oishi's ``Dot2`` ("Accurate sum and dot product", 2005):
    the result is the exact dot product rounded once, up to a relative error of
    ``eps + (n eps)^2 cond``. Used where a short dot product cancels and its
    *sign* matters, as ``pi . L`` for a light close to the plane. Where the
    splitting overflows (entries beyond ~1e300 in float64, ~1e30 in float32)
    the plain sum is returned instead.
    """
    nmant = np.finfo(np.dtype(a.dtype)).nmant
    splitter = float(2 ** ((nmant + 2) // 2) + 1)  # 2^27 + 1 (float64), 2^12 + 1 (float32)
    a, b = xp.broadcast_arrays(a, b)
    p, s = _two_product(a[..., 0], b[..., 0], splitter)
    for i in range(1, a.shape[-1]):
        h, r = _two_product(a[..., i], b[..., i], splitter)
        p, q = _two_sum(p, h)
        s = s + (q + r)
    compensated = p + s
    return xp.where(xp.isfinite(compensated), compensated, dot(xp, a, b))


def cross(xp: ModuleType, a: Array, b: Array) -> Array:
    """The cross product of ``(..., 3)`` vectors (stacked, so it traces under jit)."""
    ax, ay, az = a[..., 0], a[..., 1], a[..., 2]
    bx, by, bz = b[..., 0], b[..., 1], b[..., 2]
    return xp.stack([ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx], axis=-1)


def _max_abs(xp: ModuleType, a: Array) -> tuple[Array, Array, Array]:
    """``(m, a / m, m > 0)`` with ``m = max |a_i|`` (1 in place of a zero ``m``)."""
    m = xp.max(xp.abs(a), axis=-1)
    nonzero = m > 0
    safe_m = xp.where(nonzero, m, xp.ones_like(m))
    return safe_m, a / safe_m[..., None], nonzero


def norm(xp: ModuleType, a: Array) -> Array:
    """``|a|`` without overflow or underflow of the squares.

    The vector is first scaled by its largest component, so a float32 vector of
    size 1e25 or 1e-25 (whose squares leave float32's range) keeps its length.
    """
    m, b, nonzero = _max_abs(xp, a)
    sq = dot(xp, b, b)
    # Double where: sqrt is never differentiated at 0 (finite gradients at a = 0).
    safe_sq = xp.where(nonzero, sq, xp.ones_like(sq))
    return xp.where(nonzero, m * xp.sqrt(safe_sq), xp.zeros_like(sq))


def safe_normalize(xp: ModuleType, a: Array) -> tuple[Array, Array]:
    """``(a / |a|, |a|)``; a zero vector gives a zero direction, never NaN.

    The vector is scaled by its largest component first, so neither the squares
    nor the length overflow or underflow (float32 directions of size 1e-25 or
    1e25 normalize correctly). The double ``where`` keeps reverse-mode
    gradients finite at ``a = 0``: the square root is taken of a value replaced
    by 1 there, so its derivative is never evaluated at 0. Callers turn the
    zero case into an error (or NaN).
    """
    m, b, nonzero = _max_abs(xp, a)
    sq = dot(xp, b, b)
    safe_sq = xp.where(nonzero, sq, xp.ones_like(sq))
    length = xp.where(nonzero, m * xp.sqrt(safe_sq), xp.zeros_like(sq))
    inv = xp.where(nonzero, 1 / xp.sqrt(safe_sq), xp.zeros_like(sq))
    return b * inv[..., None], length
