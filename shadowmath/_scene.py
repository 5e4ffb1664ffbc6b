"""The array path of :func:`fit_shadow`'s scene options: homogeneous and directional
lights, receivers, graphics APIs, an ``up`` hint and stable maps.

One core on trusted arrays (NumPy or JAX, whole arrays), called by the boundary
in :mod:`._setup` after it converted and shape-checked everything. Whether a
homogeneous light is directional (``w == 0``) is a *value*, not static under
``jax.jit``, so both fits are computed for every entry and selected with
``where``: the frame's ``Z`` (``-xyz`` or the blocker's direction from the
point), the frustum's coordinates (``x`` or ``x / z``), its bounds and origin.
Every unselected branch is kept finite (safe divisors), so neither its values
nor its derivatives leak NaN into the selected one.
"""

from __future__ import annotations

from types import ModuleType
from typing import NamedTuple

from . import _messages as msg
from ._conventions import _clip_from_gl, _texture_from_gl_clip
from ._formulas import formulas
from ._frame import LightFrame, light_entries
from ._frustum import NEAR_FAR_SLACK, Frustum, projection_entries
from ._validate import Array, Checks, Context, all_finite, non_finite

Matrix = tuple[Array, ...]


class SceneOptions(NamedTuple):
    """The static options of the scene path (one cached jit per set)."""

    api: str
    reversed_z: bool
    stable: bool
    homogeneous: bool  # the light is (*batch, 4)
    texels: tuple[int, int]  # (width, height) of the map, for stable snapping


ZERO_DIRECTIONAL = (
    "light_position: zero directional light (w = 0 and x = y = z = 0): a directional "
    "light's (x, y, z) must point toward the light"
)
UP_PARALLEL = (
    "up: the up hint is zero or parallel to the light's viewing direction; pick another up"
)
STABLE_NEEDS_UP = (
    "up: stable=True needs an up hint for a point light (w != 0), so that its frame "
    "cannot jump; pass up=(x, y, z)"
)


def _const_times(xp: ModuleType, C: tuple[tuple[float, ...], ...], m: Matrix) -> Matrix:
    """``C @ m`` for a constant ``C`` (exact floats) and 16 row-major entries ``m``."""
    out = []
    for i in range(4):
        for j in range(4):
            terms = [m[4 * k + j] if c == 1.0 else c * m[4 * k + j] for k, c in enumerate(C[i])]
            used = [t for t, c in zip(terms, C[i], strict=True) if c != 0.0]
            total = used[0] if used else xp.zeros_like(m[0])
            for t in used[1:]:
                total = total + t
            out.append(total)
    return tuple(out)


def _pick(xp: ModuleType, cond: Array | None, a: Array, b: Array) -> Array:
    """``a`` where ``cond`` (directional), else ``b``; ``b`` when there is no choice."""
    return b if cond is None else xp.where(cond, a, b)


def scene_core(
    ctx: Context,
    checks: Checks,
    light: Array,
    world: Array,
    B: Array | None,
    receivers: Array | None,
    up: Array | None,
    margins: tuple[float, float],
    near: Array | None,
    far: Array | None,
    aim: str,
    opts: SceneOptions,
) -> tuple[LightFrame, Frustum, Matrix, Matrix, Matrix]:
    """Frame, frustum, ``W`` (12), clip (16) and texture (16) entries of the scene fit.

    ``world`` holds the blocker's vertices in world coordinates (placement applied,
    checked finite); the other arrays are shape-checked, their values checked here.
    """
    xp = ctx.xp
    F = formulas(xp)
    eps = ctx.eps
    if receivers is not None:
        checks.require(all_finite(xp, receivers, 2), non_finite("receivers"))
    if up is not None:
        checks.require(all_finite(xp, up, 1), non_finite("up"))

    # The light: a point (w != 0: at xyz / w) or a direction toward the light (w == 0).
    directional: Array | None = None
    xyz = light[..., :3]
    if opts.homogeneous:
        w = light[..., 3]
        directional = w == 0
        pos = xyz / xp.where(directional, xp.ones_like(w), w)[..., None]
        checks.require(
            xp.logical_not(directional) | (xp.max(xp.abs(xyz), axis=-1) > 0), ZERO_DIRECTIONAL
        )
    else:
        pos = xyz

    # Pass 1: the viewing direction and the blocker's centre.
    offsets = world - pos[..., None, :]
    lo_w, hi_w = xp.min(world, axis=-2), xp.max(world, axis=-2)
    if aim == "mean":
        to_blocker = xp.mean(offsets, axis=-2)
    else:
        to_blocker = 0.5 * (xp.max(offsets, axis=-2) + xp.min(offsets, axis=-2))
    coords = xp.maximum(xp.max(xp.abs(world), axis=(-2, -1)), xp.max(xp.abs(pos), axis=-1))
    # The directional fit's provisional origin: the bounding box's centre, or (stable)
    # the vertices' mean, the centre of a bounding sphere that turns with the blocker.
    centre = xp.mean(world, axis=-2) if opts.stable else 0.5 * (lo_w + hi_w)
    d = _pick(xp, None if directional is None else directional[..., None], -xyz, to_blocker)

    # The frame: the helper axis (Nagy), or the part of `up` perpendicular to Z.
    if up is None:
        axes = F.frame_axes(d[..., 0], d[..., 1], d[..., 2])
    else:
        one = xp.ones_like(d[..., 0])
        axes = F.rolled_axes(
            d[..., 0], d[..., 1], d[..., 2], up[..., 0], up[..., 1], up[..., 2], one, 0 * one
        )
        up_len = xp.max(xp.abs(up), axis=-1)
        checks.require((up_len > 0) & (axes[10] > (256 * eps) ** 2), UP_PARALLEL)
    if opts.stable and up is None:
        ok = xp.zeros(d.shape[:-1], dtype=bool) if directional is None else directional
        checks.require(ok, STABLE_NEEDS_UP)
    length_ok = axes[9] > 32 * eps * coords
    if directional is not None:
        length_ok = length_ok | directional
    checks.require(length_ok, msg.ZERO_DIRECTION)
    X = xp.stack(axes[0:3], axis=-1)
    Y = xp.stack(axes[3:6], axis=-1)
    Z = xp.stack(axes[6:9], axis=-1)

    # Pass 2: light coordinates about the provisional origin (the light, or the centre).
    o1 = _pick(xp, None if directional is None else directional[..., None], centre, pos)

    def light_xyz(p: Array) -> tuple[Array, Array, Array]:
        rel = p - o1[..., None, :]
        return (
            xp.sum(rel * X[..., None, :], axis=-1),
            xp.sum(rel * Y[..., None, :], axis=-1),
            xp.sum(rel * Z[..., None, :], axis=-1),
        )

    bx, by, bz = light_xyz(world)
    reach = xp.max(xp.abs(world - o1[..., None, :]), axis=(-2, -1))
    noise = 32 * eps * reach
    dir_b = None if directional is None else directional[..., None]
    safe_bz = xp.where(bz > 0, bz, xp.ones_like(bz))
    ux = _pick(xp, dir_b, bx, bx / safe_bz)
    uy = _pick(xp, dir_b, by, by / safe_bz)
    zb_min, zb_max = xp.min(bz, axis=-1), xp.max(bz, axis=-1)
    in_front = zb_min > noise
    if directional is not None:
        in_front = in_front | directional
    checks.require(in_front, msg.BEHIND_LIGHT)

    # The sides: the symmetric frustum of the ratios (point), the bounding box of the
    # light coordinates (directional), or the bounding sphere snapped to texels (stable).
    hi_x, lo_x = xp.max(ux, axis=-1), xp.min(ux, axis=-1)
    hi_y, lo_y = xp.max(uy, axis=-1), xp.min(uy, axis=-1)
    p_half_x, p_half_y = xp.maximum(hi_x, -lo_x), xp.maximum(hi_y, -lo_y)
    zero = xp.zeros_like(p_half_x)
    if opts.stable:
        radius = xp.sqrt(xp.max(xp.sum((world - centre[..., None, :]) ** 2, axis=-1), axis=-1))
        mx, my = margins
        width, height = opts.texels
        # Half-extents that still hold the sphere after the centre moved by half a texel:
        # h (1 - 1 / (m W)) = r, one texel being 2 h / (m W) in world units.
        d_half_x = radius / (1 - 1 / (mx * width))
        d_half_y = radius / (1 - 1 / (my * height))
        tx, ty = 2 * d_half_x / (mx * width), 2 * d_half_y / (my * height)
        # Anchored in world: the centre's coordinates along X and Y from the world
        # origin, rounded to whole texels (the origin moves along Z only).
        ax, ay = xp.sum(centre * X, axis=-1), xp.sum(centre * Y, axis=-1)
        safe_tx = xp.where(tx > 0, tx, xp.ones_like(tx))
        safe_ty = xp.where(ty > 0, ty, xp.ones_like(ty))
        d_cx = xp.round(ax / safe_tx) * tx - ax
        d_cy = xp.round(ay / safe_ty) * ty - ay
    else:
        d_half_x, d_half_y = 0.5 * (hi_x - lo_x), 0.5 * (hi_y - lo_y)
        d_cx, d_cy = 0.5 * (hi_x + lo_x), 0.5 * (hi_y + lo_y)
    half_x = _pick(xp, directional, d_half_x, p_half_x)
    half_y = _pick(xp, directional, d_half_y, p_half_y)
    cx = _pick(xp, directional, d_cx, zero)
    cy = _pick(xp, directional, d_cy, zero)
    safe_zmin = xp.where(zb_min > 0, zb_min, xp.ones_like(zb_min))
    silhouette_noise = _pick(xp, directional, 2 * noise, 2 * noise / safe_zmin)
    checks.require((half_x > silhouette_noise) & (half_y > silhouette_noise), msg.ZERO_SILHOUETTE)
    safe_hx = xp.where(half_x > 0, half_x, xp.ones_like(half_x))
    safe_hy = xp.where(half_y > 0, half_y, xp.ones_like(half_y))

    # The depth range: the blocker, and the receivers inside the side planes.
    z_lo, z_hi = zb_min, zb_max
    if receivers is not None:
        rx, ry, rz = light_xyz(receivers)
        safe_rz = xp.where(rz > 0, rz, xp.ones_like(rz))
        vx = _pick(xp, dir_b, rx, rx / safe_rz)
        vy = _pick(xp, dir_b, ry, ry / safe_rz)
        sx_, sy_ = (margins[0] / safe_hx)[..., None], (margins[1] / safe_hy)[..., None]
        inside = (xp.abs(sx_ * (vx - cx[..., None])) <= 1) & (
            xp.abs(sy_ * (vy - cy[..., None])) <= 1
        )
        in_front_r = rz > 0 if directional is None else (rz > 0) | dir_b
        counted = inside & in_front_r
        z_lo = xp.minimum(z_lo, xp.min(xp.where(counted, rz, zb_min[..., None]), axis=-1))
        z_hi = xp.maximum(z_hi, xp.max(xp.where(counted, rz, zb_max[..., None]), axis=-1))

    # Directional: move the origin back along -Z, behind everything counted, by the
    # depth range plus the box's size (so near > 0 with room to spare).
    if directional is not None:
        pad = (z_hi - z_lo) + xp.maximum(half_x, half_y)
        shift = xp.where(directional, z_lo - pad, zero)
        origin = o1 + shift[..., None] * Z
        z_lo, z_hi, zb_min, zb_max = z_lo - shift, z_hi - shift, zb_min - shift, zb_max - shift
    else:
        origin = o1
    given_near, given_far = near, far
    near = z_lo * (1 - NEAR_FAR_SLACK) if given_near is None else given_near
    far = z_hi * (1 + NEAR_FAR_SLACK) if given_far is None else given_far
    if given_near is not None:
        checks.require(xp.isfinite(given_near), msg.NEAR_NOT_FINITE)
    if given_far is not None:
        checks.require(xp.isfinite(given_far), msg.FAR_NOT_FINITE)
    if given_near is not None:
        checks.require(near > 0, msg.NEAR_POSITIVE)
    checks.require(near < far, msg.NEAR_FAR)
    if given_near is not None:
        checks.require(near <= zb_min, msg.NEAR_CLIPS)
    if given_far is not None:
        checks.require(far >= zb_max, msg.FAR_CLIPS)

    shape = tuple(xp.broadcast_shapes(half_x.shape, near.shape, far.shape, origin.shape[:-1]))
    if checks.invalid is not None:
        checks.invalid = xp.broadcast_to(checks.invalid, shape)

    def field(v: Array) -> Array:
        return checks.poison(xp.broadcast_to(v, shape), 0)

    def vec(v: Array) -> Array:
        return checks.poison(xp.broadcast_to(v, (*shape, 3)), 1)

    frame = LightFrame(origin=vec(origin), x_axis=vec(X), y_axis=vec(Y), z_axis=vec(Z))
    safe_far = xp.where(far > near, far, near + 1)
    frustum = Frustum(
        rx_max=field(half_x),
        ry_max=field(half_y),
        near=field(near),
        far=field(far),
        margin_x=xp.broadcast_to(ctx.constant(margins[0]), shape),
        margin_y=xp.broadcast_to(ctx.constant(margins[1]), shape),
        x_offset=field(cx),
        y_offset=field(cy),
        orthographic=False if directional is None else xp.broadcast_to(directional, shape),
    )
    # The matrices from safe values (the poisoned fields' NaN are multiplied in later).
    safe = frustum._replace(
        rx_max=xp.broadcast_to(safe_hx, shape),
        ry_max=xp.broadcast_to(safe_hy, shape),
        near=xp.broadcast_to(near, shape),
        far=xp.broadcast_to(safe_far, shape),
        x_offset=xp.broadcast_to(cx, shape),
        y_offset=xp.broadcast_to(cy, shape),
    )
    W = light_entries(xp, LightFrame(origin, X, Y, Z))
    zero_e = xp.zeros_like(W[0])
    W16 = (*W, zero_e, zero_e, zero_e, zero_e + 1)
    gl_clip = F.compose_rows(projection_entries(xp, safe), W16)
    clip = _const_times(xp, _clip_from_gl(opts.api, opts.reversed_z), gl_clip)
    tex = _const_times(xp, _texture_from_gl_clip(opts.api, opts.reversed_z), gl_clip)
    if B is not None:
        clip = F.compose_rows(clip, tuple(B[..., i // 4, i % 4] for i in range(16)))
    return frame, frustum, W, clip, tex
