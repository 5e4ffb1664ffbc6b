"""Blinn's planar-projection shadow matrix ("Me and My (Fake) Shadow", 1988)."""

from __future__ import annotations

import math

import numpy as np

from shadowmath._backends import _kernels
from shadowmath._boundary import _status
from shadowmath._boundary._shapes import ArrayLike, Float, Real
from shadowmath._boundary._validate import (
    Array,
    Checks,
    Context,
    all_finite,
    batch_shape,
    convert,
    flat_batch,
    non_finite,
    raise_status,
    require_last,
)
from shadowmath._math._frame import stack_matrix
from shadowmath._math._specialize import formulas


def planar_projection(
    plane: Real[ArrayLike, "*#batch 4"], light: Real[ArrayLike, "*#batch 4"]
) -> Float[Array, "*batch 4 4"]:
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
    require_last("plane", pi, 4, hint="a plane is (a, b, c, d) for a x + b y + c z + d = 0")
    require_last(
        "light", L, 4, hint="a light is (x, y, z, w): append w=1 for a point, w=0 for a direction"
    )
    shape = batch_shape(pi.shape[:-1], L.shape[:-1], names=("plane", "light"))
    if not ctx.is_jax and _kernels.available():
        return _planar_compiled(ctx, shape, pi, L)
    xp = ctx.xp
    checks = Checks(ctx)
    checks.require(all_finite(xp, pi, 1), _MESSAGES[0][1])
    checks.require(all_finite(xp, L, 1), _MESSAGES[1][1])
    nmant = np.finfo(ctx.dtype).nmant
    splitter = float(2 ** ((nmant + 2) // 2) + 1)  # 2^27 + 1 (float64), 2^12 + 1 (float32)
    e = formulas(xp).planar_entries(
        tuple(pi[..., i] for i in range(4)), tuple(L[..., i] for i in range(4)), splitter
    )
    checks.require(e[18] > 0, _MESSAGES[2][1])
    checks.require(xp.any(L != 0, axis=-1), _MESSAGES[3][1])
    # The threshold is relative to the terms' size, never an absolute distance:
    # a light within a few ulps of the scene's scale from the plane is in it as
    # far as the rounding of its own coordinates can tell.
    checks.require(xp.abs(e[16]) > 16 * ctx.eps * e[17], _MESSAGES[4][1])
    M = xp.broadcast_to(stack_matrix(xp, e[:16]), (*shape, 4, 4))
    return checks.poison(M, 2)


_MESSAGES = (
    (_status.PLANAR_NONFINITE_PLANE, non_finite("plane")),
    (_status.PLANAR_NONFINITE_LIGHT, non_finite("light")),
    (
        _status.PLANAR_ZERO_NORMAL,
        "plane: the normal (a, b, c) is zero; a plane needs a nonzero normal",
    ),
    (
        _status.PLANAR_ZERO_LIGHT,
        "light: all components are zero; use (x, y, z, 1) for a point light or "
        "(dx, dy, dz, 0) with a nonzero direction for a directional light",
    ),
    (
        _status.PLANAR_IN_PLANE,
        "light lies in the plane (plane . light = 0): a point light on the plane, or a "
        "directional light parallel to it, collapses the projection; move the light off "
        "the plane or tilt it",
    ),
)


def _planar_compiled(ctx: Context, shape: tuple[int, ...], pi: Array, L: Array) -> Array:
    """:func:`planar_projection` through the compiled loop (NumPy input, Numba installed)."""
    count = math.prod(shape)
    out = np.empty((count, 16), dtype=ctx.dtype)
    status = np.empty(count, dtype=np.int32)
    _kernels.loops().planar_loop(
        flat_batch(pi, shape, (4,)), flat_batch(L, shape, (4,)), ctx.eps, out, status
    )
    if status[0] if count == 1 else status.any():
        raise_status(status.reshape(shape), _MESSAGES)
    return out.reshape(*shape, 4, 4)
