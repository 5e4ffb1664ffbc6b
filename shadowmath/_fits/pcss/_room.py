r"""Room for the PCSS kernel: :func:`pcss_border_texels` and :func:`widen_cascades`.

The blocker search of :func:`~shadowmath.pcss_parameters` reaches ``K |d_R - d_near|``
texels from a receiver, at most ``max(K)`` (a stored depth spans at most 1): a map's
border must hold that, and a cascade's box must hold every caster inside the search
region of a receiver in its slice.
"""

from __future__ import annotations

import math

import numpy as np

from shadowmath._boundary._shapes import ArrayLike, Real
from shadowmath._boundary._validate import Checks, convert
from shadowmath._fits.cascades._result import Cascades
from shadowmath._geometry._depth_bias import check_kernel
from shadowmath._math._bias import PcfFilter
from shadowmath._math._pcf import border_texels

from ._driver import BAD_ANGLE, angle_ok
from ._result import PcssParameters


def pcss_border_texels(parameters: PcssParameters, *, pcf_filter: PcfFilter = "box") -> int:
    r"""The border (texels on each side) that holds every PCSS kernel of these maps.

    The search reaches ``K |d_R - d_near| <= max(K)`` texels (stored depths span at most
    1) and the filter no farther (``d_B`` lies between ``d_near`` and ``d_R``); sampled
    ``pcf_filter``'s way it reads :func:`pcf_border_texels` of ``k = ceil(max K)``:

    .. math:: b = \max\left(1, \lceil k + c - \tfrac12 \rceil\right),
        \qquad c = \tfrac12 \text{ (box)}, \ 1 \text{ (bilinear)}.

    Refit the map with ``border_texels=b``: a wider border leaves fewer texels per unit,
    so ``K`` only shrinks and ``b`` still holds (no second round). In an atlas, allocate
    the tiles with it (:func:`allocate_atlas`'s ``border_texels``).

    Arguments:
        parameters: :class:`PcssParameters` of one map or many (the largest ``K`` counts;
            NaN entries, such as a failed atlas tile's, are ignored).
        pcf_filter: ``"box"`` (nearest taps) or ``"bilinear"``.

    Returns:
        The border in texels.

    Raises:
        ValueError: no finite ``K``; an unknown ``pcf_filter``.

    Example:
        >>> import numpy as np, shadowmath as sm
        >>> p = sm.PcssParameters(np.array([7.2, 3.0]), np.array(0.0))
        >>> pcss_border_texels(p), pcss_border_texels(p, pcf_filter="bilinear")
        (8, 9)
    """
    if not isinstance(parameters, PcssParameters):
        raise ValueError(f"parameters: expected PcssParameters, got {type(parameters).__name__}")
    K = np.asarray(parameters.texels_per_depth, dtype=np.float64)
    finite = K[np.isfinite(K)]
    if finite.size == 0:
        raise ValueError("parameters: no finite texels_per_depth")
    reach, filt = check_kernel(math.ceil(float(finite.max())), pcf_filter)
    return border_texels(reach, filt)


def widen_cascades(cascades: Cascades, *, angular_radius: Real[ArrayLike, "*#batch"]) -> Cascades:
    r"""Cascades whose boxes hold every caster of their receivers' blocker search (Godot's rule).

    A receiver at depth ``z`` in a cascade searches the sun's cone back to the near plane,
    a disk of ``tan(theta) (z - n)`` world units, at most ``w = tan(theta) (f - n)``. Each
    box's half-width and half-height grow by ``w`` about its centre: with ``h`` the
    half-width, the maps' ``x`` and ``y`` scale by ``k = h / (h + w)``,

    .. math::

        M'_\mathrm{clip} = \mathrm{diag}(k_x, k_y, 1, 1)\, M_\mathrm{clip}, \qquad
        M'_\mathrm{tex} = (M_\mathrm{tex} M_\mathrm{clip}^{-1})\, M'_\mathrm{clip},

    texel sizes ``/ k``; depths, splits and tiles unchanged (the depth range already starts
    at the scene's corner nearest the light). Draw and sample the result as the original.
    Refused for stable cascades (their fixed, snapped squares would shimmer: NaN under JAX
    transformations; the message gives the ``border_texels`` to refit them with, whose
    border holds the search at a fixed size: with ``r`` the sphere's radius and ``W`` the
    map's width, ``b >= w (W - 1) / (2 (r + w))`` texels, since the texel is
    ``2 r / (W - 2 b - 1)``) and warped ones.

    Arguments:
        cascades: :func:`fit_cascades`' result, not ``stable``, no ``warp``.
        angular_radius: ``(*batch,)`` the sun's angular radius in radians, ``[0, pi/2)``.

    Returns:
        :class:`Cascades`, the same fields with wider boxes.

    Raises:
        ValueError: an angle outside ``[0, pi/2)`` (NaN under JAX transformations), stable
            or warped cascades, a ``cascades`` that is not :class:`Cascades`.

    Example:
        >>> import numpy as np, shadowmath as sm
        >>> view = np.eye(4); view[2, 3] = -5.0
        >>> proj = np.array([[1.0, 0, 0, 0], [0, 1, 0, 0], [0, 0, -1.02, -2.02], [0, 0, -1, 0]])
        >>> box = np.array([[-20.0, -1, -40], [20, 3, 10]])
        >>> c = sm.fit_cascades([0.3, 1.0, 0.2], view, proj, box, 1024, count=2)
        >>> wide = widen_cascades(c, angular_radius=np.radians(1.0))
        >>> bool(np.all(wide.frustum.half_width > c.frustum.half_width))
        True
    """
    if not isinstance(cascades, Cascades):
        raise ValueError(f"cascades: expected Cascades, got {type(cascades).__name__}")
    ctx, (clip, tex, theta, stable) = convert(
        world_to_clip=cascades.world_to_clip,
        world_to_texture=cascades.world_to_texture,
        angular_radius=angular_radius,
        half_width=cascades.state.half_width,
    )
    xp, checks = ctx.xp, Checks(ctx)
    if not ctx.lazy and bool(xp.any(xp.isfinite(stable))):
        raise ValueError(_stable_refusal(cascades, theta))
    checks.require(
        ~xp.isfinite(stable),
        "cascades: stable cascades cannot be widened (their squares keep a fixed size on a "
        "fixed texel grid, so that they do not shimmer); fit them with stable=False to widen "
        "them, or widen the stable squares by refitting with a larger border_texels",
    )
    checks.require(angle_ok(xp, theta), BAD_ANGLE)
    if not ctx.lazy and not bool(xp.all(tex[..., 3, :3] == 0)):
        raise ValueError("cascades: warped cascades (warp='lispsm') are not boxes")
    box = cascades.frustum
    w = xp.tan(theta)[..., None] * (box.far - box.near)
    hx, hy = box.half_width + w, box.half_height + w
    kx, ky = box.half_width / hx, box.half_height / hy
    wide_clip = xp.concatenate(
        (clip[..., :1, :] * kx[..., None, None], clip[..., 1:2, :] * ky[..., None, None],
         clip[..., 2:, :]), axis=-2,
    )  # fmt: skip
    wide_tex = (tex @ xp.linalg.inv(clip)) @ wide_clip
    texel = cascades.texel_size / xp.stack((kx, ky), axis=-1)
    return cascades._replace(
        world_to_clip=checks.poison(wide_clip, 2),
        world_to_texture=checks.poison(wide_tex, 2),
        frustum=box._replace(half_width=checks.poison(hx, 0), half_height=checks.poison(hy, 0)),
        texel_size=checks.poison(texel, 1),
    )


def _stable_refusal(cascades: Cascades, theta: object) -> str:
    """The refusal of stable cascades, with the border that holds their blocker search: the
    map's half-extent ``h + b t`` must reach ``r + w`` (``h = r / (1 - 1 / (m W))``, the
    texel ``t = 2 h / (m W) = 2 r / (W - 2 b - 1)``), so ``b >= w (W - 1) / (2 (r + w))``."""
    box = cascades.frustum
    width = np.asarray(cascades.viewports, dtype=np.float64)[:, 2]
    m = np.asarray(box.margin_x, dtype=np.float64)
    r = np.asarray(box.half_width, dtype=np.float64) * (1 - 1 / (m * width))
    w = np.tan(np.asarray(theta, dtype=np.float64))[..., None] * np.asarray(
        box.far - box.near, dtype=np.float64
    )
    need = w * (width - 1) / (2 * (r + w))
    finite = need[np.isfinite(need)]
    border = math.ceil(float(finite.max())) if finite.size else 1
    reach = float(np.max(w)) if np.all(np.isfinite(w)) else math.nan
    return (
        "cascades: stable cascades cannot be widened: their squares keep one size on a texel "
        "grid fixed in the world, so that their shadows do not shimmer, and widening would "
        f"change both. Refit them with border_texels={max(border, 1)} or more: the border then "
        f"holds every caster of the blocker search (up to {reach:.3g} world units here) at a "
        "fixed size. Or fit them with stable=False, and widen those."
    )
