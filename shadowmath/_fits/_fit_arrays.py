"""The fits on whole arrays (NumPy or JAX): the drivers of :mod:`._fit_formulas`' steps.

One driver for both kinds of light; the kind is static (``key.directional``), so
only its fit is traced or run. Each pass is one expression over ``(*batch, N)``
component arrays (under ``jax.jit`` XLA fuses it into one loop over the vertices);
the per-entry steps are the formulas shared with the compiled loops of
:mod:`._loops`. Every check is computed with safe divisors and handed to
``Checks`` in the order of :data:`._status.FIT_CHECKS`, so the first failure is
reported with the same message as the compiled loop's.
"""

from __future__ import annotations

import math
from types import ModuleType, SimpleNamespace
from typing import Any, NamedTuple

import numpy as np

from shadowmath._backends import _kernels
from shadowmath._boundary import _messages as msg
from shadowmath._boundary._status import FIT_CHECKS, FORMULA_CHECKS
from shadowmath._boundary._validate import Array, Checks, Context, all_finite
from shadowmath._math._frustum import NEAR_FAR_SLACK
from shadowmath._math._specialize import formulas, scalar_formulas

from ._spec import FitKey

Components = tuple[Array, Array, Array]


class FitEntries(NamedTuple):
    """A fit's per-entry results, as component arrays of the batch shape (or scalars)."""

    origin: tuple[Array, ...]  # 3
    axes: tuple[Array, ...]  # X, Y, Z: 9
    box: tuple[Array, ...]  # half_x, half_y, near, far, x_offset, y_offset
    W: tuple[Array, ...]  # 12
    clip: tuple[Array, ...]  # 16 (placement not applied)
    tex: tuple[Array, ...]  # 16


class Inputs(NamedTuple):
    """The trusted arrays of one fit (``None`` where not given)."""

    light: Array  # (*batch, 3): a position or a direction toward the light
    verts: Array  # (*batch, N, 3)
    B: Array | None
    R: Array | None
    U: Array | None
    near: Array | None
    far: Array | None


class Driver(NamedTuple):
    """How one call runs the steps: its namespace, and its formulas per vertex and per entry.

    On whole arrays both are ``formulas(xp)`` and per-entry values are ``(*batch,)``
    arrays (``expand`` broadcasts them against ``(*batch, N)``). For one NumPy
    entry (batch shape ``()``) the per-entry steps run on Python floats
    (``scalar_formulas()``), which costs microseconds instead of the 0-d array
    overhead of hundreds of NumPy calls; the vertex passes stay NumPy.
    """

    xp: ModuleType
    Fv: SimpleNamespace  # per-vertex formulas (whole arrays)
    Fe: SimpleNamespace  # per-entry formulas
    eps: float
    scalar: bool

    def entry(self, v: Array) -> Array:
        """A reduction's result as a per-entry value."""
        return float(v) if self.scalar else v

    def expand(self, values: tuple[Array, ...]) -> tuple[Array, ...]:
        """Per-entry values broadcast against ``(*batch, N)`` vertex components."""
        return values if self.scalar else tuple(v[..., None] for v in values)

    def bounds(self, x: Array) -> tuple[Array, Array]:
        return self.entry(self.xp.max(x, axis=-1)), self.entry(self.xp.min(x, axis=-1))

    def sums(self, c: Components) -> tuple[Array, ...]:
        return tuple(self.entry(self.xp.sum(v, axis=-1)) for v in c)

    def max_abs(self, *vs: Array) -> Array:
        xp = self.xp
        out = xp.max(xp.abs(vs[0]), axis=-1)
        for v in vs[1:]:
            out = xp.maximum(out, xp.max(xp.abs(v), axis=-1))
        return self.entry(out)


def driver(ctx: Context, scalar: bool) -> Driver:
    """The driver of one call; ``scalar`` for one NumPy entry."""
    F = formulas(ctx.xp)
    return Driver(ctx.xp, F, scalar_formulas() if scalar else F, ctx.eps, scalar)


def fit_arrays(ctx: Context, checks: Checks, key: FitKey, a: Inputs, d: Driver) -> FitEntries:
    """The fit of ``key`` on shape-checked arrays; every value check goes to ``checks``."""
    xp = ctx.xp
    flags: dict[str, Array] = {
        "light": all_finite(xp, a.light, 1),
        "vertices": all_finite(xp, a.verts, 2),
    }
    if a.B is not None:
        flags["placement"] = all_finite(xp, a.B, 2)
        b = tuple(a.B[..., i // 4, i % 4] for i in range(16))
        flags["singular_placement"] = d.Fv.placement_ok(b, d.eps)
    if a.R is not None:
        flags["receivers"] = all_finite(xp, a.R, 2)
    if a.U is not None:
        flags["up"] = all_finite(xp, a.U, 1)
    world = _world(d, a.verts, a.B, flags)
    fit = _directional if key.directional else _point
    entries = fit(d, key, a, world, flags)
    for name, _ in FIT_CHECKS:  # in report order
        ok = flags.get(name, True)
        if ok is not True:
            checks.require(ok, _MESSAGES[name])
    calm = flags.get("wide_warning", True)
    if xp is np and calm is not True and not np.all(calm):  # (JAX: no warnings)
        msg.warn_wide()
    return entries


_MESSAGES = dict(FIT_CHECKS)


def _world(d: Driver, verts: Array, B: Array | None, flags: dict[str, Array]) -> Components:
    """The vertices' world components, through the placement (checked: ``w > 0``)."""
    px, py, pz = verts[..., 0], verts[..., 1], verts[..., 2]
    if B is None:
        return px, py, pz
    b = tuple(B[..., None, i // 4, i % 4] for i in range(16))
    x, y, z, w = d.Fv.place(b, px, py, pz)
    flags["projective"] = d.xp.all(w > 0, axis=-1)
    return x, y, z


def _components(d: Driver, v: Array | None) -> Components:
    if v is None:
        return 0.0, 0.0, 0.0
    return d.entry(v[..., 0]), d.entry(v[..., 1]), d.entry(v[..., 2])


def _finite3(d: Driver, s: tuple[Array, ...]) -> Array:
    return d.Fe.isfinite(s[0]) & d.Fe.isfinite(s[1]) & d.Fe.isfinite(s[2])


def _point(
    d: Driver, key: FitKey, a: Inputs, world: Components, flags: dict[str, Array]
) -> FitEntries:
    """The article's MDV fit of a point light (with or without ``up``), on whole arrays;
    a spot light aims along its axis instead and clips the sides to its cone."""
    xp, eps = d.xp, d.eps
    L = _components(d, a.light)
    o = tuple(p - lc for p, lc in zip(world, d.expand(L), strict=True))
    sums = d.sums(o)
    if key.spot:
        aim = tuple(d.entry(a.light[..., i]) for i in (3, 4, 5))
        angle = d.entry(a.light[..., 7])
        flags["spot_angle"] = d.Fe.spot_angle_ok(angle)
    elif key.aim_bbox:
        aim = tuple(0.5 * (hi + lo) for hi, lo in (d.bounds(c) for c in o))
    else:
        aim = tuple(s / o[0].shape[-1] for s in sums)
    flags["overflow"] = _finite3(d, sums)
    reach = d.max_abs(*o)
    # The position only: a spot light packs its direction and tan(angle) after it.
    coords = xp.maximum(d.max_abs(*world), d.max_abs(a.light[..., :3]))
    axes, ok_nonzero, ok_direction, flags["up_parallel"] = d.Fe.fit_axes(
        aim, _components(d, a.U), key.has_up, coords, eps
    )
    flags["spot" if key.spot else "direction"] = ok_nonzero if key.spot else ok_direction
    x, y, z = d.Fv.to_light(*o, d.expand(axes))
    # One reciprocal per vertex, as the compiled loop and adaptive_frustum's pass compute it.
    inv_z = 1 / xp.where(z > 0, z, xp.ones_like(z))
    (hi_x, lo_x), (hi_y, lo_y) = d.bounds(x * inv_z), d.bounds(y * inv_z)
    zb_max, zb_min = d.bounds(z)
    if key.spot:
        t = d.entry(a.light[..., 6])
        *sides, flags["behind"], flags["outside_cone"], flags["silhouette"] = d.Fe.spot_sides(
            (hi_x, lo_x, hi_y, lo_y), t, zb_min, reach, eps
        )
        sides = tuple(sides)
    else:
        half_x, half_y, flags["behind"], flags["silhouette"] = d.Fe.point_sides(
            hi_x, lo_x, hi_y, lo_y, zb_min, reach, eps
        )
        zero = 0.0 * half_x
        sides = (half_x, half_y, zero, zero)
    flags["near_rounding"] = d.Fe.near_clear(zb_min, coords, eps)
    flags["too_wide"], flags["wide_warning"] = d.Fe.fov_ok(sides, key.margins)
    z_hi = _receivers(d, key, a, L, axes, sides, zb_max)
    return _finish(d, key, a, flags, L, axes, sides, (zb_min, z_hi, zb_min, zb_max))


def _directional(
    d: Driver, key: FitKey, a: Inputs, world: Components, flags: dict[str, Array]
) -> FitEntries:
    """The orthographic fit of a directional light (box or stable), on whole arrays."""
    eps = d.eps
    toward = tuple(-c for c in _components(d, a.light))
    coords = d.max_abs(*world)
    axes, flags["zero_light"], _, flags["up_parallel"] = d.Fe.fit_axes(
        toward, _components(d, a.U), key.has_up, coords, eps
    )
    sums = d.sums(world)
    flags["overflow"] = _finite3(d, sums)
    if key.stable:  # the minimal enclosing sphere: the shape's, whatever its vertices
        cx, cy, cz, r2 = _enclosing_sphere(d, world)
        c = (cx, cy, cz)
    else:
        c = tuple(0.5 * (hi + lo) for hi, lo in (d.bounds(p) for p in world))
    o = tuple(p - cc for p, cc in zip(world, d.expand(c), strict=True))
    reach = d.max_abs(*o)
    x, y, z = d.Fv.to_light(*o, d.expand(axes))
    zb_max, zb_min = d.bounds(z)
    if key.stable:
        texels = (*key.margins, *key.texels)
        *sides, flags["silhouette"] = d.Fe.stable_sides(r2, c, axes, texels, reach, eps)
    else:
        *sides, flags["silhouette"] = d.Fe.box_sides(*d.bounds(x), *d.bounds(y), reach, eps)
    z_hi = _receivers(d, key, a, c, axes, tuple(sides), zb_max)
    *origin, shift = d.Fe.directional_origin(zb_min, z_hi, sides[0], sides[1], c, axes)
    z = (zb_min - shift, z_hi - shift, zb_min - shift, zb_max - shift)
    return _finish(d, key, a, flags, tuple(origin), axes, tuple(sides), z)


def _enclosing_sphere(d: Driver, world: Components) -> tuple[Array, Array, Array, Array]:
    """The vertices' minimal enclosing sphere: centre (3) and ``r^2``, per entry.

    Its support points (2 to 4 vertices) come from Welzl's algorithm on the host
    (:func:`._kernels.sphere_support`; under JAX through ``pure_callback``: they are
    piecewise constant), the sphere from :func:`sphere_through` on them, so values
    and derivatives follow the support points.
    """
    xp = d.xp
    points = xp.stack(world, axis=-1)
    if xp is np:
        support = _kernels.sphere_support(points)
    else:
        import jax

        shape = jax.ShapeDtypeStruct((*points.shape[:-2], 5), np.int32)  # type: ignore[no-untyped-call]
        support = jax.pure_callback(
            _kernels.sphere_support, shape, jax.lax.stop_gradient(points), vmap_method="expand_dims"
        )
    q = tuple(
        xp.take_along_axis(w, support[..., j : j + 1], axis=-1)[..., 0]
        for j in range(4)
        for w in world
    )
    k = support[..., 4]
    if d.scalar:
        q, k = tuple(float(v) for v in q), int(k)
    cx, cy, cz, r2 = d.Fe.sphere_through(q, k)
    return cx, cy, cz, r2


def _receivers(
    d: Driver,
    key: FitKey,
    a: Inputs,
    origin: tuple[Array, ...],
    axes: tuple[Array, ...],
    sides: tuple[Array, ...],
    z_hi: Array,
) -> Array:
    """The far end widened over the receivers (points or triangles) inside the map's sides.

    Receivers never move ``near``: one nearer than every caster cannot be shadowed.
    """
    if a.R is None:
        return z_hi
    xp = d.xp
    half_x, half_y, cx, cy = sides
    safe_hx = d.Fe.where(half_x > 0, half_x, 1.0)
    safe_hy = d.Fe.where(half_y > 0, half_y, 1.0)
    s = d.expand((key.margins[0] / safe_hx, key.margins[1] / safe_hy, cx, cy))
    o, ax = d.expand(origin), d.expand(axes)
    corners = []
    for j in range(0, a.R.shape[-1], 3):  # one point, or a triangle's three corners
        r = (a.R[..., j] - o[0], a.R[..., j + 1] - o[1], a.R[..., j + 2] - o[2])
        corners.extend(d.Fv.to_light(*r, ax))
    if key.triangles:
        z = d.Fv.triangle_far(tuple(corners), s, key.directional, d.eps)
    else:
        counted = d.Fv.receiver_counted(*corners, s, key.directional)
        z = d.Fv.where(counted, corners[2], -math.inf)
    far = d.entry(xp.max(z, axis=-1))
    return d.Fe.where(far > z_hi, far, z_hi)


def _components_of(v: Array) -> tuple[Array, ...]:
    return tuple(v[..., j] for j in range(v.shape[-1]))


def _finish(
    d: Driver,
    key: FitKey,
    a: Inputs,
    flags: dict[str, Any],
    origin: tuple[Array, ...],
    axes: tuple[Array, ...],
    sides: tuple[Array, ...],
    z: tuple[Array, Array, Array, Array],
) -> FitEntries:
    """The depth range and its checks, then the matrices from safe values."""
    given = tuple(None if v is None else d.entry(v) for v in (a.near, a.far))
    F = d.Fe
    near, far, ok = F.depth_range(z, given, (key.has_near, key.has_far), NEAR_FAR_SLACK)
    flags.update(zip(FORMULA_CHECKS[5:], ok, strict=True))
    half_x, half_y, cx, cy = sides
    if a.R is not None and d.xp is not np:
        # A non-finite receiver is only counted out (a where), which would give it a zero
        # derivative: link it into the matrices by 0 * its non-finite entries (NaN exactly
        # there, 0 elsewhere), so that its derivative is NaN too. JAX only: NumPy raises.
        xp = d.xp
        link = sum(xp.sum(xp.where(xp.isfinite(c), 0.0, c), axis=-1) for c in _components_of(a.R))
        cx = cx + 0.0 * link
    safe = F.safe_box(half_x, half_y, cx, cy, near, far)
    W, clip, tex = F.fit_rows(origin, axes, safe, key.margins, key.directional, key.api)
    return FitEntries(origin, axes, (half_x, half_y, near, far, cx, cy), W, clip, tex)
