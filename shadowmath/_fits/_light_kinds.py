"""A light's kind, read in one place: typed lights, homogeneous ``(x, y, z, w)``, spot rows.

:func:`fit_shadow` (one kind per call) and :func:`fit_atlas` (a kind per light) read
lights through these: the kind of a typed light is its type (:data:`KIND_OF`); a
homogeneous light is directional where ``w == 0`` (``xyz`` points toward the light)
and a point light at ``xyz / w`` elsewhere (:func:`homogeneous`); a spot light is
packed as one row of 8 numbers, position, axis, ``tan(angle)`` and angle
(:func:`spot_rows`), which is what the fits' drivers read.
"""

from __future__ import annotations

import math
from types import ModuleType

from shadowmath._boundary._validate import Array
from shadowmath.lights import DirectionalLight, PointLight, SpotLight

#: The kinds' codes (a light's kind is static: each code selects one fit).
POINT, SPOT, SUN = 0, 1, 2

#: The kind of each typed light.
KIND_OF: dict[type, int] = {PointLight: POINT, SpotLight: SPOT, DirectionalLight: SUN}


def homogeneous(xp: ModuleType, L: Array) -> tuple[Array, Array]:
    """``(*batch, 4)`` homogeneous lights: where each is directional (``w == 0``), and
    ``(*batch, 3)`` its direction toward the light (``xyz``) or its position (``xyz / w``)."""
    w = L[..., 3:]
    sun = w == 0
    xyz = L[..., :3] / xp.where(sun, xp.ones_like(w), w)
    return sun[..., 0], xp.where(sun, L[..., :3], xyz)


def spot_rows(xp: ModuleType, position: Array, direction: Array, angle: Array) -> Array:
    """Spot lights as ``(*batch, 8)`` rows: position, axis, ``tan(angle)``, angle
    (arrays of one broadcast batch shape: ``(*batch, 3)``, ``(*batch, 3)``, ``(*batch,)``)."""
    a = angle[..., None]
    return xp.concatenate([position, direction, xp.tan(a), a], axis=-1)


def spot_row(position: list[float], direction: list[float], angle: float) -> list[float]:
    """One spot light's row of :func:`spot_rows` as Python floats (the atlas's lights)."""
    return [*position, *direction, math.tan(angle), angle]


__all__ = ["KIND_OF", "POINT", "SPOT", "SUN", "homogeneous", "spot_row", "spot_rows"]
