"""One fit of :func:`fit_shadow` per entry: the single driver of :mod:`._fit_formulas`' steps.

Every step of the fit (aim, frame, sides, receivers, depth range, checks, matrices)
is written here once, and every backend runs this code:

* **per entry** (Numba, or Python floats for one small fit): :func:`._loops.fit_loop`
  calls :func:`fit_entry` for each batch entry with Python/Numba floats;
* **on whole arrays** (NumPy, JAX under ``jit``, ``vmap``, ``grad``):
  :func:`shadowmath._fits.shadow._arrays.fit_arrays` calls it once, and each per-entry
  value is an array of the batch shape.

So the code uses no data-dependent Python branch: a choice between values is the
``where`` primitive, and a failed check sets its status bit through ``flag``
(``0 if ok else bit``, elementwise on arrays); the static options of the record ``o``
(:class:`FitOptions` on arrays; the same fields as a NumPy record for Numba) are
plain branches. The O(N) work over the vertices is the only thing with one form per
backend: the passes ``spread``, ``light_pass``, ``receiver_far`` and ``enclosing_ball``
(loops over the vertices in :mod:`._loops`, reductions over the last axis in
:mod:`shadowmath._fits.shadow._arrays`), both calling the same per-vertex formulas. The
vertex source ``vs`` and the receivers ``R`` are whatever the backend's passes read.
"""

from __future__ import annotations

from typing import NamedTuple, TypeAlias

import numpy as np

from shadowmath._boundary._shapes import ArrayLike, Options, Real, Scalar, Status, Truth, Vertices
from shadowmath._boundary._status import (
    AFFINE_PLACEMENT,
    FORMULA_BITS,
    LIGHT,
    NEAR_ROUNDING,
    OUTSIDE_CONE,
    PLACEMENT,
    RECEIVERS,
    SINGULAR_PLACEMENT,
    SPOT,
    SPOT_ANGLE,
    TOO_WIDE,
    UP,
    WIDE_WARNING,
)

from ._fit_formulas import (
    bounds_about,
    box_sides,
    depth_range,
    directional_origin,
    fit_axes,
    fit_rows,
    fov_ok,
    near_clear,
    placement_affine,
    placement_ok,
    point_sides,
    safe_box,
    spot_angle_ok,
    spot_sides,
    stable_sides,
)
from ._formulas import axes_from_z, fabs, flag, isfinite, maximum, normalize3, where
from ._vertex_passes import enclosing_ball, light_pass, receiver_far, spread


class FitOptions(NamedTuple):
    """The static options of one fit, by name (a NumPy record with these fields for Numba)."""

    directional: bool
    spot: bool
    aim_bbox: bool
    stable: bool
    has_placement: bool
    has_receivers: bool
    has_up: bool
    has_near: bool
    has_far: bool
    triangles: bool  # receiver rows are triangles (9 numbers), not points
    single: bool  # float32 input computed in float64 (per entry): Z is rounded to float32
    margin_x: float
    margin_y: float
    texels_x: float
    texels_y: float
    eps: float
    slack: float


class Entry(NamedTuple):
    """One fit's results (per-entry values): what the drivers store or assemble."""

    status: Status
    origin: tuple[Scalar, ...]  # 3
    axes: tuple[Scalar, ...]  # X, Y, Z: 9
    box: tuple[Scalar, ...]  # half_x, half_y, near, far, x_offset, y_offset
    W: tuple[Scalar, ...]  # 12
    clip: tuple[Scalar, ...]  # 16 (placement not applied)
    tex: tuple[Scalar, ...]  # 16


#: One fit's given numbers: the light (3), a spot light's axis, ``tan`` and angle (5), up
#: (3), the placement (16), the given near and far.
Given: TypeAlias = tuple[
    tuple[Scalar, ...], tuple[Scalar, ...], tuple[Scalar, ...], tuple[Scalar, ...],
    tuple[Scalar, Scalar],
]  # fmt: skip
#: A light placed: status, origin (3), axes (9), sides (half-widths, centre), depths (4).
Placed: TypeAlias = tuple[
    Status, tuple[Scalar, Scalar, Scalar], tuple[Scalar, ...],
    tuple[Scalar, Scalar, Scalar, Scalar], tuple[Scalar, Scalar, Scalar, Scalar],
]  # fmt: skip


# A primitive of the backends (specialize binds each backend's own; this is Python's).
def to_single(x: float) -> float:
    """``x`` rounded to float32 (a per-entry loop computing a float32 fit in float64)."""
    return float(np.float32(x))


def fit_entry(
    given: Given,
    vs: Vertices,
    R: Real[ArrayLike, "... M k"] | None,
    o: Options,
    api: tuple[tuple[float, ...], tuple[float, ...]],
) -> Entry:
    """One entry's fit. ``given = (L, S, U, b, nf)``: the light (3: a position, or a
    direction toward the light), a spot light's axis, ``tan`` and angle (5), up (3),
    the placement (16) and the given near and far; ``vs`` the casters, ``R`` the
    receivers (as the backend's passes read them); ``api = (C, T C)`` rows.
    Returns an :class:`Entry`."""
    nf = given[4]
    if o.directional:
        st, origin, a, sides, z = directional_entry(given, vs, R, o)
    else:
        st, origin, a, sides, z = point_entry(given, vs, R, o)
    st = st | input_checks(given, o)
    n, f, ok = depth_range(z, nf, (o.has_near, o.has_far), o.slack)
    st = st | flags(ok, 5)
    hx, hy, cx, cy = sides
    safe = safe_box((hx, hy, cx, cy, n, f))
    W, clip, tex = fit_rows((origin, a), safe, (o.margin_x, o.margin_y), o.directional, api)
    return Entry(st, origin, a, (hx, hy, n, f, cx, cy), W, clip, tex)


def flags(ok: tuple[Truth, ...], first: int) -> Status:
    """Status bits of the formula checks ``ok`` (starting at ``FORMULA_BITS[first]``)."""
    st = 0
    for j in range(len(ok)):
        st = st | flag(ok[j], FORMULA_BITS[first + j])
    return st


def input_checks(given: Given, o: Options) -> Status:
    """The given numbers' checks: finite light (and spot), up and placement; a placement
    that is invertible beyond rounding."""
    L, S, U, b, _ = given
    st = flag(isfinite(L[0]) & isfinite(L[1]) & isfinite(L[2]), LIGHT)
    if o.spot:
        ok = isfinite(S[0])
        for j in range(1, 5):
            ok = ok & isfinite(S[j])
        st = st | flag(ok, LIGHT)
    if o.has_up:
        st = st | flag(isfinite(U[0]) & isfinite(U[1]) & isfinite(U[2]), UP)
    if o.has_placement:
        ok = isfinite(b[0])
        for j in range(1, 16):
            ok = ok & isfinite(b[j])
        st = st | flag(ok, PLACEMENT) | flag(placement_affine(b, o.eps), AFFINE_PLACEMENT)
        st = st | flag(placement_ok(b, o.eps), SINGULAR_PLACEMENT)
    return st


def point_entry(
    given: Given, vs: Vertices, R: Real[ArrayLike, "... M k"] | None, o: Options
) -> Placed:
    """One point (or spot) light's fit: the article's MDV frame aimed at the casters'
    mean (or box centre), or a spot light's axis with its sides clipped to the cone."""
    L, S, U, _, _ = given
    eps = o.eps
    s, p_lo, p_hi, st, n = spread(vs, L)
    lo, hi, reach, coords = bounds_about(p_lo, p_hi, L)
    if o.spot:
        d = (S[0], S[1], S[2])
        st = st | flag(spot_angle_ok(S[4]), SPOT_ANGLE)
    elif o.aim_bbox:
        d = (0.5 * (hi[0] + lo[0]), 0.5 * (hi[1] + lo[1]), 0.5 * (hi[2] + lo[2]))
    else:
        d = (s[0] / n, s[1] / n, s[2] / n)
    coords = maximum(maximum(coords, fabs(L[0])), maximum(fabs(L[1]), fabs(L[2])))
    a, ok_nonzero, ok_dir, ok_up = fit_axes(d, U, o.has_up, coords, eps)
    if o.spot:
        st = st | flag(ok_nonzero, SPOT) | flags((ok_up,), 2)
    else:
        st = st | flags((ok_dir, ok_up), 1)
    if o.single and not o.has_up:
        # The helper axis is decided on Z as returned (rounded to float32), as a
        # float32 fit on arrays decides it, so the documented rule holds for that frame.
        zx, zy, zz, _ = normalize3(d[0], d[1], d[2])
        zx, zy, zz = to_single(zx), to_single(zy), to_single(zz)
        a = axes_from_z(zx, zy, zz) + (zx, zy, zz)  # noqa: RUF005 (Numba: tuple concatenation)
    bounds = light_pass(vs, L, a, True)
    hx, lx, hy, ly, zb_max, zb_min = bounds
    if o.spot:
        half_x, half_y, cx, cy, ok_behind, ok_cone, ok_sil = spot_sides(
            (hx, lx, hy, ly), S[3], zb_min, reach, eps
        )
        st = st | flag(ok_cone, OUTSIDE_CONE)
    else:
        half_x, half_y, ok_behind, ok_sil = point_sides((hx, lx, hy, ly), zb_min, reach, eps)
        cx = cy = 0.0 * half_x
    st = st | flags((ok_behind, ok_sil), 3) | flag(near_clear(zb_min, coords, eps), NEAR_ROUNDING)
    ok_fov, calm = fov_ok((half_x, half_y, cx, cy), (o.margin_x, o.margin_y))
    # (Not an error: the boundary warns, unless a failed check raises first.)
    st = st | flag(ok_fov, TOO_WIDE) | flag(calm, WIDE_WARNING)
    z_hi, bits, link = receivers_far(R, (L, a), (half_x, half_y, cx, cy), zb_max, o)
    st = st | bits
    return (
        st,
        (L[0], L[1], L[2]),
        a,
        (half_x, half_y, cx + link, cy),
        (zb_min, z_hi, zb_min, zb_max),
    )


def directional_entry(
    given: Given, vs: Vertices, R: Real[ArrayLike, "... M k"] | None, o: Options
) -> Placed:
    """One directional light's fit: the casters' box (or, ``stable``, their minimal
    enclosing sphere snapped to whole texels) across the light's direction."""
    L, _, U, _, _ = given
    eps = o.eps
    zero = 0.0 * L[0]
    _, lo, hi, st, _ = spread(vs, (zero, zero, zero))  # the world points' bounds
    coords = bounds_about(lo, hi, (zero, zero, zero))[3]
    a, ok_light, _, ok_up = fit_axes((-L[0], -L[1], -L[2]), U, o.has_up, coords, eps)
    st = st | flags((ok_light,), 0) | flags((ok_up,), 2)
    if o.stable:  # the minimal enclosing sphere: the shape's, whatever its vertices
        sphere = enclosing_ball(vs)
        c = (sphere[0], sphere[1], sphere[2])
    else:
        sphere = (zero, zero, zero, zero)
        c = (0.5 * (hi[0] + lo[0]), 0.5 * (hi[1] + lo[1]), 0.5 * (hi[2] + lo[2]))
    bounds = light_pass(vs, c, a, False)
    reach = bounds_about(lo, hi, c)[2]  # max |p - c|
    hx, lx, hy, ly, zb_max, zb_min = bounds
    if o.stable:
        texels4 = (o.margin_x, o.margin_y, o.texels_x, o.texels_y)
        half_x, half_y, cx, cy, ok_sil = stable_sides((c, sphere[3]), a, texels4, reach, eps)
    else:
        half_x, half_y, cx, cy, ok_sil = box_sides((hx, lx, hy, ly), reach, eps)
    st = st | flags((ok_sil,), 4)
    z_hi, bits, link = receivers_far(R, (c, a), (half_x, half_y, cx, cy), zb_max, o)
    st = st | bits
    ox, oy, oz, shift = directional_origin((zb_min, z_hi), (half_x, half_y), c, a)
    z = (zb_min - shift, z_hi - shift, zb_min - shift, zb_max - shift)
    return st, (ox, oy, oz), a, (half_x, half_y, cx + link, cy), z


def receivers_far(
    R: Real[ArrayLike, "... M k"] | None,
    frame: tuple[tuple[Scalar, ...], tuple[Scalar, ...]],
    sides: tuple[Scalar, Scalar, Scalar, Scalar],
    z_hi: Scalar,
    o: Options,
) -> tuple[Scalar, Status, Scalar]:
    """``far`` widened over the receivers inside the map's sides (``frame``: the
    frame's origin and axes), the receivers' check bit, and a link.

    Receivers never move ``near``: one nearer than every caster cannot be shadowed.
    ``link``: 0, or under JAX NaN where a receiver is not finite. A non-finite receiver
    is only counted out (a ``where``), which would give it a zero derivative; the
    entries add the link to the map's x offset (which no ``where`` guards), so that
    the matrices and their derivatives are NaN there.
    """
    if not o.has_receivers:
        return z_hi, 0, 0.0
    origin, a = frame
    half_x, half_y, cx, cy = sides
    s = (o.margin_x / where(half_x > 0, half_x, 1.0), o.margin_y / where(half_y > 0, half_y, 1.0))
    far, ok, link = receiver_far(R, origin, a, (s[0], s[1], cx, cy), o)
    return where(far > z_hi, far, z_hi), flag(ok, RECEIVERS), link


FUNCTIONS = (
    "fit_entry",
    "flags",
    "input_checks",
    "point_entry",
    "directional_entry",
    "receivers_far",
)
