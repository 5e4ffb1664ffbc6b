"""Percentage-closer filtering at the door: the lookup's and the kernel's checks (the
comparisons are :mod:`shadowmath._math._pcf`'s)."""

from __future__ import annotations

import math

import numpy as np

from shadowmath._boundary._renamed import renamed_keywords
from shadowmath._boundary._shapes import ArrayLike, BoolLike, Float, IntLike, Real
from shadowmath._boundary._validate import (
    Array,
    Checks,
    all_finite,
    batch_shape,
    convert,
    non_finite,
    require_last,
    shape_error,
)
from shadowmath._math import _pcf
from shadowmath._math._bias import PcfFilter

from ._depth_bias import check_kernel


@renamed_keywords(radius="pcf_radius", filter="pcf_filter")
def pcf_border_texels(pcf_radius: IntLike, pcf_filter: PcfFilter = "box") -> int:
    r"""The empty border a shadow map needs around the silhouette for a PCF kernel.

    A lookup compares texel centres up to ``c`` texels away from ``(s, t)`` along
    each axis, with a nonzero weight only strictly inside that reach (``c = k + 1/2``
    for a box kernel of radius ``k``, ``c = k + 1`` for a bilinear one). A receiver
    point outside the map is lit (clamp-to-border, the rule of :func:`pcf`). An
    infinitely large map would agree only if no caster lies within reach of the
    map's outside: a point just past the edge reaches texels ``0 .. ceil(c - 1/2) - 1``
    of that edge, so they must be empty, or the soft shadow is cut off at the map's
    edge. And at least one edge texel must be empty for clamp-to-edge sampling
    (Nagy's border, :func:`border_margin`):

    .. math:: b = \max\left(1, \lceil c - \tfrac12 \rceil\right)
        = \begin{cases} \max(1, k) & \text{box} \\ k + 1 & \text{bilinear} \end{cases}

    Pass it as ``border_texels`` when fitting the map.

    Arguments:
        pcf_radius: the kernel radius ``k >= 0`` in texels (``radius=``, deprecated).
        pcf_filter: ``"box"`` or ``"bilinear"`` (``filter=``, deprecated).

    Returns:
        The number of empty texels needed on each side.

    Raises:
        ValueError: a negative or non-integer ``pcf_radius``, an unknown ``pcf_filter``.

    Example:
        >>> pcf_border_texels(0), pcf_border_texels(2), pcf_border_texels(2, "bilinear")
        (1, 2, 3)
    """
    k, filt = check_kernel(pcf_radius, pcf_filter)
    return _pcf.border_texels(k, filt)


@renamed_keywords(radius="pcf_radius", filter="pcf_filter")
def pcf(
    depth_map: Float[ArrayLike, "*#batch H W"],
    coords: Real[ArrayLike, "*#batch 2"],
    depths: Real[ArrayLike, "*#batch"],
    *,
    pcf_radius: IntLike = 1,
    pcf_filter: PcfFilter = "box",
    reversed_z: BoolLike = False,
    softness: float = 0.0,
) -> Float[Array, "*batch"]:
    r"""Percentage-closer filtering: the lit fraction of receiver points in ``[0, 1]``.

    .. math::

        \mathrm{lit}(s, t, d) = \sum_{(i, j)} w_{ij}(s, t)\;
            [\, d \le z_{ij} \,], \qquad \sum_{(i,j)} w_{ij} = 1

    over the kernel's texels (see the module docs: ``"box"``, equal weights on the
    ``(2k+1)^2`` texels around the one containing ``(s, t)``; ``"bilinear"``,
    separable tent weights on ``(2k+2)^2`` texels). ``[d >= z]`` with
    ``reversed_z``.

    **Outside the map: clamp-to-border, lit.** A point whose ``(s, t)`` lies outside
    ``[0, 1]^2`` gets ``1`` (the map says nothing about it: a receiver outside the
    light's frustum is lit by this map), and kernel texels that fall outside the
    map count as lit (a border depth that lights everything). Fit the map with
    :func:`pcf_border_texels` empty texels around the silhouette so that this never
    cuts a soft shadow off at the map's edge.

    **Batches.** ``depth_map`` is ``(*batch, H, W)``: its leading dimensions
    broadcast NumPy-style with those of ``coords`` (``(*batch, 2)``) and ``depths``
    (``(*batch,)``). One map for many points is ``(H, W)`` with ``(N, 2)``; ``B``
    maps with ``N`` points each are ``(B, 1, H, W)`` with ``(B, N, 2)``. Maps are
    gathered from, never copied per point.

    **Derivatives (JAX).** With ``"bilinear"`` the weights are continuous,
    piecewise-linear functions of ``(s, t)``: ``jax.grad`` with respect to
    ``coords`` is the derivative of the filtered shadow edge (``"box"`` weights are
    piecewise constant: zero almost everywhere). The comparison is a step, so with
    the default ``softness = 0`` the derivative with respect to ``depths`` is zero
    almost everywhere. With ``softness > 0`` (in the map's depth units) each
    comparison is the C1 smoothstep ``x^2 (3 - 2x)`` of
    ``x = clip((z - d) / softness + 1/2, 0, 1)``, exact (0 or 1) farther than
    ``softness / 2`` from the stored depth, so ``depths`` get derivatives through
    the comparisons near the shadow's depth edges too.

    Arguments:
        depth_map: ``(*batch, H, W)`` stored depths, a floating dtype (convert an
            integer depth buffer to ``[0, 1]`` first); row ``0`` is ``t = 0``.
        coords: ``(*batch, 2)`` texture coordinates ``(s, t)``.
        depths: ``(*batch,)`` the receivers' depths in the map's units (``r`` of
            ``world_to_texture``, minus any bias).
        pcf_radius: kernel radius ``k >= 0`` in texels (``radius=``, deprecated).
        pcf_filter: ``"box"`` or ``"bilinear"`` (``filter=``, deprecated).
        reversed_z: the map stores ``1`` at the near plane (lit when ``d >= z``).
        softness: width of the smooth comparison in depth units (``0``: a step).

    Returns:
        ``(*batch,)`` lit fractions in ``[0, 1]``.

    Raises:
        ValueError: a map that is not ``(*batch, H, W)`` with ``H, W >= 1``, or
            not of a floating dtype; ``coords`` not ``(*batch, 2)``; batch shapes
            that do not broadcast; a bad ``pcf_radius``, ``pcf_filter`` or ``softness``; a
            kernel whose border (:func:`pcf_border_texels`) leaves no texel inside
            the map; non-finite values (NaN under JAX transformations).

    Example:
        >>> import numpy as np
        >>> depth_map = np.ones((4, 4))
        >>> depth_map[:, :2] = 0.25  # a caster over the left half
        >>> pcf(depth_map, [[0.375, 0.5], [0.625, 0.5]], [0.5, 0.5], pcf_radius=1)
        array([0.33333333, 0.66666667])
    """
    k, filt = check_kernel(pcf_radius, pcf_filter)
    if not isinstance(reversed_z, bool | np.bool_):
        raise ValueError(f"reversed_z: expected True or False, got {reversed_z!r}")
    if not (isinstance(softness, int | float) and math.isfinite(softness) and softness >= 0):
        raise ValueError(f"softness: expected a finite number >= 0, got {softness!r}")
    kind = getattr(depth_map, "dtype", None)
    kind = np.dtype(kind).kind if kind is not None else np.asarray(depth_map).dtype.kind
    if kind != "f":
        raise ValueError(
            "depth_map: expected a floating dtype (depths in [0, 1]); "
            "divide an integer depth buffer by its maximum (2^bits - 1) first"
        )
    ctx, (Z, c, d) = convert(depth_map=depth_map, coords=coords, depths=depths)
    xp = ctx.xp
    if Z.ndim < 2 or Z.shape[-1] < 1 or Z.shape[-2] < 1:
        raise shape_error("depth_map", "(*batch, H, W) with H, W >= 1", tuple(Z.shape))
    require_last("coords", c, 2)
    shape = batch_shape(
        tuple(Z.shape[:-2]),
        tuple(c.shape[:-1]),
        tuple(d.shape),
        names=("depth_map", "coords", "depths"),
    )
    H, W = Z.shape[-2:]
    border = _pcf.border_texels(k, filt)
    if min(H, W) <= 2 * border:
        raise ValueError(
            f"pcf_radius: a {filt} kernel of radius {k} needs {border} empty border texels "
            f"on each side, which leaves no texel inside a {W} x {H} map"
        )
    checks = Checks(ctx)
    checks.require(all_finite(xp, Z, 2), non_finite("depth_map"))
    checks.require(all_finite(xp, c, 1), non_finite("coords"))
    checks.require(xp.isfinite(d), non_finite("depths"))
    lit = _pcf.pcf(
        xp, Z, c, d, radius=k, filter=filt, reversed_z=bool(reversed_z), softness=float(softness)
    )
    del shape
    return checks.poison(xp.asarray(lit), 0)
