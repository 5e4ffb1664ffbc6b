"""Typed lights: the light's kind is its type, never a value read at run time.

Each light is a NamedTuple of arrays, so it is a JAX pytree (``jit``, ``vmap`` and
``grad`` go through it) and takes leading batch dimensions like every array in
shadowmath. :func:`fit_shadow` picks the fit by the type: both kinds are never
computed for one entry. The homogeneous form ``(x, y, z, w)`` is read into one of
these types once per call (see :func:`fit_shadow`).
"""

from __future__ import annotations

from typing import NamedTuple, TypeAlias

from ._boundary._shapes import ArrayLike, Real


class PointLight(NamedTuple):
    """A point light (shining every way from a point): a perspective shadow map.

    Attributes:
        position: ``(*batch, 3)`` the light's position ``(x, y, z)`` in world coordinates.

    Example:
        >>> import numpy as np
        >>> PointLight(np.array([0.0, 4.0, 2.0])).position.shape
        (3,)
    """

    position: Real[ArrayLike, "*#batch 3"]


class DirectionalLight(NamedTuple):
    """A directional light (parallel rays, like the sun): an orthographic shadow map.

    Its fits' ``frustum`` is an :class:`OrthographicBox`.

    Attributes:
        direction: ``(*batch, 3)`` a vector pointing from the scene *toward* the
            light (any nonzero length): the homogeneous light ``(x, y, z, 0)``.

    Example:
        >>> import numpy as np
        >>> DirectionalLight(np.array([0.3, 1.0, -0.2])).direction.shape
        (3,)
    """

    direction: Real[ArrayLike, "*#batch 3"]


class SpotLight(NamedTuple):
    """A spot light: a point light shining into a cone. A perspective shadow map.

    The frame's ``Z`` is the cone's axis (not the blocker's mean direction), and the
    fitted frustum is the article's tight fit to the blocker's silhouette clipped to
    the cone's bounding square ``|x / z|, |y / z| <= tan(angle)``: no texel is spent
    outside that square, and no caster inside the cone is lost.

    Attributes:
        position: ``(*batch, 3)`` the light's position in world coordinates.
        direction: ``(*batch, 3)`` the cone's axis, from the light toward what it lights
            (any nonzero length).
        angle: ``(*batch,)`` the cone's half-angle in radians, in ``(0, pi/2)``.

    Example:
        >>> import numpy as np
        >>> spot = SpotLight(np.zeros(3), np.array([0.0, 0.0, 1.0]), np.array(0.5))
        >>> spot.angle.shape
        ()
    """

    position: Real[ArrayLike, "*#batch 3"]
    direction: Real[ArrayLike, "*#batch 3"]
    angle: Real[ArrayLike, "*#batch"]


#: Any typed light: what :func:`fit_shadow` and the other fits take beside the arrays.
Light: TypeAlias = PointLight | DirectionalLight | SpotLight
