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

from types import ModuleType, SimpleNamespace
from typing import Any, NamedTuple

from ._frustum import NEAR_FAR_SLACK
from ._spec import FitKey
from ._specialize import formulas
from ._status import FIT_CHECKS, FORMULA_CHECKS
from ._validate import Array, Checks, Context, all_finite

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


def fit_arrays(ctx: Context, checks: Checks, key: FitKey, a: Inputs) -> FitEntries:
    """The fit of ``key`` on shape-checked arrays; every value check goes to ``checks``."""
    xp = ctx.xp
    F = formulas(xp)
    flags: dict[str, Array] = {
        "light": all_finite(xp, a.light, 1),
        "vertices": all_finite(xp, a.verts, 2),
    }
    if a.B is not None:
        flags["placement"] = all_finite(xp, a.B, 2)
    if a.R is not None:
        flags["receivers"] = all_finite(xp, a.R, 2)
    if a.U is not None:
        flags["up"] = all_finite(xp, a.U, 1)
    world = _world(xp, F, a.verts, a.B, flags)
    fit = _directional if key.directional else _point
    entries = fit(ctx, F, key, a, world, flags)
    for name, _ in FIT_CHECKS:  # in report order
        ok = flags.get(name, True)
        if ok is not True:
            checks.require(ok, _MESSAGES[name])
    return entries


_MESSAGES = dict(FIT_CHECKS)


def _world(
    xp: ModuleType, F: SimpleNamespace, verts: Array, B: Array | None, flags: dict[str, Array]
) -> Components:
    """The vertices' world components, through the placement (checked: ``w > 0``)."""
    px, py, pz = verts[..., 0], verts[..., 1], verts[..., 2]
    if B is None:
        return px, py, pz
    b = tuple(B[..., None, i // 4, i % 4] for i in range(16))
    x, y, z, w = F.place(b, px, py, pz)
    flags["projective"] = xp.all(w > 0, axis=-1)
    return x, y, z


def _components(v: Array | None) -> Components:
    if v is None:
        return 0.0, 0.0, 0.0
    return v[..., 0], v[..., 1], v[..., 2]


def _expand(values: tuple[Array, ...]) -> tuple[Array, ...]:
    """Per-entry components broadcast against ``(*batch, N)`` vertex components."""
    return tuple(v[..., None] for v in values)


def _finite3(xp: ModuleType, s: tuple[Array, ...]) -> Array:
    return xp.isfinite(s[0]) & xp.isfinite(s[1]) & xp.isfinite(s[2])


def _bounds(xp: ModuleType, x: Array) -> tuple[Array, Array]:
    return xp.max(x, axis=-1), xp.min(x, axis=-1)


def _max_abs(xp: ModuleType, *vs: Array) -> Array:
    out = xp.max(xp.abs(vs[0]), axis=-1)
    for v in vs[1:]:
        out = xp.maximum(out, xp.max(xp.abs(v), axis=-1))
    return out


def _point(
    ctx: Context,
    F: SimpleNamespace,
    key: FitKey,
    a: Inputs,
    world: Components,
    flags: dict[str, Array],
) -> FitEntries:
    """The article's MDV fit of a point light (with or without ``up``), on whole arrays."""
    xp, eps = ctx.xp, ctx.eps
    L = _components(a.light)
    o = tuple(p - lc[..., None] for p, lc in zip(world, L, strict=True))
    sums = tuple(xp.sum(c, axis=-1) for c in o)
    if key.aim_bbox:
        d = tuple(0.5 * (hi + lo) for hi, lo in (_bounds(xp, c) for c in o))
    else:
        d = tuple(s / o[0].shape[-1] for s in sums)
    flags["overflow"] = _finite3(xp, sums)
    reach = _max_abs(xp, *o)
    coords = xp.maximum(_max_abs(xp, *world), _max_abs(xp, a.light))
    axes, _, flags["direction"], flags["up_parallel"] = F.fit_axes(
        d, _components(a.U), key.has_up, coords, eps
    )
    x, y, z = F.to_light(*o, _expand(axes))
    safe_z = xp.where(z > 0, z, xp.ones_like(z))
    (hi_x, lo_x), (hi_y, lo_y) = _bounds(xp, x / safe_z), _bounds(xp, y / safe_z)
    zb_max, zb_min = _bounds(xp, z)
    half_x, half_y, flags["behind"], flags["silhouette"] = F.point_sides(
        hi_x, lo_x, hi_y, lo_y, zb_min, reach, eps
    )
    zero = 0.0 * half_x
    sides = (half_x, half_y, zero, zero)
    z_lo, z_hi = _receivers(xp, F, key, a, L, axes, sides, (zb_min, zb_max))
    return _finish(F, key, a, flags, L, axes, sides, (z_lo, z_hi, zb_min, zb_max))


def _directional(
    ctx: Context,
    F: SimpleNamespace,
    key: FitKey,
    a: Inputs,
    world: Components,
    flags: dict[str, Array],
) -> FitEntries:
    """The orthographic fit of a directional light (box or stable), on whole arrays."""
    xp, eps = ctx.xp, ctx.eps
    d = tuple(-c for c in _components(a.light))
    coords = _max_abs(xp, *world)
    axes, flags["zero_light"], _, flags["up_parallel"] = F.fit_axes(
        d, _components(a.U), key.has_up, coords, eps
    )
    sums = tuple(xp.sum(c, axis=-1) for c in world)
    flags["overflow"] = _finite3(xp, sums)
    if key.stable:  # the bounding sphere about the mean turns with the blocker
        c = tuple(s / world[0].shape[-1] for s in sums)
    else:
        c = tuple(0.5 * (hi + lo) for hi, lo in (_bounds(xp, p) for p in world))
    o = tuple(p - cc[..., None] for p, cc in zip(world, c, strict=True))
    reach = _max_abs(xp, *o)
    x, y, z = F.to_light(*o, _expand(axes))
    zb_max, zb_min = _bounds(xp, z)
    if key.stable:
        r2 = xp.max(x * x + y * y + z * z, axis=-1)
        texels = (*key.margins, *key.texels)
        *sides, flags["silhouette"] = F.stable_sides(r2, c, axes, texels, reach, eps)
    else:
        *sides, flags["silhouette"] = F.box_sides(*_bounds(xp, x), *_bounds(xp, y), reach, eps)
    z_lo, z_hi = _receivers(xp, F, key, a, c, axes, tuple(sides), (zb_min, zb_max))
    *origin, shift = F.directional_origin(z_lo, z_hi, sides[0], sides[1], c, axes)
    z = (z_lo - shift, z_hi - shift, zb_min - shift, zb_max - shift)
    return _finish(F, key, a, flags, tuple(origin), axes, tuple(sides), z)


def _receivers(
    xp: ModuleType,
    F: SimpleNamespace,
    key: FitKey,
    a: Inputs,
    origin: tuple[Array, ...],
    axes: tuple[Array, ...],
    sides: tuple[Array, ...],
    zb: tuple[Array, Array],
) -> tuple[Array, Array]:
    """The depth range widened over the receiver points inside the map's sides."""
    if a.R is None:
        return zb
    o = tuple(r - oc[..., None] for r, oc in zip(_components(a.R), origin, strict=True))
    x, y, z = F.to_light(*o, _expand(axes))
    half_x, half_y, cx, cy = sides
    safe_hx = xp.where(half_x > 0, half_x, xp.ones_like(half_x))
    safe_hy = xp.where(half_y > 0, half_y, xp.ones_like(half_y))
    s = _expand((key.margins[0] / safe_hx, key.margins[1] / safe_hy, cx, cy))
    counted = F.receiver_counted(x, y, z, s, key.directional)
    z_lo = xp.minimum(zb[0], xp.min(xp.where(counted, z, zb[0][..., None]), axis=-1))
    z_hi = xp.maximum(zb[1], xp.max(xp.where(counted, z, zb[1][..., None]), axis=-1))
    return z_lo, z_hi


def _finish(
    F: SimpleNamespace,
    key: FitKey,
    a: Inputs,
    flags: dict[str, Any],
    origin: tuple[Array, ...],
    axes: tuple[Array, ...],
    sides: tuple[Array, ...],
    z: tuple[Array, Array, Array, Array],
) -> FitEntries:
    """The depth range and its checks, then the matrices from safe values."""
    near, far, ok = F.depth_range(z, (a.near, a.far), (key.has_near, key.has_far), NEAR_FAR_SLACK)
    flags.update(zip(FORMULA_CHECKS[5:], ok, strict=True))
    half_x, half_y, cx, cy = sides
    safe = F.safe_box(half_x, half_y, cx, cy, near, far)
    W, clip, tex = F.fit_rows(origin, axes, safe, key.margins, key.directional, key.api)
    return FitEntries(origin, axes, (half_x, half_y, near, far, cx, cy), W, clip, tex)
