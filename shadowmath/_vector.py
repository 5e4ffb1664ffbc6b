"""Small vector helpers on ``(..., 3)`` arrays, written with the array API only."""

from __future__ import annotations

from types import ModuleType

from ._backend import Array


def dot(xp: ModuleType, a: Array, b: Array) -> Array:
    """``sum(a * b, axis=-1)`` with broadcasting."""
    return xp.sum(a * b, axis=-1)


def cross(xp: ModuleType, a: Array, b: Array) -> Array:
    """The cross product of ``(..., 3)`` vectors (stacked, so it traces under jit)."""
    ax, ay, az = a[..., 0], a[..., 1], a[..., 2]
    bx, by, bz = b[..., 0], b[..., 1], b[..., 2]
    return xp.stack([ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx], axis=-1)


def norm(xp: ModuleType, a: Array) -> Array:
    return xp.sqrt(dot(xp, a, a))


def safe_normalize(xp: ModuleType, a: Array) -> tuple[Array, Array]:
    """``(a / |a|, |a|)``; a zero vector gives a zero direction, never NaN.

    The double ``where`` keeps reverse-mode gradients finite at ``a = 0``: the
    square root is taken of a value replaced by 1 there, so its derivative is
    never evaluated at 0. Callers turn the zero case into an error (or NaN).
    """
    sq = dot(xp, a, a)
    nonzero = sq > 0
    safe_sq = xp.where(nonzero, sq, xp.ones_like(sq))
    length = xp.where(nonzero, xp.sqrt(safe_sq), xp.zeros_like(sq))
    inv = xp.where(nonzero, 1 / xp.sqrt(safe_sq), xp.zeros_like(sq))
    return a * inv[..., None], length
