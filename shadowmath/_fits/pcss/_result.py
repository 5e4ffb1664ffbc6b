"""What the PCSS functions return: :class:`PcssParameters` and :class:`PcssWidths`."""

from __future__ import annotations

from typing import NamedTuple

from shadowmath._boundary._shapes import Float
from shadowmath._boundary._validate import Array


class PcssParameters(NamedTuple):
    """What a PCSS shader needs of one shadow map (:func:`pcss_parameters`).

    Attributes:
        texels_per_depth: ``(*maps, 2)`` ``K``: the blocker search radius and the penumbra
            width in texels (along the texture's ``s`` and ``t``) per unit of stored depth.
        near_depth: ``(*maps,)`` ``d_near``: the depth stored at the map's near plane, 0
            (or 1 with reversed Z): no caster is nearer the light.
    """

    texels_per_depth: Float[Array, "*maps 2"]
    near_depth: Float[Array, "*maps"]


class PcssWidths(NamedTuple):
    """The blocker search radius and the penumbra width in texels (:func:`pcss_widths`).

    Attributes:
        search: ``(*batch, 2)`` the blocker search radius along ``s`` and ``t``: the light
            as the receiver sees it, on the near plane (the light's size in texels at the
            receiver's depth).
        penumbra: ``(*batch, 2)`` the penumbra's half-width (the PCF filter's radius).
    """

    search: Float[Array, "*batch 2"]
    penumbra: Float[Array, "*batch 2"]
