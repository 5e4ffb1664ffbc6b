"""One table of the fits' value checks: their order, their status bits and their messages.

A fit's per-entry formulas (:mod:`shadowmath._math._fit_formulas`) return their checks as booleans
(True: valid). The array path hands each to ``Checks.require`` with its message
from this table; the compiled loops set the check's bit in a status word, and the
boundary raises the message of the first failing bit, in the same order. The bit
of a check is ``1 << index`` in :data:`FIT_CHECKS`, so order, bit and message can
never disagree.
"""

from __future__ import annotations

from . import _messages as msg
from ._validate import non_finite

#: The fits' checks in the order their failures are reported.
FIT_CHECKS: tuple[tuple[str, str], ...] = (
    ("light", non_finite("light")),
    ("vertices", non_finite("blocker_vertices")),
    ("placement", non_finite("blocker_to_world")),
    ("receivers", non_finite("receivers")),
    ("up", non_finite("up")),
    ("affine_placement", msg.AFFINE_PLACEMENT),
    ("projective", msg.PROJECTIVE_PLACEMENT),
    ("singular_placement", msg.SINGULAR_PLACEMENT),
    ("zero_light", msg.ZERO_DIRECTIONAL),
    ("spot", msg.ZERO_SPOT),
    ("spot_angle", msg.SPOT_ANGLE),
    ("direction", msg.ZERO_DIRECTION),
    ("up_parallel", msg.UP_PARALLEL),
    ("behind", msg.BEHIND_LIGHT),
    ("near_rounding", msg.NEAR_ROUNDING),
    ("outside_cone", msg.OUTSIDE_CONE),
    ("silhouette", msg.ZERO_SILHOUETTE),
    ("too_wide", msg.TOO_WIDE),
    ("near_finite", msg.NEAR_NOT_FINITE),
    ("far_finite", msg.FAR_NOT_FINITE),
    ("near_positive", msg.NEAR_POSITIVE),
    ("near_far", msg.NEAR_FAR),
    ("near_clips", msg.NEAR_CLIPS),
    ("far_clips", msg.FAR_CLIPS),
    ("overflow", msg.OVERFLOW),
)

_INDEX = {name: i for i, (name, _) in enumerate(FIT_CHECKS)}


def bit(name: str) -> int:
    """The status bit of the check ``name``."""
    return 1 << _INDEX[name]


# Bits used by the compiled loops (module constants: Numba freezes them at compile time).
LIGHT = bit("light")
VERTICES = bit("vertices")
PLACEMENT = bit("placement")
AFFINE_PLACEMENT = bit("affine_placement")
RECEIVERS = bit("receivers")
UP = bit("up")
PROJECTIVE = bit("projective")
OVERFLOW = bit("overflow")
SPOT = bit("spot")
SPOT_ANGLE = bit("spot_angle")
OUTSIDE_CONE = bit("outside_cone")
SINGULAR_PLACEMENT = bit("singular_placement")
NEAR_ROUNDING = bit("near_rounding")
TOO_WIDE = bit("too_wide")
#: Not an error: a point-light fit wider than ``msg.WIDE_FOV_DEGREES`` (the boundary warns).
WIDE_WARNING = 1 << 30

#: The order of the checks that the per-entry formulas return as a tuple of booleans.
FORMULA_CHECKS = (
    "zero_light",
    "direction",
    "up_parallel",
    "behind",
    "silhouette",
    "near_finite",
    "far_finite",
    "near_positive",
    "near_far",
    "near_clips",
    "far_clips",
)
FORMULA_BITS = tuple(bit(name) for name in FORMULA_CHECKS)


def fit_messages(vertices_finite: bool) -> tuple[tuple[int, str], ...]:
    """``(bit, message)`` in report order; a non-finite sum of finite vertices is an overflow."""
    out = []
    for i, (name, message) in enumerate(FIT_CHECKS):
        if name == "vertices" and vertices_finite:
            message = msg.OVERFLOW
        out.append((1 << i, message))
    return tuple(out)


# planar_projection's loop: its own five checks, in order.
PLANAR_NONFINITE_PLANE = 1
PLANAR_NONFINITE_LIGHT = 2
PLANAR_ZERO_NORMAL = 4
PLANAR_ZERO_LIGHT = 8
PLANAR_IN_PLANE = 16


#: fit_cascades' checks in the order their failures are reported (bit ``1 << index``):
#: the per-entry steps (:mod:`shadowmath._math._cascade_steps`) set them in a status word
#: with ``flag``; the boundary raises the first failing one's message (NumPy) or hands
#: each to ``Checks.require`` (JAX: NaN outputs).
CASCADE_CHECKS: tuple[tuple[str, str], ...] = (
    ("light_finite", non_finite("light")),
    ("view_finite", non_finite("view")),
    ("projection_finite", non_finite("projection")),
    ("bounds_finite", non_finite("scene_bounds")),
    ("up_finite", non_finite("up")),
    ("view_affine", "view: expected an affine world-to-view matrix (last row 0, 0, 0, 1)"),
    ("view_singular", "view: singular (its 3x3 part has no inverse)"),
    ("projection_singular", "projection: singular (no inverse)"),
    ("infinite_far", "projection: an infinite far plane needs a perspective camera (near > 0)"),
    ("bounds_order", "scene_bounds: the max corner must be >= the min corner on every axis"),
    ("light_zero", "light: zero direction (x = y = z = 0): a directional light points toward "
     "the light"),
    ("up_parallel", msg.UP_PARALLEL),
    ("far_infinite", "max_distance: the projection's far plane is at infinity; give the "
     "shadow distance as max_distance"),
    ("max_distance", "max_distance: the shadow distance must lie beyond the camera's near "
     "plane and no farther than its far plane"),
    ("log_near", msg.LOG_NEAR),
    ("splits_increase", "splits: the depths must increase"),
    ("splits_range", "splits: the depths must lie within the camera's [near, far] view depths"),
)  # fmt: skip

_CASCADE_INDEX = {name: i for i, (name, _) in enumerate(CASCADE_CHECKS)}


def cascade_bit(name: str) -> int:
    """The status bit of fit_cascades' check ``name``."""
    return 1 << _CASCADE_INDEX[name]


# Bits of fit_cascades' checks (module constants: Numba freezes them at compile time).
C_LIGHT_FINITE = cascade_bit("light_finite")
C_VIEW_FINITE = cascade_bit("view_finite")
C_PROJECTION_FINITE = cascade_bit("projection_finite")
C_BOUNDS_FINITE = cascade_bit("bounds_finite")
C_UP_FINITE = cascade_bit("up_finite")
C_VIEW_AFFINE = cascade_bit("view_affine")
C_VIEW_SINGULAR = cascade_bit("view_singular")
C_PROJECTION_SINGULAR = cascade_bit("projection_singular")
C_INFINITE_FAR = cascade_bit("infinite_far")
C_BOUNDS_ORDER = cascade_bit("bounds_order")
C_LIGHT_ZERO = cascade_bit("light_zero")
C_UP_PARALLEL = cascade_bit("up_parallel")
C_FAR_INFINITE = cascade_bit("far_infinite")
C_MAX_DISTANCE = cascade_bit("max_distance")
C_LOG_NEAR = cascade_bit("log_near")
C_SPLITS_INCREASE = cascade_bit("splits_increase")
C_SPLITS_RANGE = cascade_bit("splits_range")


def cascade_messages() -> tuple[tuple[int, str], ...]:
    """``(bit, message)`` of fit_cascades' checks, in report order."""
    return tuple((1 << i, message) for i, (_, message) in enumerate(CASCADE_CHECKS))
