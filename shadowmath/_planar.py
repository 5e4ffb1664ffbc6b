"""Blinn's planar-projection shadow matrix ("Me and My (Fake) Shadow", 1988)."""

from __future__ import annotations

from typing import Any

from ._validate import Array, Checks, all_finite, batch_shape, convert, non_finite, require_last
from ._vector import accurate_dot, norm


def planar_projection(plane: Any, light: Any) -> Array:
    r"""The matrix that flattens geometry onto ``plane`` as seen from ``light``.

    .. math::

        M = \operatorname{sign}(\pi \cdot L)\,\big((\pi \cdot L)\, I - L\, \pi^{\mathsf T}\big)

    For a homogeneous point ``p``, ``M @ p = (pi.L) p - (pi.p) L`` is the
    intersection of the line through ``p`` and ``L`` with the plane: indeed
    ``pi . (M p) = (pi.L)(pi.p) - (pi.p)(pi.L) = 0``. The light is the null
    vector of ``M`` and ``M @ M = |pi.L| M`` (a projection, up to scale).

    **Orientation.** The plane's sign is free (``pi`` and ``-pi`` are the same
    plane) but the matrix's is not: the homogeneous ``w`` of a projected point
    between the light and the plane is ``|pi.L| - s (pi.p) L_w`` with
    ``s = sign(pi.L)``, which the factor ``sign(pi.L)`` makes positive
    whichever sign the caller gave the plane, so GPU clipping keeps the shadow.

    **Anti-shadows.** For a point light, a point *beyond* the light (farther
    from the plane than the light, on the same side) gets ``w < 0``: its line
    through the light meets the plane on the wrong side, a false "anti-shadow"
    that clipping removes only if ``w < 0`` survives to the rasterizer (draw
    with clipping on; never divide by ``w`` on the CPU without checking its
    sign). Points on the far side of the plane get ``w > 0`` and land on the
    plane too: confine the shadow to the receiver (stencil or mask). For a
    directional light ``w = |pi.L|`` is the same for every point.

    **Singular.** ``M`` has rank 3 (it collapses space onto a plane): never
    invert it.

    Arguments:
        plane: ``(*batch, 4)`` plane ``(a, b, c, d)`` with ``a x + b y + c z + d = 0``.
        light: ``(*batch, 4)`` homogeneous light ``(x, y, z, w)``: ``w = 1`` a point
            light at ``(x, y, z)`` (any ``w != 0`` means the point ``xyz / w``),
            ``w = 0`` a directional light whose ``(x, y, z)`` points from the
            scene toward the light.

    Returns:
        ``(*batch, 4, 4)`` column-vector matrix (``p' = M @ p``), batch
        dimensions broadcast.

    Raises:
        ValueError: wrong shapes; non-finite values; a plane with a zero normal;
            a light of all zeros (a zero directional light); the light lying in
            the plane (``pi . L = 0`` relative to the scene's scale: a point
            light on the plane or a directional light parallel to it). Under JAX
            transformations the affected matrices are NaN instead.

    Example:
        >>> import numpy as np
        >>> M = planar_projection([0, 1, 0, 0], [0, 10, 0, 1])  # floor y=0, light above
        >>> p = M @ np.array([1.0, 5.0, 0.0, 1.0])
        >>> p[:3] / p[3]  # the shadow of (1, 5, 0) lands at x = 2 on the floor
        array([2., 0., 0.])
    """
    ctx, (pi, L) = convert(plane=plane, light=light)
    xp = ctx.xp
    require_last("plane", pi, 4, hint="a plane is (a, b, c, d) for a x + b y + c z + d = 0")
    require_last(
        "light", L, 4, hint="a light is (x, y, z, w): append w=1 for a point, w=0 for a direction"
    )
    shape = batch_shape(pi.shape[:-1], L.shape[:-1], names=("plane", "light"))

    checks = Checks(ctx)
    checks.require(all_finite(xp, pi, 1), non_finite("plane"))
    checks.require(all_finite(xp, L, 1), non_finite("light"))
    n_len = norm(xp, pi[..., :3])
    checks.require(n_len > 0, "plane: the normal (a, b, c) is zero; a plane needs a nonzero normal")
    checks.require(
        xp.any(L != 0, axis=-1),
        "light: all components are zero; use (x, y, z, 1) for a point light or "
        "(dx, dy, dz, 0) with a nonzero direction for a directional light",
    )
    # pi.L cancels for a light close to the plane far from the origin (terms of
    # size |n||l| and |d w|, a small sum): compensated, it is accurate to an ulp
    # of itself, so its sign (which orients M) and size are right.
    pi_dot_L = accurate_dot(xp, pi, L)
    # The threshold is relative to the terms' size, never an absolute distance:
    # a light within a few ulps of the scene's scale from the plane is in it as
    # far as the rounding of its own coordinates can tell.
    scale = n_len * norm(xp, L[..., :3]) + xp.abs(pi[..., 3] * L[..., 3])
    checks.require(
        xp.abs(pi_dot_L) > 16 * ctx.eps * scale,
        "light lies in the plane (plane . light = 0): a point light on the plane, or a "
        "directional light parallel to it, collapses the projection; move the light off "
        "the plane or tilt it",
    )

    sign = xp.where(pi_dot_L < 0, ctx.constant(-1.0), ctx.constant(1.0))
    # Diagonal entries (pi.L) - L_i pi_i are the other three terms of pi.L:
    # summed directly (compensated) they keep full relative precision where the
    # subtraction would cancel. Off-diagonal entries are single products.
    others = xp.ones((4, 4), dtype=ctx.dtype) - xp.eye(4, dtype=ctx.dtype)
    diagonal = accurate_dot(xp, pi[..., None, :], L[..., None, :] * others)
    off_diagonal = -(sign[..., None, None] * L[..., :, None]) * pi[..., None, :]
    is_diagonal = xp.eye(4, dtype=xp.bool)
    M = xp.where(is_diagonal, (sign[..., None] * diagonal)[..., None, :], off_diagonal)
    M = xp.broadcast_to(M, (*shape, 4, 4))
    return checks.poison(M, 2)
