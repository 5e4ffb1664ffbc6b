"""Smooth, still-conservative variants for gradient-based fitting.

The article's frustum takes hard maxima of the projection ratios: its gradient
flows to the extreme vertex only and jumps when another vertex takes over. Its
light frame picks a helper axis discretely: ``X`` and ``Y`` jump when two
components of ``Z`` tie. For optimisation this module offers

* :func:`smooth_max`, a log-sum-exp soft maximum that is an *upper bound* of
  the true maximum, so a frustum built from it never clips the blocker;
* :func:`smooth_frustum`, the (symmetric or off-centre) frustum from soft
  bounds of the ratios, and :func:`offcenter_frustum`, its exact (hard) limit;
* :func:`rolled_light_frame`, a light frame from a direction and a roll angle
  about it, continuous in both (the reference ``up`` axis is fixed, not chosen).

Trusted cores only: the public functions, which check their arguments and
call these, are in :mod:`shadowmath._geometry._smooth_frustum`.
"""

from __future__ import annotations

from types import ModuleType

from shadowmath._boundary._shapes import Float
from shadowmath._boundary._validate import Array


def smooth_max(
    xp: ModuleType,
    x: Float[Array, "*#batch n"],
    temperature: Float[Array, "*#batch"],
    weights: Float[Array, "*#batch n"] | None = None,
) -> Float[Array, "*batch"]:
    """``T log sum_i w_i exp(x_i / T)`` over the last axis, shifted by the hard max for range.

    The shift ``m = max x`` cancels mathematically (its derivative is
    ``1 - sum softmax = 0``), and keeps every exponent ``<= 0``, so nothing
    overflows. ``weights`` (0 or 1) drop padded entries.
    """
    m = xp.max(x, axis=-1)
    T = temperature[..., None]
    e = xp.exp((x - m[..., None]) / T)
    if weights is not None:
        e = e * weights
    return m + temperature * xp.log(xp.sum(e, axis=-1))


def soft_bounds(
    xp: ModuleType,
    rx: Float[Array, "*#batch n"],
    ry: Float[Array, "*#batch n"],
    T: Float[Array, "*#batch"],
    *,
    symmetric: bool,
    weights: Float[Array, "*#batch n"] | None = None,
) -> tuple[
    Float[Array, "*batch"], Float[Array, "*batch"], Float[Array, "*batch"], Float[Array, "*batch"]
]:
    """``(hi_x, lo_x, hi_y, lo_y)``: soft outer bounds of the ratios at temperature ``T``.

    ``weights`` (0 or 1 per vertex) drop padded entries.
    """
    if symmetric:
        # The soft max of (r, -r): a smooth upper bound of max |r| (abs is not smooth at 0).
        w2 = None if weights is None else xp.concat([weights, weights], axis=-1)
        hi_x = smooth_max(xp, xp.concat([rx, -rx], axis=-1), T, w2)
        hi_y = smooth_max(xp, xp.concat([ry, -ry], axis=-1), T, w2)
        return hi_x, -hi_x, hi_y, -hi_y
    return (
        smooth_max(xp, rx, T, weights),
        -smooth_max(xp, -rx, T, weights),
        smooth_max(xp, ry, T, weights),
        -smooth_max(xp, -ry, T, weights),
    )
