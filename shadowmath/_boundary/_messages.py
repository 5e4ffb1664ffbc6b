"""The value errors shared by the array path and the compiled loop, word for word.

A check that several functions (and both backends) perform has its message here,
so that the same bad input gets the same ``ValueError`` whichever path ran.
"""

import warnings


class ShadowFitWarning(UserWarning):
    """A fit that is valid but wasteful: past a documented soft limit (see :func:`fit_shadow`),
    or computed at another precision than its input's (float16 arguments, computed and
    returned in float32)."""


def warn_wide() -> None:
    """Warn that a point-light fit is wider than ``WIDE_FOV_DEGREES`` (NumPy input)."""
    warnings.warn(WIDE, ShadowFitWarning, stacklevel=4)


ZERO_DIRECTION = (
    "the light's viewing direction is zero: the light sits at the blocker's centre "
    "(zero mean direction vector, or one within rounding of zero); move the light or "
    "pass an explicit direction to light_frame_from_direction"
)
BEHIND_LIGHT = (
    "vertices: a blocker vertex is not strictly in front of the light (z <= 0 in light "
    "coordinates, or within rounding of 0); one frustum cannot cover it: move the light "
    "out of the blocker, or split the blocker (or use an omnidirectional shadow map)"
)
ZERO_SILHOUETTE = (
    "vertices: the blocker's silhouette has zero width or height as seen from the light "
    "(a single point, or a flat blocker seen edge-on, within rounding); no frustum can "
    "be fitted"
)
NEAR_NOT_FINITE = "near: must be finite"
FAR_NOT_FINITE = "far: must be finite"
NEAR_POSITIVE = "near: the near plane must lie in front of the light (near > 0)"
NEAR_FAR = "near/far: the near plane must be closer than the far plane"
NEAR_CLIPS = (
    "near: the near plane cuts into the blocker (near > the closest vertex's z in light "
    "coordinates), so the GPU would clip part of the blocker out of the shadow map; pass "
    "a smaller near (or None for the default just in front of the blocker)"
)
FAR_CLIPS = (
    "far: the far plane cuts into the blocker (far < the farthest vertex's z in light "
    "coordinates), so the GPU would clip part of the blocker out of the shadow map; pass "
    "a larger far (or None for the default just behind the blocker)"
)


def not_affine(name: str) -> str:
    """The refusal of a placement ``name`` whose last row is not ``(0, 0, 0, 1)``."""
    return (
        f"{name}: its last row is not (0, 0, 0, 1) to rounding: the matrix looks row-major "
        "(transposed: the translation in the bottom row, as row-vector APIs store it) or "
        "projective; give the column-vector local-to-world matrix (transpose a row-major one)"
    )


AFFINE_PLACEMENT = not_affine("blocker_to_world")
PROJECTIVE_PLACEMENT = (
    "blocker_to_world: sends a blocker vertex to w <= 0 (a projective placement); "
    "use an affine placement, last row (0, 0, 0, 1)"
)
OVERFLOW = (
    "blocker_vertices: the coordinates are too large: their sums overflow the "
    "floating-point range; scale the scene down"
)
ZERO_DIRECTIONAL = (
    "light: zero directional light (x = y = z = 0): a directional light's (x, y, z) "
    "must point toward the light"
)
UP_PARALLEL = (
    "up: the up hint is zero or parallel to the light's viewing direction; pick another up"
)
STABLE_NEEDS_UP = (
    "up: stable=True needs an up hint for a point light, so that its frame cannot jump; "
    "pass up=(x, y, z)"
)
ZERO_SPOT = "light: the spot light's direction is zero; it must point along the axis of its cone"
SPOT_ANGLE = (
    "light: a spot light's angle is the half-angle of its cone and must lie in (0, pi/2) "
    "radians; for a wider light use a point light's cube map"
)
OUTSIDE_CONE = (
    "vertices: the blocker lies outside the spot light's cone (as seen from the light); "
    "nothing of it can shadow what the spot lights"
)
SINGULAR_PLACEMENT = (
    "blocker_to_world: the placement is singular (its determinant is zero to rounding): "
    "it flattens the blocker onto a plane, a line or a point, so no light frame or "
    "silhouette can be fitted to it; give an invertible placement"
)
NEAR_ROUNDING = (
    "light: the nearest caster is within rounding of the light (closer than 32 eps times "
    "the coordinates' magnitude), so the near plane and the frame would be rounding noise; "
    "move the light away from the blocker, or express the coordinates about a nearby origin"
)
#: The widest point-light frustum fitted (full angle, degrees); MAX_FOV_TAN is tan(85 deg).
MAX_FOV_DEGREES = 170.0
MAX_FOV_TAN = 11.430052302761343
TOO_WIDE = (
    "light: the fitted frustum would be wider than 170 degrees (the light is too close to "
    "the blocker, or inside its hull): its texels near the edges would be useless; use a "
    "cube map (cube_face_projection), a spot light's cone (sm.SpotLight), or move the light "
    "away from the blocker"
)
#: A point-light fit wider than this (full angle, degrees) warns (:class:`ShadowFitWarning`):
#: a texel at the map's edge then subtends a quarter of the angle of one at its centre.
WIDE_FOV_DEGREES = 120.0
WIDE_FOV_TAN = 1.7320508075688772
WIDE = (
    "light: the fitted frustum is wider than 120 degrees (up to 170 is fitted): a texel at "
    "the map's edge sees a quarter of the angle of one at its centre or less; a cube map "
    "(cube_face_projection), a spot light's cone or a light farther from the blocker "
    "spends the texels better"
)

#: A split range that starts at or behind the camera with a logarithmic part.
LOG_NEAR = (
    "near: logarithmic splits need near > 0 (use scheme='uniform' for a range that starts "
    "at the camera)"
)
