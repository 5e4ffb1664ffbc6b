"""The compiled loops of :mod:`._kernels`, imported only when Numba is installed.

Every compiled function here is a module-level ``numba.njit(cache=True)``
function whose callees are module-level too, so Numba's on-disk cache finds
them again in the next process (a loop built inside a function, closing over
its callees, is compiled anew in every process).
"""

from __future__ import annotations

import math
from typing import Any

import numba
import numpy as np

from ._formulas import specialize
from ._kernels import (
    BEHIND_LIGHT,
    FAR_CLIPS,
    FAR_NOT_FINITE,
    NEAR_CLIPS,
    NEAR_FAR,
    NEAR_NOT_FINITE,
    NEAR_POSITIVE,
    NONFINITE_LIGHT,
    NONFINITE_PLACEMENT,
    NONFINITE_VERTICES,
    OVERFLOW,
    PLANAR_IN_PLANE,
    PLANAR_NONFINITE_LIGHT,
    PLANAR_NONFINITE_PLANE,
    PLANAR_ZERO_LIGHT,
    PLANAR_ZERO_NORMAL,
    PROJECTIVE_PLACEMENT,
    ZERO_DIRECTION,
    ZERO_SILHOUETTE,
)


@numba.njit(cache=True)
def _where(c: Any, a: Any, b: Any) -> Any:
    return a if c else b


# The formulas of _formulas compiled for scalars: the same source as the array path.
_F = specialize(
    {"where": _where, "sqrt": math.sqrt, "fabs": abs, "isfinite": math.isfinite},
    wrap=numba.njit(cache=True),
)
normalize3 = _F.normalize3
axes_from_z = _F.axes_from_z
projection_rows = _F.projection_rows
light_rows = _F.light_rows
clip_rows = _F.clip_rows
texture_rows = _F.texture_rows
compose_rows = _F.compose_rows
planar_entries = _F.planar_entries


@numba.njit(cache=True)
def planar_loop(plane: Any, light: Any, eps: float, out: Any, status: Any) -> None:
    splitter = 134217729.0  # 2^27 + 1: the loop computes in float64
    for i in range(out.shape[0]):
        P, L = plane[i % plane.shape[0]], light[i % light.shape[0]]
        pi = (float(P[0]), float(P[1]), float(P[2]), float(P[3]))
        li = (float(L[0]), float(L[1]), float(L[2]), float(L[3]))
        st = 0
        for v in pi:
            if not math.isfinite(v):
                st |= PLANAR_NONFINITE_PLANE
        for v in li:
            if not math.isfinite(v):
                st |= PLANAR_NONFINITE_LIGHT
        e = planar_entries(pi, li, splitter)
        if not e[18] > 0:
            st |= PLANAR_ZERO_NORMAL
        if li[0] == 0 and li[1] == 0 and li[2] == 0 and li[3] == 0:
            st |= PLANAR_ZERO_LIGHT
        if not abs(e[16]) > 16 * eps * e[17]:
            st |= PLANAR_IN_PLANE
        status[i] = st
        for j in range(16):
            out[i, j] = e[j]


@numba.njit(cache=True)
def place(
    b: Any, has_b: bool, px: float, py: float, pz: float
) -> tuple[float, float, float, float]:
    """A vertex in world coordinates and its homogeneous w (1 without a placement)."""
    if not has_b:
        return px, py, pz, 1.0
    w = b[12] * px + b[13] * py + b[14] * pz + b[15]
    s = 1.0 / w if w > 0 else 1.0
    return (
        (b[0] * px + b[1] * py + b[2] * pz + b[3]) * s,
        (b[4] * px + b[5] * py + b[6] * pz + b[7]) * s,
        (b[8] * px + b[9] * py + b[10] * pz + b[11]) * s,
        w,
    )


# error_model="numpy": a division is a plain division (no ZeroDivisionError branch);
# the loop never divides by zero anyway (z > 0 is tested first).
@numba.njit(cache=True, error_model="numpy")
def fit_loop(
    light: Any,
    verts: Any,
    placement: Any,
    near: Any,
    far: Any,
    options: Any,
    out: Any,
    mats: Any,
    status: Any,
) -> None:
    aim_bbox, has_b = options[0] != 0, options[1] != 0
    has_near, has_far = options[2] != 0, options[3] != 0
    mx, my, eps, slack = options[4], options[5], options[6], options[7]
    single = options[8] != 0
    n = verts.shape[1]
    for i in range(out.shape[0]):
        L = light[i % light.shape[0]]
        V = verts[i % verts.shape[0]]
        bm = placement[i % placement.shape[0]]
        lx, ly, lz = float(L[0]), float(L[1]), float(L[2])
        b = (
            float(bm[0, 0]), float(bm[0, 1]), float(bm[0, 2]), float(bm[0, 3]),
            float(bm[1, 0]), float(bm[1, 1]), float(bm[1, 2]), float(bm[1, 3]),
            float(bm[2, 0]), float(bm[2, 1]), float(bm[2, 2]), float(bm[2, 3]),
            float(bm[3, 0]), float(bm[3, 1]), float(bm[3, 2]), float(bm[3, 3]),
        )  # fmt: skip
        st = 0
        if not (math.isfinite(lx) and math.isfinite(ly) and math.isfinite(lz)):
            st |= NONFINITE_LIGHT
        if has_b:
            for e in b:
                if not math.isfinite(e):
                    st |= NONFINITE_PLACEMENT
        # Pass 1: the viewing direction and the two scales.
        sx = sy = sz = 0.0
        lo_x = lo_y = lo_z = math.inf
        hi_x = hi_y = hi_z = -math.inf
        coords = max(abs(lx), abs(ly), abs(lz))
        reach = raw = 0.0
        for k in range(n):
            # The given vertices' own sum: non-finite exactly when one of them is
            # (a placement's NaN must not be reported as the vertices').
            vx, vy, vz = float(V[k, 0]), float(V[k, 1]), float(V[k, 2])
            raw += vx + vy + vz
            px, py, pz, w = place(b, has_b, vx, vy, vz)
            if not w > 0:
                st |= PROJECTIVE_PLACEMENT
            ox, oy, oz = px - lx, py - ly, pz - lz
            sx += ox
            sy += oy
            sz += oz
            lo_x, lo_y, lo_z = min(lo_x, ox), min(lo_y, oy), min(lo_z, oz)
            hi_x, hi_y, hi_z = max(hi_x, ox), max(hi_y, oy), max(hi_z, oz)
            coords = max(coords, abs(px), abs(py), abs(pz))
            reach = max(reach, abs(ox), abs(oy), abs(oz))
        if not math.isfinite(raw):
            st |= NONFINITE_VERTICES
        elif not (math.isfinite(sx) and math.isfinite(sy) and math.isfinite(sz)):
            st |= OVERFLOW
        if aim_bbox:
            dx, dy, dz = 0.5 * (hi_x + lo_x), 0.5 * (hi_y + lo_y), 0.5 * (hi_z + lo_z)
        else:
            dx, dy, dz = sx / n, sy / n, sz / n
        zx, zy, zz, length = normalize3(dx, dy, dz)
        if single:
            # The helper axis is decided on Z as returned (rounded to float32),
            # so that the documented rule holds for the frame the caller sees.
            zx, zy, zz = float(np.float32(zx)), float(np.float32(zy)), float(np.float32(zz))
        ax = (*axes_from_z(zx, zy, zz), zx, zy, zz)
        if not length > 32 * eps * coords:
            st |= ZERO_DIRECTION
        # Pass 2: the ratios and the depth range in light coordinates.
        rx_hi = ry_hi = z_max = -math.inf
        rx_lo = ry_lo = z_min = math.inf
        for k in range(n):
            px, py, pz, w = place(b, has_b, float(V[k, 0]), float(V[k, 1]), float(V[k, 2]))
            ox, oy, oz = px - lx, py - ly, pz - lz
            x = ox * ax[0] + oy * ax[1] + oz * ax[2]
            y = ox * ax[3] + oy * ax[4] + oz * ax[5]
            z = ox * ax[6] + oy * ax[7] + oz * ax[8]
            z_min, z_max = min(z_min, z), max(z_max, z)
            inv_z = 1.0 / z if z > 0 else 1.0
            rx, ry = x * inv_z, y * inv_z
            rx_lo, rx_hi = min(rx_lo, rx), max(rx_hi, rx)
            ry_lo, ry_hi = min(ry_lo, ry), max(ry_hi, ry)
        noise = 32 * eps * reach
        if not z_min > noise:
            st |= BEHIND_LIGHT
        half_x, half_y = max(rx_hi, -rx_lo), max(ry_hi, -ry_lo)
        ratio_noise = 2 * noise / (z_min if z_min > 0 else 1.0)
        if not (half_x > ratio_noise and half_y > ratio_noise):
            st |= ZERO_SILHOUETTE
        n_near = z_min * (1 - slack)
        if has_near:
            n_near = float(near[i % near.shape[0]])
            if not math.isfinite(n_near):
                st |= NEAR_NOT_FINITE
            if not n_near > 0:
                st |= NEAR_POSITIVE
            if not n_near <= z_min:
                st |= NEAR_CLIPS
        n_far = z_max * (1 + slack)
        if has_far:
            n_far = float(far[i % far.shape[0]])
            if not math.isfinite(n_far):
                st |= FAR_NOT_FINITE
            if not n_far >= z_max:
                st |= FAR_CLIPS
        if not n_near < n_far:
            st |= NEAR_FAR
        status[i] = st
        if st != 0:
            n_near, n_far, half_x, half_y = 1.0, 2.0, 1.0, 1.0  # never divide by 0
        p = projection_rows(mx / half_x, my / half_y, 0.0, 0.0, n_near, n_far)
        wl = light_rows(lx, ly, lz, ax[0], ax[1], ax[2], ax[3], ax[4], ax[5], ax[6], ax[7], ax[8])
        clip = clip_rows(wl, p)
        tex = texture_rows(clip)
        if has_b:
            clip = compose_rows(clip, b)
        row, mat = out[i], mats[i]
        row[0], row[1], row[2] = lx, ly, lz
        for j in range(9):
            row[3 + j] = ax[j]
        row[12], row[13], row[14], row[15] = half_x, half_y, n_near, n_far
        row[16], row[17], row[18], row[19] = mx, my, 0.0, 0.0
        for j in range(12):
            mat[0, j // 4, j % 4] = wl[j]
        for j in range(16):
            mat[1, j // 4, j % 4] = clip[j]
            mat[2, j // 4, j % 4] = tex[j]
            mat[3, j // 4, j % 4] = b[j] if has_b else (1.0 if j % 5 == 0 else 0.0)
        mat[0, 3, 0], mat[0, 3, 1], mat[0, 3, 2], mat[0, 3, 3] = 0.0, 0.0, 0.0, 1.0
