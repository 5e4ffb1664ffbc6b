"""Small vector helpers on ``(..., 3)`` arrays, written with the array API only."""

from __future__ import annotations

from types import ModuleType

from shadowmath._boundary._shapes import Bool, Float
from shadowmath._boundary._validate import Array


def matmul(
    xp: ModuleType, a: Float[Array, "*#batch n k"], b: Float[Array, "*#batch k m"]
) -> Float[Array, "*batch n m"]:
    """``a @ b``, under JAX at full float32 precision (``Precision.HIGHEST``).

    JAX's default precision lets NVIDIA GPUs (and TPUs) multiply float32 matrices in
    TF32 or bfloat16 passes: about ``1e-3`` relative, several texels of a 4096² map.
    Every matrix product a fit makes under JAX goes through here (the test
    ``test_jax_matrix_products_ask_for_full_precision`` reads the traced programs).
    """
    if xp.__name__ == "numpy":
        return xp.matmul(a, b)
    import jax

    return xp.matmul(a, b, precision=jax.lax.Precision.HIGHEST)


def dot(
    xp: ModuleType, a: Float[Array, "*#batch k"], b: Float[Array, "*#batch k"]
) -> Float[Array, "*batch"]:
    """``sum(a * b, axis=-1)`` with broadcasting."""
    return xp.sum(a * b, axis=-1)


def cross(
    xp: ModuleType, a: Float[Array, "*#batch 3"], b: Float[Array, "*#batch 3"]
) -> Float[Array, "*batch 3"]:
    """The cross product of ``(..., 3)`` vectors (stacked, so it traces under jit)."""
    ax, ay, az = a[..., 0], a[..., 1], a[..., 2]
    bx, by, bz = b[..., 0], b[..., 1], b[..., 2]
    return xp.stack([ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx], axis=-1)


def _max_abs(
    xp: ModuleType, a: Float[Array, "*batch k"]
) -> tuple[Float[Array, "*batch"], Float[Array, "*batch k"], Bool[Array, "*batch"]]:
    """``(m, a / m, m > 0)`` with ``m = max |a_i|`` (1 in place of a zero ``m``)."""
    m = xp.max(xp.abs(a), axis=-1)
    nonzero = m > 0
    safe_m = xp.where(nonzero, m, xp.ones_like(m))
    return safe_m, a / safe_m[..., None], nonzero


def norm(xp: ModuleType, a: Float[Array, "*batch k"]) -> Float[Array, "*batch"]:
    """``|a|`` without overflow or underflow of the squares.

    The vector is first scaled by its largest component, so a float32 vector of
    size 1e25 or 1e-25 (whose squares leave float32's range) keeps its length.
    """
    m, b, nonzero = _max_abs(xp, a)
    sq = dot(xp, b, b)
    # Double where: sqrt is never differentiated at 0 (finite gradients at a = 0).
    safe_sq = xp.where(nonzero, sq, xp.ones_like(sq))
    return xp.where(nonzero, m * xp.sqrt(safe_sq), xp.zeros_like(sq))
