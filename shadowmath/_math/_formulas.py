"""Per-entry formulas, one source for every backend: NumPy, JAX and the compiled loop.

Each function here is plain arithmetic on *components* (scalars or arrays of the
same batch shape), written with three primitives only: ``where``, ``sqrt`` and
``fabs``. :func:`._specialize.specialize` binds them to a backend: NumPy's or JAX's array
functions (the arguments are then ``(*batch,)`` arrays and everything
broadcasts) or Numba's scalar ones (the compiled loops of :mod:`._loops` call
the same functions once per batch entry). So the frame, the frustum and the
matrices are written once, and the backends cannot drift apart.

Trusted inputs only: these functions check nothing (the public functions did).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from shadowmath._boundary._shapes import Scalar, Truth

# Placeholders, rebound per backend by specialize(); NumPy's by default.
where: Callable[..., Any] = np.where
sqrt: Callable[..., Any] = np.sqrt
fabs: Callable[..., Any] = np.abs
isfinite: Callable[..., Any] = np.isfinite
maximum: Callable[..., Any] = np.maximum
log2: Callable[..., Any] = np.log2


def flag(ok: Truth, bit: int) -> Scalar:
    """``bit`` where the check ``ok`` failed, else 0 (a primitive: each backend binds its own)."""
    return 0 if ok else bit


def normalize3(x: Scalar, y: Scalar, z: Scalar) -> tuple[Scalar, Scalar, Scalar, Scalar]:
    """``(x, y, z) / |(x, y, z)|`` and the length, without overflow; zero gives zero.

    Scaled by the largest component first, so float32 vectors of size 1e-25 or
    1e25 (whose squares leave float32's range) normalize correctly. The double
    ``where`` keeps reverse-mode derivatives finite at zero: the square root is
    never differentiated at 0.
    """
    ax, ay, az = fabs(x), fabs(y), fabs(z)
    m = where(ax >= ay, ax, ay)
    m = where(m >= az, m, az)
    nonzero = m > 0
    safe_m = where(nonzero, m, 1.0)
    bx, by, bz = x / safe_m, y / safe_m, z / safe_m
    sq = bx * bx + by * by + bz * bz
    safe_sq = where(nonzero, sq, 1.0)
    root = sqrt(safe_sq)
    inv = where(nonzero, 1.0 / root, 0.0)
    return bx * inv, by * inv, bz * inv, where(nonzero, m * root, 0.0)


def helper_axis3(zx: Scalar, zy: Scalar, zz: Scalar) -> tuple[Scalar, Scalar, Scalar]:
    """The world axis at the smallest ``|z_k|`` (ties to the lowest index), as 0/1 floats."""
    ax, ay, az = fabs(zx), fabs(zy), fabs(zz)
    pick_x = (ax <= ay) & (ax <= az)
    pick_y = (pick_x == 0) & (ay <= az)
    pick_z = (pick_x == 0) & (pick_y == 0)
    zero = ax * 0.0  # in z's dtype (a bare 1.0 would be float64 in NumPy's where)
    one = zero + 1.0
    return where(pick_x, one, zero), where(pick_y, one, zero), where(pick_z, one, zero)


def frame_axes(dx: Scalar, dy: Scalar, dz: Scalar) -> tuple[Scalar, ...]:
    """Nagy's light frame for the viewing direction ``d``: ``X, Y, Z`` (9 components), ``|d|``.

    ``Z = d / |d|``, ``X = normalize(Z x V)`` with ``V`` the helper axis of ``Z``,
    ``Y = X x Z`` (left-handed: ``X x Y = -Z``).
    """
    zx, zy, zz, length = normalize3(dx, dy, dz)
    return (*axes_from_z(zx, zy, zz), zx, zy, zz, length)


def axes_from_z(
    zx: Scalar, zy: Scalar, zz: Scalar
) -> tuple[Scalar, Scalar, Scalar, Scalar, Scalar, Scalar]:
    """``X`` and ``Y`` of the frame with unit ``Z`` (the helper axis decided on ``Z`` as given)."""
    vx, vy, vz = helper_axis3(zx, zy, zz)
    xx, xy, xz, _ = normalize3(zy * vz - zz * vy, zz * vx - zx * vz, zx * vy - zy * vx)
    return xx, xy, xz, xy * zz - xz * zy, xz * zx - xx * zz, xx * zy - xy * zx


def rolled_axes(
    d: tuple[Scalar, Scalar, Scalar], u: tuple[Scalar, Scalar, Scalar], c: Scalar, s: Scalar
) -> tuple[Scalar, ...]:
    """The frame of ``Z = d / |d|`` with reference axis ``U``, turned by the angle (``c, s``).

    ``X0 = normalize(Z x U)``, ``Y0 = X0 x Z``, ``X = c X0 + s Y0``,
    ``Y = c Y0 - s X0`` (``c = cos theta``, ``s = sin theta``). Returns ``X, Y, Z``
    (9 components), ``|d|`` and ``|Z x U|^2`` (the squared sine of the angle
    between ``d`` and ``U``; zero when they are parallel).
    """
    zx, zy, zz, length = normalize3(d[0], d[1], d[2])
    vx, vy, vz, _ = normalize3(u[0], u[1], u[2])
    cx, cy, cz = zy * vz - zz * vy, zz * vx - zx * vz, zx * vy - zy * vx
    sin_sq = cx * cx + cy * cy + cz * cz
    ax, ay, az, _ = normalize3(cx, cy, cz)
    bx, by, bz = ay * zz - az * zy, az * zx - ax * zz, ax * zy - ay * zx
    return (
        c * ax + s * bx, c * ay + s * by, c * az + s * bz,
        c * bx - s * ax, c * by - s * ay, c * bz - s * az,
        zx, zy, zz, length, sin_sq,
    )  # fmt: skip


def two_sum(a: Scalar, b: Scalar) -> tuple[Scalar, Scalar]:
    """Knuth's error-free sum: ``s + e == a + b`` exactly, ``s = fl(a + b)``."""
    s = a + b
    bb = s - a
    return s, (a - (s - bb)) + (b - bb)


def two_product(a: Scalar, b: Scalar, splitter: float) -> tuple[Scalar, Scalar]:
    """Dekker's error-free product ``p + e == a * b`` (no FMA needed).

    Veltkamp's split cuts each factor into halves whose products are exact. A
    compiler that fuses ``ah * bh - p`` into an FMA still gets the exact value.
    """
    ca, cb = splitter * a, splitter * b
    ah = ca - (ca - a)
    bh = cb - (cb - b)
    al, bl = a - ah, b - bh
    p = a * b
    return p, ((ah * bh - p) + ah * bl + al * bh) + al * bl


def dot2(a: tuple[Scalar, ...], b: tuple[Scalar, ...], splitter: float) -> Scalar:
    """``sum(a_i b_i)`` as if computed in twice the working precision.

    Ogita, Rump and Oishi's ``Dot2`` ("Accurate sum and dot product", 2005):
    the exact dot product rounded once, up to a relative error of
    ``eps + (n eps)^2 cond``. Where the splitting overflows (entries beyond
    ~1e300 in float64, ~1e30 in float32) the plain sum is returned instead.
    ``splitter`` is ``2^ceil(p/2) + 1`` for a ``p``-bit significand.
    """
    p, s = two_product(a[0], b[0], splitter)
    plain = a[0] * b[0]
    for i in range(1, len(a)):
        h, r = two_product(a[i], b[i], splitter)
        p, q = two_sum(p, h)
        s = s + (q + r)
        plain = plain + a[i] * b[i]
    compensated = p + s
    return where(isfinite(compensated), compensated, plain)


def planar_entries(
    pi: tuple[Scalar, ...], L: tuple[Scalar, ...], splitter: float
) -> tuple[Scalar, ...]:
    """Blinn's ``sign(pi.L) ((pi.L) I - L pi^T)`` as 16 entries, then ``pi.L`` and its scale.

    ``pi.L`` cancels for a light close to the plane far from the origin; it is
    computed compensated (:func:`dot2`), so its sign (which orients the matrix)
    and size are right. The diagonal entries ``(pi.L) - L_i pi_i`` are the
    other three terms of ``pi.L``, summed compensated too, where the
    subtraction would cancel. The scale ``|n| |l| + |d w|`` is the size of the
    terms of ``pi.L``, for a relative threshold.
    """
    d = dot2(pi, L, splitter)
    one = d * 0.0 + 1.0
    sign = where(d < 0, -one, one)
    a0 = sign * dot2((pi[1], pi[2], pi[3]), (L[1], L[2], L[3]), splitter)
    a1 = sign * dot2((pi[0], pi[2], pi[3]), (L[0], L[2], L[3]), splitter)
    a2 = sign * dot2((pi[0], pi[1], pi[3]), (L[0], L[1], L[3]), splitter)
    a3 = sign * dot2((pi[0], pi[1], pi[2]), (L[0], L[1], L[2]), splitter)
    s0, s1, s2, s3 = -sign * L[0], -sign * L[1], -sign * L[2], -sign * L[3]
    n_len = normalize3(pi[0], pi[1], pi[2])[3]
    l_len = normalize3(L[0], L[1], L[2])[3]
    return (
        a0, s0 * pi[1], s0 * pi[2], s0 * pi[3],
        s1 * pi[0], a1, s1 * pi[2], s1 * pi[3],
        s2 * pi[0], s2 * pi[1], a2, s2 * pi[3],
        s3 * pi[0], s3 * pi[1], s3 * pi[2], a3,
        d, n_len * l_len + fabs(pi[3] * L[3]), n_len,
    )  # fmt: skip


def projection_rows(
    scale: tuple[Scalar, Scalar], centre: tuple[Scalar, Scalar], near: Scalar, far: Scalar
) -> tuple[Scalar, Scalar, Scalar, Scalar, Scalar, Scalar]:
    """The nonzero entries of the blocker projection ``P`` (light to OpenGL clip).

    ``P = [[sx, 0, -sx cx, 0], [0, sy, -sy cy, 0], [0, 0, a, b], [0, 0, 1, 0]]``
    with ``a = (f + n) / (f - n)`` and ``b = -2 n (f / (f - n))`` (the product
    ``f n`` is never formed, so it cannot overflow). ``scale = (sx, sy)``,
    ``centre = (cx, cy)``. Returns ``(sx, -sx cx, sy, -sy cy, a, b)``.
    """
    (sx, sy), (cx, cy) = scale, centre
    ratio = far / (far - near)
    return sx, -sx * cx, sy, -sy * cy, (far + near) / (far - near), -2.0 * near * ratio


def light_rows(
    origin: tuple[Scalar, Scalar, Scalar], axes: tuple[Scalar, ...]
) -> tuple[Scalar, ...]:
    """``world_to_light = [[R, -R o], [0, 1]]`` as 12 entries (its first three rows).

    ``origin = o`` (3), ``axes``: the rows ``X, Y, Z`` of ``R`` (their first 9 entries).
    """
    ox, oy, oz = origin[0], origin[1], origin[2]
    xx, xy, xz, yx, yy, yz = axes[0], axes[1], axes[2], axes[3], axes[4], axes[5]
    zx, zy, zz = axes[6], axes[7], axes[8]
    tx = -(xx * ox + xy * oy + xz * oz)
    ty = -(yx * ox + yy * oy + yz * oz)
    tz = -(zx * ox + zy * oy + zz * oz)
    return xx, xy, xz, tx, yx, yy, yz, ty, zx, zy, zz, tz


def clip_rows(w: tuple[Scalar, ...], p: tuple[Scalar, ...]) -> tuple[Scalar, ...]:
    """``P @ world_to_light`` in closed form (16 entries), ``w`` from :func:`light_rows`.

    Row 0 is ``sx (X - cx Z)`` (with its translation), row 1 ``sy (Y - cy Z)``,
    row 2 ``a Z + (0, 0, 0, b)``, row 3 ``Z``: no 4x4 product is formed.
    (Written out entry by entry: the compiled loop needs tuples of static length.)
    """
    sx, sxc, sy, syc, a, b = p
    return (
        sx * w[0] + sxc * w[8], sx * w[1] + sxc * w[9],
        sx * w[2] + sxc * w[10], sx * w[3] + sxc * w[11],
        sy * w[4] + syc * w[8], sy * w[5] + syc * w[9],
        sy * w[6] + syc * w[10], sy * w[7] + syc * w[11],
        a * w[8], a * w[9], a * w[10], a * w[11] + b,
        w[8], w[9], w[10], w[11],
    )  # fmt: skip


def texture_rows(c: tuple[Scalar, ...]) -> tuple[Scalar, ...]:
    """OpenGL clip rows to texture rows: ``(s q, t q, r q) = (clip_xyz + w) / 2``, ``q = w``."""
    return (
        0.5 * (c[0] + c[12]), 0.5 * (c[1] + c[13]), 0.5 * (c[2] + c[14]), 0.5 * (c[3] + c[15]),
        0.5 * (c[4] + c[12]), 0.5 * (c[5] + c[13]), 0.5 * (c[6] + c[14]), 0.5 * (c[7] + c[15]),
        0.5 * (c[8] + c[12]), 0.5 * (c[9] + c[13]), 0.5 * (c[10] + c[14]), 0.5 * (c[11] + c[15]),
        c[12], c[13], c[14], c[15],
    )  # fmt: skip


def _row_times(
    m: tuple[Scalar, ...], i: int, b: tuple[Scalar, ...]
) -> tuple[Scalar, Scalar, Scalar, Scalar]:
    """Row ``i`` of ``m @ b`` (both 16 row-major entries)."""
    m0, m1, m2, m3 = m[4 * i], m[4 * i + 1], m[4 * i + 2], m[4 * i + 3]
    return (
        m0 * b[0] + m1 * b[4] + m2 * b[8] + m3 * b[12],
        m0 * b[1] + m1 * b[5] + m2 * b[9] + m3 * b[13],
        m0 * b[2] + m1 * b[6] + m2 * b[10] + m3 * b[14],
        m0 * b[3] + m1 * b[7] + m2 * b[11] + m3 * b[15],
    )


def compose_rows(m: tuple[Scalar, ...], b: tuple[Scalar, ...]) -> tuple[Scalar, ...]:
    """The product ``m @ b`` of two 4x4 matrices given as 16 row-major entries each."""
    return (*_row_times(m, 0, b), *_row_times(m, 1, b), *_row_times(m, 2, b), *_row_times(m, 3, b))


FUNCTIONS = (
    "normalize3",
    "helper_axis3",
    "frame_axes",
    "axes_from_z",
    "rolled_axes",
    "projection_rows",
    "light_rows",
    "clip_rows",
    "texture_rows",
    "two_sum",
    "two_product",
    "dot2",
    "planar_entries",
    "_row_times",
    "compose_rows",
)
