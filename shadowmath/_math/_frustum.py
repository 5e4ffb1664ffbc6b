"""The shadow map's volume: a perspective frustum or an orthographic box, and its projections.

Light coordinates (see :mod:`shadowmath._frame`) have the light at the origin
and ``+Z`` toward the blocker. A light-space point ``(x, y, z)`` with ``z > 0``
projects to the ratios ``x / z`` and ``y / z``; the frustum scales the largest
of them to the border margin, so the blocker's silhouette fills the map up to a
border of untouched texels. A directional light's map is an orthographic box
instead (:class:`OrthographicBox`): two types, so that no field changes meaning.

Trusted cores only: the public functions, which check their arguments and
call these, are in :mod:`shadowmath._geometry._adaptive_frustum`.
"""

from __future__ import annotations

from types import ModuleType
from typing import Any, NamedTuple

import numpy as np

from shadowmath._boundary._renamed import warn_renamed
from shadowmath._boundary._shapes import ArrayLike, Bool, Float, Scalar
from shadowmath._boundary._validate import Array

from ._specialize import formulas

#: Relative slack of the default near and far planes around the blocker:
#: ``near = z_min * (1 - NEAR_FAR_SLACK)``, ``far = z_max * (1 + NEAR_FAR_SLACK)``.
NEAR_FAR_SLACK = 1.0 / 64.0

#: The default of the deprecated ``Frustum(orthographic=...)``: not given.
_NOT_GIVEN: Any = object()


class _FrustumFields(NamedTuple):
    """The fields of :class:`Frustum` (a base, so that ``Frustum`` can take the old flag)."""

    rx_max: Array
    ry_max: Array
    near: Array
    far: Array
    margin_x: Array
    margin_y: Array
    x_offset: Array = 0.0
    y_offset: Array = 0.0


class Frustum(_FrustumFields):
    """A perspective frustum in light coordinates, symmetric unless offset.

    A light-space point ``(x, y, z)`` maps to NDC
    ``x_ndc = m_x (x / z - c_x) / R_x``, ``y_ndc = m_y (y / z - c_y) / R_y``.
    A directional light's map is an :class:`OrthographicBox` instead.

    Attributes (each ``(*batch,)``):
        rx_max: half-width :math:`R_x` of the frustum at ``z = 1`` about its centre: for
            the article's symmetric frustum, the largest ``|x / z|`` of the blocker.
        ry_max: the same along light ``Y``.
        near: distance of the near plane from the light (``z``), ``> 0``.
        far: distance of the far plane, ``> near``.
        margin_x: fraction :math:`m_x` of the map's half-width the silhouette may fill
            (``(width - 2 border) / width``; the article's 0.98).
        margin_y: the same along light ``Y`` (the map's height).
        x_offset: the ratio :math:`c_x = x / z` at the map's centre (default 0:
            symmetric). An off-centre frustum spans ``x / z`` in
            ``[x_offset - rx_max, x_offset + rx_max]`` (before the margin).
        y_offset: the same along light ``Y``.

    Deprecated: ``Frustum(..., orthographic=True)`` gives an :class:`OrthographicBox`
    (``orthographic=False`` a ``Frustum``), and ``frustum.orthographic`` reads
    ``False``, each with a ``DeprecationWarning``: tell the two apart with
    ``isinstance(frustum, OrthographicBox)``.

    Example:
        >>> fr = Frustum(0.5, 0.25, 1.0, 3.0, 0.98, 0.98)
        >>> fr.rx_max, fr.x_offset
        (0.5, 0.0)
    """

    __slots__ = ()

    def __new__(cls, *fields: Array, **named: Array) -> Frustum:
        """``Frustum(rx_max, ry_max, near, far, margin_x, margin_y, x_offset=0, y_offset=0)``
        (positional or by name); the deprecated ninth field ``orthographic`` returns the
        type it describes."""
        orthographic = named.pop("orthographic", _NOT_GIVEN)
        if len(fields) == 9:  # the old ninth positional field
            *fields, orthographic = fields  # type: ignore[assignment]
        base = _FrustumFields(*fields, **named)  # the NamedTuple's own argument checks
        if orthographic is _NOT_GIVEN:
            return tuple.__new__(cls, base)
        warn_renamed(
            "Frustum(orthographic=...)",
            "OrthographicBox (half_width, half_height, near, far, margin_x, margin_y, "
            "center_x, center_y) for a directional light's box, Frustum for a perspective one",
        )
        return volume(base, _static_flag(orthographic))  # type: ignore[return-value]

    @property
    def orthographic(self) -> bool:
        """Deprecated: always ``False``; use ``isinstance(frustum, OrthographicBox)``."""
        warn_renamed("Frustum.orthographic", "isinstance(frustum, OrthographicBox)")
        return False


class OrthographicBox(NamedTuple):
    """An orthographic box in light coordinates: a directional light's shadow map.

    A light-space point ``(x, y, z)`` maps to NDC
    ``x_ndc = m_x (x - c_x) / R_x``, ``y_ndc = m_y (y - c_y) / R_y``, and depth
    ``-1`` at ``z = near``, ``+1`` at ``z = far``. Lengths are world units.

    Attributes (each ``(*batch,)``):
        half_width: :math:`R_x`, the box's half-width along light ``X`` about its
            centre, before the margin (the blocker's extent).
        half_height: :math:`R_y`, the same along light ``Y``.
        near: the near plane's ``z`` (it may be negative: the box needs no eye).
        far: the far plane's ``z``, ``> near``.
        margin_x: fraction :math:`m_x` of the map's half-width the box fills
            (``(width - 2 border) / width``).
        margin_y: the same along light ``Y`` (the map's height).
        center_x: :math:`c_x`, the light ``x`` of the box's centre line (default 0).
        center_y: :math:`c_y`, the same along light ``Y``.

    Deprecated: the :class:`Frustum` names ``rx_max``, ``ry_max``, ``x_offset``,
    ``y_offset`` read ``half_width``, ``half_height``, ``center_x``, ``center_y``, and
    ``orthographic`` reads ``True``, each with a ``DeprecationWarning``.

    Example:
        >>> box = OrthographicBox(2.0, 1.0, -1.0, 5.0, 0.98, 0.98, center_x=3.0)
        >>> box.half_width, box.center_x
        (2.0, 3.0)
    """

    half_width: Array
    half_height: Array
    near: Array
    far: Array
    margin_x: Array
    margin_y: Array
    center_x: Array = 0.0
    center_y: Array = 0.0

    @property
    def rx_max(self) -> Array:
        """Deprecated name of :attr:`half_width`."""
        warn_renamed("OrthographicBox.rx_max", "half_width")
        return self.half_width

    @property
    def ry_max(self) -> Array:
        """Deprecated name of :attr:`half_height`."""
        warn_renamed("OrthographicBox.ry_max", "half_height")
        return self.half_height

    @property
    def x_offset(self) -> Array:
        """Deprecated name of :attr:`center_x`."""
        warn_renamed("OrthographicBox.x_offset", "center_x")
        return self.center_x

    @property
    def y_offset(self) -> Array:
        """Deprecated name of :attr:`center_y`."""
        warn_renamed("OrthographicBox.y_offset", "center_y")
        return self.center_y

    @property
    def orthographic(self) -> bool:
        """Deprecated: always ``True``; use ``isinstance(box, OrthographicBox)``."""
        warn_renamed("OrthographicBox.orthographic", "isinstance(box, OrthographicBox)")
        return True


def volume(
    fields: tuple[Scalar, ...] | Float[Array, " 8 *batch"], directional: bool
) -> Frustum | OrthographicBox:
    """The light's map volume of 8 trusted fields in their common order.

    ``(R_x, R_y, near, far, m_x, m_y, c_x, c_y)``: an :class:`OrthographicBox` for a
    directional light, else a :class:`Frustum` (a static choice, fine under ``jit``).
    """
    return OrthographicBox._make(fields) if directional else Frustum._make(fields)


def _static_flag(orthographic: bool | Bool[ArrayLike, "*batch"]) -> bool:
    """The deprecated ``orthographic`` flag as one bool (a batch must not mix kinds)."""
    if isinstance(orthographic, bool | np.bool_):
        return bool(orthographic)
    flags = np.asarray(orthographic, dtype=bool)
    if flags.all() or not flags.any():
        return bool(flags.all())
    raise ValueError(
        "orthographic: a batch mixes perspective and orthographic entries; give a Frustum "
        "for the perspective ones and an OrthographicBox for the orthographic ones"
    )


def blocker_reach(
    xp: ModuleType, light: Float[Array, "*#batch 3"], verts: Float[Array, "*#batch N 3"]
) -> Float[Array, "*batch"]:
    """``(*batch,)`` the largest coordinate of any ``V - L``: the scale of the rounding noise."""
    return xp.max(xp.abs(verts - light[..., None, :]), axis=(-2, -1))


def projection_terms(
    xp: ModuleType, fr: Frustum | OrthographicBox
) -> tuple[Float[Array, "*batch"], ...]:
    """``(sx, -sx cx, sy, -sy cy, a, b)``: the nonzero entries of the blocker projection."""
    half_x, half_y, near, far, margin_x, margin_y, cx, cy = fr
    sx, sy = margin_x / half_x, margin_y / half_y
    terms: tuple[Array, ...] = formulas(xp).projection_rows((sx, sy), (cx, cy), near, far)
    return terms


def projection_entries(
    xp: ModuleType, fr: Frustum | OrthographicBox
) -> tuple[Float[Array, "*batch"], ...]:
    """The 16 entries of the blocker projection of a trusted frustum or box (by its type)."""
    sx, sxc, sy, syc, a, b = projection_terms(xp, fr)
    zero = xp.zeros_like(sx)
    one = zero + 1
    if not isinstance(fr, OrthographicBox):
        return (
            sx, zero, sxc, zero,
            zero, sy, syc, zero,
            zero, zero, a, b,
            zero, zero, one, zero,
        )  # fmt: skip
    # Orthographic entries (far > near for a valid box; a bad entry is poisoned by its checks).
    depth = fr.far - fr.near
    inv = 1.0 / xp.where(depth > 0, depth, xp.ones_like(depth))
    oa, ob = 2.0 * inv, -(fr.far + fr.near) * inv
    return (
        sx, zero, zero, sxc,
        zero, sy, zero, syc,
        zero, zero, oa, ob,
        zero, zero, zero, one,
    )  # fmt: skip
